// TEMPORARY until the io branch lands.
#include <algorithm>
#include <numeric>
#include "snl/network.hpp"
namespace snl {
namespace {
GlobalId merge_pairs(std::vector<GlobalId>& e, std::vector<double>& r, bool canon) {
  const std::size_t m = r.size();
  std::vector<std::size_t> idx(m);
  std::iota(idx.begin(), idx.end(), 0);
  auto key = [&](std::size_t t) {
    GlobalId a = e[2 * t], b = e[2 * t + 1];
    if (canon && a > b) std::swap(a, b);
    return std::make_pair(a, b);
  };
  std::sort(idx.begin(), idx.end(), [&](std::size_t x, std::size_t y) {
    auto kx = key(x), ky = key(y);
    return kx != ky ? kx < ky : r[x] < r[y];
  });
  std::vector<GlobalId> ne;
  std::vector<double> nr;
  for (std::size_t s = 0; s < m;) {
    std::size_t t = s;
    double sum = 0;
    while (t < m && key(idx[t]) == key(idx[s])) sum += r[idx[t++]];
    auto k = key(idx[s]);
    ne.push_back(k.first);
    ne.push_back(k.second);
    nr.push_back(sum / double(t - s));
    s = t;
  }
  GlobalId merged = static_cast<GlobalId>(m - nr.size());
  e.swap(ne);
  r.swap(nr);
  return merged;
}
}  // namespace
MergeStats merge_duplicates(std::vector<GlobalId>& se, std::vector<double>& sr, std::vector<GlobalId>& ae,
                            std::vector<double>& ar) {
  MergeStats s;
  s.merged_sensor_pairs = merge_pairs(se, sr, true);
  s.merged_anchor_pairs = merge_pairs(ae, ar, false);
  return s;
}
}  // namespace snl
