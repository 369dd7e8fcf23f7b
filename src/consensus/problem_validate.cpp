// Validation of consensus problems held in memory (format of docs/consensus.md,
// "snl-consensus" version 1). No MPI, no HDF5: the checks run in a fixed order
// and report the first violation only, so every rank that validates the same
// data reports the same message.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "consensus/problem_detail.hpp"
#include "snl/consensus/problem.hpp"

namespace snl::consensus {

namespace {

std::string num(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Inf" : "-Inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string s(GlobalId v) { return std::to_string(v); }

std::string row_of(const char* name, GlobalId row) { return std::string("dataset '") + name + "' row " + s(row) + ": "; }

std::string range_text(GlobalId n) { return "out of range [0, " + s(n) + ")"; }

/// Size check of an in-memory array against its expected number of values.
std::string check_size(const char* name, std::size_t got, std::uint64_t want, const std::string& what) {
  if (got == want) return {};
  return std::string("dataset '") + name + "' has " + std::to_string(got) + " values, expected " + what + " = " +
         std::to_string(want);
}

/// Every value finite and (positive: > 0); row = index / cols.
std::string check_values(const char* name, const std::vector<double>& v, int cols, bool positive) {
  for (std::size_t k = 0; k < v.size(); ++k) {
    const GlobalId row = static_cast<GlobalId>(k / static_cast<std::size_t>(cols));
    const std::string col = cols > 1 ? "column " + s(static_cast<GlobalId>(k % cols)) + ": " : "";
    if (!std::isfinite(v[k])) return row_of(name, row) + col + num(v[k]) + " is not a finite number";
    if (positive && !(v[k] > 0)) return row_of(name, row) + col + num(v[k]) + " is not > 0";
  }
  return {};
}

std::string check_header(const ProblemData& d) {
  if (d.num_nodes < 2) return "attribute 'num_nodes' must be >= 2 (consensus needs a network), got " + s(d.num_nodes);
  if (d.num_nodes > kMaxNodes) return "attribute 'num_nodes' must be <= " + s(kMaxNodes) + ", got " + s(d.num_nodes);
  if (d.dim < 1 || d.dim > kMaxDim)
    return "attribute 'dim' must be in [1, " + s(kMaxDim) + "], got " + s(d.dim);
  if (d.family == Family::kExp && d.dim != 1)
    return "attribute 'dim' must be 1 for family 'exp' (f_p is scalar), got " + s(d.dim);
  return {};
}

/// Node ids in range, no self loops, each undirected link once ((i, j) and
/// (j, i) are the same link): duplicates are refused, not merged, because a
/// repeated link would be a repeated constraint row of A (001's A must have
/// full row rank on the tree) and usually means a broken writer.
std::string check_edges(const ProblemData& d) {
  const GlobalId n = d.num_nodes;
  if (d.edges.size() % 2 != 0) return "dataset 'edges' has " + std::to_string(d.edges.size()) + " values, expected 2 per row";
  const GlobalId E = static_cast<GlobalId>(d.edges.size() / 2);
  // Checked first, so that a huge num_nodes with little data (only logistic
  // files tie no dataset to n) cannot make the checks below allocate for n.
  if (E < n - 1)
    return "dataset 'edges' has " + s(E) + " rows: the graph is not connected (" + s(n) +
           " nodes need at least " + s(n - 1) + " links); consensus is undefined on a disconnected network";
  for (GlobalId e = 0; e < E; ++e) {
    const GlobalId i = d.edges[2 * e], j = d.edges[2 * e + 1];
    for (GlobalId v : {i, j})
      if (v < 0 || v >= n) return row_of("edges", e) + "node id " + s(v) + " " + range_text(n);
    if (i == j) return row_of("edges", e) + "self-loop (" + s(i) + ", " + s(j) + ")";
  }
  // First duplicate in row order: sort (min, max, row); in each run of equal
  // links every row but the first repeats an earlier one.
  std::vector<GlobalId> order(static_cast<std::size_t>(E));
  std::iota(order.begin(), order.end(), GlobalId{0});
  const auto key = [&](GlobalId e) {
    const GlobalId i = d.edges[2 * e], j = d.edges[2 * e + 1];
    return std::make_pair(std::min(i, j), std::max(i, j));
  };
  std::sort(order.begin(), order.end(), [&](GlobalId a, GlobalId b) {
    const auto ka = key(a), kb = key(b);
    return ka != kb ? ka < kb : a < b;
  });
  GlobalId bad = -1, first = -1;
  std::size_t run = 0;  // start of the current run of equal links
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (key(order[k]) != key(order[k - 1])) {
      run = k;
      continue;
    }
    if (bad < 0 || order[k] < bad) bad = order[k], first = order[run];
  }
  if (bad >= 0) {
    const auto l = key(bad);
    return row_of("edges", bad) + "link (" + s(l.first) + ", " + s(l.second) + ") repeats row " + s(first) +
           " (each undirected link must be listed once)";
  }
  return {};
}

std::string check_exp(const ProblemData& d) {
  const auto n = static_cast<std::uint64_t>(d.num_nodes);
  const std::pair<const char*, const std::vector<double>*> params[] = {
      {"exp_a", &d.exp_a}, {"exp_b", &d.exp_b}, {"exp_c", &d.exp_c}, {"exp_d", &d.exp_d}};
  for (const auto& [name, v] : params)
    if (auto m = check_size(name, v->size(), n, "num_nodes"); !m.empty()) return m;
  for (const auto& [name, v] : params)
    if (auto m = check_values(name, *v, 1, true); !m.empty()) return m;
  return {};
}

std::string check_quadratic(const ProblemData& d) {
  const auto nq = static_cast<std::uint64_t>(d.num_nodes) * static_cast<std::uint64_t>(d.dim);
  if (auto m = check_size("quad_h", d.quad_h.size(), nq, "num_nodes * dim"); !m.empty()) return m;
  if (auto m = check_size("quad_r", d.quad_r.size(), nq, "num_nodes * dim"); !m.empty()) return m;
  if (auto m = check_values("quad_h", d.quad_h, d.dim, true); !m.empty()) return m;
  return check_values("quad_r", d.quad_r, d.dim, false);
}

/// logistic and least_squares: samples (features, labels, owner) and lambda.
std::string check_samples(const ProblemData& d) {
  const auto S = static_cast<std::uint64_t>(d.labels.size());
  if (auto m = check_size("features", d.features.size(), S * static_cast<std::uint64_t>(d.dim),
                          "rows of labels * dim");
      !m.empty())
    return m;
  if (auto m = check_size("owner", d.owner.size(), S, "rows of labels"); !m.empty()) return m;
  if (auto m = check_values("features", d.features, d.dim, false); !m.empty()) return m;
  if (d.family == Family::kLogistic) {
    for (std::size_t k = 0; k < d.labels.size(); ++k)
      if (d.labels[k] != 1.0 && d.labels[k] != -1.0)
        return row_of("labels", static_cast<GlobalId>(k)) + num(d.labels[k]) + " is not +1 or -1";
  } else if (auto m = check_values("labels", d.labels, 1, false); !m.empty()) {
    return m;  // least_squares: targets b_s, any finite real
  }
  for (std::size_t k = 0; k < d.owner.size(); ++k)
    if (d.owner[k] < 0 || d.owner[k] >= d.num_nodes)
      return row_of("owner", static_cast<GlobalId>(k)) + "node id " + s(d.owner[k]) + " " + range_text(d.num_nodes);
  if (!std::isfinite(d.lambda) || !(d.lambda > 0))
    return "attribute 'lambda' must be a finite number > 0 (the regulariser makes each f_p strictly convex), got " +
           num(d.lambda);
  return {};
}

/// Data of another family would be silently ignored: refuse it instead.
std::string check_foreign(const ProblemData& d) {
  const std::string fam = family_name(d.family);
  const auto foreign = [&](const char* name, bool present, Family owner) -> std::string {
    if (!present || owner == d.family || (has_samples(owner) && has_samples(d.family))) return {};
    return std::string("dataset '") + name + "' belongs to family '" + family_name(owner) +
           "', but this problem's family is '" + fam + "'";
  };
  const std::pair<const char*, std::pair<bool, Family>> all[] = {
      {"exp_a", {!d.exp_a.empty(), Family::kExp}},         {"exp_b", {!d.exp_b.empty(), Family::kExp}},
      {"exp_c", {!d.exp_c.empty(), Family::kExp}},         {"exp_d", {!d.exp_d.empty(), Family::kExp}},
      {"quad_h", {!d.quad_h.empty(), Family::kQuadratic}}, {"quad_r", {!d.quad_r.empty(), Family::kQuadratic}},
      {"features", {!d.features.empty(), Family::kLogistic}}, {"labels", {!d.labels.empty(), Family::kLogistic}},
      {"owner", {!d.owner.empty(), Family::kLogistic}}};
  for (const auto& [name, p] : all)
    if (auto m = foreign(name, p.first, p.second); !m.empty()) return m;
  return {};
}

std::string check_family(const ProblemData& d) {
  if (auto m = check_foreign(d); !m.empty()) return m;
  switch (d.family) {
    case Family::kExp: return check_exp(d);
    case Family::kQuadratic: return check_quadratic(d);
    case Family::kLogistic:
    case Family::kLeastSquares: return check_samples(d);
  }
  return "unknown family";
}

/// truth_path: a permutation of 0..n-1 whose consecutive entries are links.
std::string check_truth_path(const ProblemData& d, const Adjacency& adj) {
  if (d.truth_path.empty()) return {};
  const GlobalId n = d.num_nodes;
  if (auto m = check_size("truth_path", d.truth_path.size(), static_cast<std::uint64_t>(n), "num_nodes"); !m.empty())
    return m;
  std::vector<GlobalId> seen(static_cast<std::size_t>(n), -1);
  for (GlobalId k = 0; k < n; ++k) {
    const GlobalId v = d.truth_path[k];
    if (v < 0 || v >= n) return row_of("truth_path", k) + "node id " + s(v) + " " + range_text(n);
    if (seen[v] >= 0)
      return row_of("truth_path", k) + "node " + s(v) + " appears again (first at row " + s(seen[v]) +
             "): not a permutation of the nodes";
    seen[v] = k;
  }
  for (GlobalId k = 1; k < n; ++k) {
    const GlobalId u = d.truth_path[k - 1], v = d.truth_path[k];
    if (!adj.linked(u, v))
      return row_of("truth_path", k) + "nodes " + s(u) + " (row " + s(k - 1) + ") and " + s(v) +
             " are not a link of 'edges': not a Hamilton path of the graph";
  }
  return {};
}

std::string check_connected(const ProblemData& d, const Adjacency& adj) {
  const GlobalId n = d.num_nodes;
  std::vector<char> reached(static_cast<std::size_t>(n), 0);
  std::vector<GlobalId> stack{0};
  reached[0] = 1;
  GlobalId count = 1;
  while (!stack.empty()) {
    const GlobalId u = stack.back();
    stack.pop_back();
    for (std::int64_t k = adj.offset[u]; k < adj.offset[u + 1]; ++k) {
      const GlobalId v = adj.col[k];
      if (!reached[v]) reached[v] = 1, ++count, stack.push_back(v);
    }
  }
  if (count == n) return {};
  const GlobalId first = static_cast<GlobalId>(std::find(reached.begin(), reached.end(), 0) - reached.begin());
  return "dataset 'edges': the graph is not connected (node " + s(first) + " cannot be reached from node 0; " +
         s(count) + " of " + s(n) + " nodes reachable): consensus is undefined on a disconnected network";
}

}  // namespace

Adjacency::Adjacency(GlobalId n, const std::vector<GlobalId>& edges) {
  offset.assign(static_cast<std::size_t>(n) + 1, 0);
  const std::size_t E = edges.size() / 2;
  for (std::size_t e = 0; e < E; ++e) ++offset[edges[2 * e] + 1], ++offset[edges[2 * e + 1] + 1];
  for (GlobalId i = 0; i < n; ++i) offset[i + 1] += offset[i];
  col.resize(static_cast<std::size_t>(offset[n]));
  std::vector<std::int64_t> fill(offset.begin(), offset.end() - 1);
  for (std::size_t e = 0; e < E; ++e) {
    const GlobalId i = edges[2 * e], j = edges[2 * e + 1];
    col[fill[i]++] = j;
    col[fill[j]++] = i;
  }
  for (GlobalId i = 0; i < n; ++i) std::sort(col.begin() + offset[i], col.begin() + offset[i + 1]);
}

bool Adjacency::linked(GlobalId i, GlobalId j) const {
  return std::binary_search(col.begin() + offset[i], col.begin() + offset[i + 1], j);
}

// Finite values are not enough: f_p, its gradient and its Hessian at x = 0 must
// be finite in double precision (quad_r = 1e200 squares to infinity), or every
// method fails with nothing to say about the data.
std::string check_finite_at_zero(const ProblemData& d) {
  const int q = d.dim;
  const std::vector<double> zero(q, 0.0);
  std::vector<double> g(q), h(static_cast<std::size_t>(q) * q);
  const char* data = d.family == Family::kExp         ? "exp_a..exp_d"
                     : d.family == Family::kQuadratic ? "quad_h, quad_r"
                     : d.family == Family::kLogistic  ? "features"
                                                      : "features, labels";
  const GlobalId chunk = 65536;  // the nodes' data copied a chunk at a time
  LocalObjectives obj;
  std::vector<GlobalId> ids;
  for (GlobalId p = 0; p < d.num_nodes; ++p) {
    if (p % chunk == 0) {
      ids.clear();
      for (GlobalId i = p; i < std::min(d.num_nodes, p + chunk); ++i) ids.push_back(i);
      obj = LocalObjectives(d, ids);
    }
    const LocalId v = static_cast<LocalId>(p % chunk);
    const double f = obj.value(v, zero.data());
    obj.gradient(v, zero.data(), g.data());
    obj.hessian(v, zero.data(), h.data());
    bool ok = std::isfinite(f);
    for (double v : g) ok = ok && std::isfinite(v);
    for (double v : h) ok = ok && std::isfinite(v);
    if (!ok)
      return std::string(data) + ": node " + std::to_string(p) +
             ": its f_p, gradient or Hessian at x = 0 overflows double precision (values too large; rescale the data)";
  }
  return "";
}

std::string check_problem(const ProblemData& d) {
  if (auto m = check_header(d); !m.empty()) return m;
  if (auto m = check_edges(d); !m.empty()) return m;
  if (auto m = check_family(d); !m.empty()) return m;
  if (auto m = check_finite_at_zero(d); !m.empty()) return m;
  const Adjacency adj(d.num_nodes, d.edges);
  if (auto m = check_truth_path(d, adj); !m.empty()) return m;
  return check_connected(d, adj);
}

void validate_problem(const ProblemData& data) {
  const std::string m = check_problem(data);
  if (!m.empty()) throw Error(m);
}

}  // namespace snl::consensus
