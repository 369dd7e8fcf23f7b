// What the serial partition of a network costs, and what it gives, for a few
// ways of calling METIS: METIS's defaults (what --partition metis runs),
// random matching, recursive bisection, and METIS on a graph first coarsened
// by matching within P id blocks (what ranks holding a block each could do
// with no communication). Every run prints its time, edge cut and imbalance:
//   snl_metis_options NET.h5 NPARTS [P] [LEVELS] [REPS]
//   way W seconds T edge_cut C imbalance I coarse_nodes N
#include <metis.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include "snl/io/network.hpp"

namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Csr {
  std::vector<idx_t> xadj, adjncy, vwgt, adjwgt;
  idx_t n() const { return static_cast<idx_t>(xadj.size() - 1); }
};

Csr build(std::int64_t n, const std::vector<snl::GlobalId>& edges) {
  Csr g;
  g.xadj.assign(n + 1, 0);
  g.adjncy.resize(edges.size());
  for (std::size_t e = 0; e < edges.size(); e += 2) {
    ++g.xadj[edges[e] + 1];
    ++g.xadj[edges[e + 1] + 1];
  }
  for (std::int64_t v = 0; v < n; ++v) g.xadj[v + 1] += g.xadj[v];
  std::vector<idx_t> fill(g.xadj.begin(), g.xadj.end() - 1);
  for (std::size_t e = 0; e < edges.size(); e += 2) {
    g.adjncy[fill[edges[e]]++] = static_cast<idx_t>(edges[e + 1]);
    g.adjncy[fill[edges[e + 1]]++] = static_cast<idx_t>(edges[e]);
  }
  for (std::int64_t v = 0; v < n; ++v) std::sort(g.adjncy.begin() + g.xadj[v], g.adjncy.begin() + g.xadj[v + 1]);
  return g;
}

std::int64_t cut(const Csr& g, const std::vector<idx_t>& part) {
  std::int64_t c = 0;
  for (idx_t v = 0; v < g.n(); ++v)
    for (idx_t k = g.xadj[v]; k < g.xadj[v + 1]; ++k) c += part[v] != part[g.adjncy[k]];
  return c / 2;
}

double imbalance(const std::vector<idx_t>& part, int np) {
  std::vector<std::int64_t> cnt(np, 0);
  for (idx_t p : part) ++cnt[p];
  return static_cast<double>(*std::max_element(cnt.begin(), cnt.end())) * np / static_cast<double>(part.size());
}

// One level of heavy-edge matching restricted to edges inside an id block
// (P blocks as block_range gives them), then contraction. cmap: fine -> coarse.
Csr coarsen(const Csr& g, int P, std::vector<idx_t>& cmap) {
  const idx_t n = g.n();
  cmap.assign(n, -1);
  idx_t nc = 0;
  for (int r = 0; r < P; ++r) {
    snl::GlobalId b, e;
    snl::block_range(n, P, r, b, e);
    for (idx_t v = static_cast<idx_t>(b); v < static_cast<idx_t>(e); ++v) {
      if (cmap[v] >= 0) continue;
      idx_t best = -1, bw = -1;
      for (idx_t k = g.xadj[v]; k < g.xadj[v + 1]; ++k) {
        const idx_t u = g.adjncy[k];
        if (u < static_cast<idx_t>(b) || u >= static_cast<idx_t>(e) || cmap[u] >= 0 || u == v) continue;
        const idx_t w = g.adjwgt.empty() ? 1 : g.adjwgt[k];
        if (w > bw) bw = w, best = u;
      }
      cmap[v] = nc;
      if (best >= 0) cmap[best] = nc;
      ++nc;
    }
  }
  // Contract: coarse rows in coarse-id order, neighbour weights summed.
  std::vector<idx_t> first(nc, -1), second(nc, -1);
  for (idx_t v = 0; v < n; ++v) (first[cmap[v]] < 0 ? first[cmap[v]] : second[cmap[v]]) = v;
  Csr c;
  c.xadj.assign(nc + 1, 0);
  c.vwgt.assign(nc, 0);
  std::vector<idx_t> mark(nc, -1), slot;
  c.adjncy.reserve(g.adjncy.size());
  c.adjwgt.reserve(g.adjncy.size());
  for (idx_t cv = 0; cv < nc; ++cv) {
    const idx_t start = static_cast<idx_t>(c.adjncy.size());
    for (idx_t v : {first[cv], second[cv]}) {
      if (v < 0) continue;
      c.vwgt[cv] += g.vwgt.empty() ? 1 : g.vwgt[v];
      for (idx_t k = g.xadj[v]; k < g.xadj[v + 1]; ++k) {
        const idx_t cu = cmap[g.adjncy[k]];
        if (cu == cv) continue;
        const idx_t w = g.adjwgt.empty() ? 1 : g.adjwgt[k];
        if (mark[cu] >= start) {
          c.adjwgt[mark[cu]] += w;
        } else {
          mark[cu] = static_cast<idx_t>(c.adjncy.size());
          c.adjncy.push_back(cu);
          c.adjwgt.push_back(w);
        }
      }
    }
    c.xadj[cv + 1] = static_cast<idx_t>(c.adjncy.size());
  }
  return c;
}

std::vector<idx_t> metis(Csr& g, int np, const char* way) {
  idx_t nv = g.n(), ncon = 1, nparts = np, obj = 0;
  idx_t opt[METIS_NOPTIONS];
  METIS_SetDefaultOptions(opt);
  opt[METIS_OPTION_SEED] = 1;
  opt[METIS_OPTION_NUMBERING] = 0;
  const std::string w = way;
  if (w == "rm") opt[METIS_OPTION_CTYPE] = METIS_CTYPE_RM;
  if (w == "niter1") opt[METIS_OPTION_NITER] = 1;
  std::vector<idx_t> part(nv, 0);
  idx_t* vw = g.vwgt.empty() ? nullptr : g.vwgt.data();
  idx_t* aw = g.adjwgt.empty() ? nullptr : g.adjwgt.data();
  int st = w == "recursive"
               ? METIS_PartGraphRecursive(&nv, &ncon, g.xadj.data(), g.adjncy.data(), vw, nullptr, aw, &nparts, nullptr,
                                          nullptr, opt, &obj, part.data())
               : METIS_PartGraphKway(&nv, &ncon, g.xadj.data(), g.adjncy.data(), vw, nullptr, aw, &nparts, nullptr,
                                     nullptr, opt, &obj, part.data());
  if (st != METIS_OK) std::printf("METIS failed (%d)\n", st);
  return part;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s NET.h5 NPARTS [P] [LEVELS] [REPS]\n", argv[0]);
    return 2;
  }
  MPI_Init(&argc, &argv);
  const int np = std::stoi(argv[2]);
  const int P = argc > 3 ? std::stoi(argv[3]) : 2;
  const int levels = argc > 4 ? std::stoi(argv[4]) : 3;
  const int reps = argc > 5 ? std::stoi(argv[5]) : 1;
  snl::Network net = snl::read_network_serial(argv[1]);
  Csr g = build(net.num_sensors, net.sensor_edges);
  net = snl::Network();
  std::printf("# n %lld edges %lld nparts %d blocks %d levels %d\n", static_cast<long long>(g.n()),
              static_cast<long long>(g.adjncy.size() / 2), np, P, levels);
  for (int rep = 0; rep < reps; ++rep) {
    for (const char* way : {"default", "rm", "niter1", "recursive", "coarsened"}) {
      auto t = Clock::now();
      std::vector<idx_t> part;
      idx_t coarse = g.n();
      if (std::string(way) == "coarsened") {
        std::vector<std::vector<idx_t>> maps(levels);
        Csr c = g;
        for (int l = 0; l < levels; ++l) c = coarsen(c, P, maps[l]);
        coarse = c.n();
        std::vector<idx_t> cp = metis(c, np, "default");
        for (int l = levels - 1; l >= 0; --l) {
          std::vector<idx_t> fine(maps[l].size());
          for (std::size_t v = 0; v < fine.size(); ++v) fine[v] = cp[maps[l][v]];
          cp.swap(fine);
        }
        part.swap(cp);
      } else {
        part = metis(g, np, way);
      }
      const double s = since(t);
      std::printf("way %s seconds %.2f edge_cut %lld imbalance %.3f coarse_nodes %lld\n", way, s,
                  static_cast<long long>(cut(g, part)), imbalance(part, np), static_cast<long long>(coarse));
      std::fflush(stdout);
    }
  }
  MPI_Finalize();
  return 0;
}
