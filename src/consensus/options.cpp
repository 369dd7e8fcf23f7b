// Options of `snl consensus solve` and the small helpers every method shares
// (dense SPD algebra, measurements in node order, checkpoint rows).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "consensus/solver_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/core/random.hpp"

namespace snl::consensus {

namespace {
struct MethodName {
  const char* name;
  Method m;
};
const MethodName kMethods[] = {{"newton-tree", Method::kNewtonTree},
                               {"newton-path", Method::kNewtonPath},
                               {"subgradient", Method::kSubgradient},
                               {"incremental", Method::kIncremental},
                               {"central", Method::kCentral}};
bool is_newton(Method m) { return m == Method::kNewtonTree || m == Method::kNewtonPath; }
bool is_baseline(Method m) { return m == Method::kSubgradient || m == Method::kIncremental; }
}  // namespace

const char* method_name(Method m) {
  for (const auto& k : kMethods)
    if (k.m == m) return k.name;
  return "?";
}

const char* dual_name(DualSolver d) {
  switch (d) {
    case DualSolver::kSplitting: return "splitting";
    case DualSolver::kExact: return "exact";
    case DualSolver::kCg: return "cg";
    case DualSolver::kNone: return "none";
  }
  return "?";
}

const char* step_rule_name(StepRule s) {
  switch (s) {
    case StepRule::kArmijo: return "armijo";
    case StepRule::kDamped: return "damped";
    case StepRule::kNone: return "none";
  }
  return "?";
}

Method SolveOptions::method_kind() const {
  for (const auto& k : kMethods)
    if (method == k.name) return k.m;
  throw Error("unknown --method '" + method + "'");
}

DualSolver SolveOptions::dual_kind() const {
  if (!is_newton(method_kind())) return DualSolver::kNone;
  if (!dual || *dual == "cg") return DualSolver::kCg;
  return *dual == "exact" ? DualSolver::kExact : DualSolver::kSplitting;
}

StepRule SolveOptions::step_kind() const {
  if (is_baseline(method_kind())) return StepRule::kNone;
  return (step_rule && *step_rule == "damped") ? StepRule::kDamped : StepRule::kArmijo;
}

double SolveOptions::damping_b() const { return damping ? *damping : 0.9; }

std::string SolveOptions::validate() const {
  if (std::none_of(std::begin(kMethods), std::end(kMethods), [&](const MethodName& k) { return method == k.name; }))
    return "unknown --method '" + method + "' (expected newton-tree, newton-path, subgradient, incremental or central)";
  const Method m = method_kind();
  const std::string who = "--method " + method;
  if (dual && *dual != "cg" && *dual != "splitting" && *dual != "exact")
    return "unknown --dual '" + *dual + "' (expected cg, splitting or exact)";
  if (dual && !is_newton(m)) return "--dual applies to newton-tree and newton-path only, not to " + who;
  if (max_iter && *max_iter < 0) return "--max-iter must be >= 0";
  if (tol && !(std::isfinite(*tol) && *tol >= 0)) return "--tol must be a finite number >= 0";
  if (oracle_tol && !(std::isfinite(*oracle_tol) && *oracle_tol >= 0))
    return "--oracle-tol must be a finite number >= 0";
  if (oracle_tol && !is_baseline(m))
    return "--oracle-tol (the error against the oracle x*) applies to subgradient and incremental only; " + who +
           " stops on its Newton decrement (--tol)";
  if (dual_max_iter && *dual_max_iter < 1) return "--dual-max-iter must be >= 1";
  if (dual_tol && !(std::isfinite(*dual_tol) && *dual_tol > 0)) return "--dual-tol must be a finite number > 0";
  if (step && !(std::isfinite(*step) && *step > 0)) return "--step must be a finite number > 0";
  if ((dual_max_iter || dual_tol) && dual_kind() != DualSolver::kSplitting && dual_kind() != DualSolver::kCg)
    return std::string(dual_max_iter ? "--dual-max-iter" : "--dual-tol") +
           " applies to the cg and splitting duals of newton-tree and newton-path only, not to " + who +
           (is_newton(m) ? " --dual exact" : "");
  if (step && !is_baseline(m))
    return "--step A (alpha0) applies to subgradient and incremental only; " + who + " takes --step armijo|damped";
  if (step_rule && *step_rule != "armijo" && *step_rule != "damped")
    return "unknown --step '" + *step_rule + "' (expected armijo, damped, or a number alpha0 for the baselines)";
  if (step_rule && is_baseline(m))
    return "--step " + *step_rule + " applies to newton-tree, newton-path and central; " + who +
           " takes --step A (alpha0 of alpha0/sqrt(k+1))";
  if (damping && !(*damping > 0 && *damping < 1)) return "--damping must be in (0, 1)";
  if (damping && step_kind() != StepRule::kDamped)
    return "--damping applies to --step damped only (" + who + " steps by " + step_rule_name(step_kind()) + ")";
  if (partition != "metis" && partition != "block") return "--partition must be metis or block";
  return "";
}

std::int64_t SolveOptions::max_iterations() const {
  return max_iter ? *max_iter : (is_baseline(method_kind()) ? 1000 : 100);
}
std::int64_t SolveOptions::dual_max_iterations() const { return dual_max_iter ? *dual_max_iter : 10000; }
double SolveOptions::tolerance() const { return tol ? *tol : (is_baseline(method_kind()) ? 0.0 : 1e-10); }
double SolveOptions::dual_tolerance() const { return dual_tol ? *dual_tol : 1e-12; }
double SolveOptions::step0() const { return step ? *step : 0.1; }

std::string SolveOptions::checkpoint_key() const {
  std::ostringstream os;
  os.precision(17);
  os << "method=" << method << " dual=" << dual_name(dual_kind());
  if (dual_kind() == DualSolver::kSplitting || dual_kind() == DualSolver::kCg)
    os << " dual_max_iter=" << dual_max_iterations() << " dual_tol=" << dual_tolerance();
  if (is_baseline(method_kind())) os << " step=" << step0();
  os << " step_rule=" << step_rule_name(step_kind());
  if (step_kind() == StepRule::kDamped) os << " damping=" << damping_b();
  return os.str();
}

std::string problem_fingerprint(const ProblemData& d) {
  std::uint64_t h = mix64(static_cast<std::uint64_t>(d.num_nodes) * 1315423911ULL ^ std::uint64_t(d.dim) << 40 ^
                          std::uint64_t(d.family));
  auto ints = [&](std::uint64_t tag, const std::vector<GlobalId>& v) {
    h = mix64(h ^ tag ^ (v.size() << 8));
    for (GlobalId x : v) h = mix64(h ^ static_cast<std::uint64_t>(x));
  };
  auto reals = [&](std::uint64_t tag, const std::vector<double>& v) {
    h = mix64(h ^ tag ^ (v.size() << 8));
    for (double x : v) {
      std::uint64_t b;
      std::memcpy(&b, &x, 8);
      h = mix64(h ^ b);
    }
  };
  ints(1, d.edges);
  ints(2, d.truth_path);
  reals(3, d.exp_a), reals(4, d.exp_b), reals(5, d.exp_c), reals(6, d.exp_d);
  reals(7, d.quad_h), reals(8, d.quad_r), reals(9, d.features), reals(10, d.labels);
  ints(11, d.owner);
  reals(12, {d.lambda});
  char b[24];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(h));
  return b;
}

namespace detail {

bool cholesky(int q, double* a) {
  for (int j = 0; j < q; ++j) {
    double d = a[j * q + j];
    for (int k = 0; k < j; ++k) d -= a[j * q + k] * a[j * q + k];
    if (!(d > 0) || !std::isfinite(d)) return false;
    d = std::sqrt(d);
    a[j * q + j] = d;
    for (int i = j + 1; i < q; ++i) {
      double s = a[i * q + j];
      for (int k = 0; k < j; ++k) s -= a[i * q + k] * a[j * q + k];
      a[i * q + j] = s / d;
    }
  }
  return true;
}

namespace {
// Solves L L^T x = b in place (L in the lower triangle of l).
void chol_solve(int q, const double* l, double* x) {
  for (int i = 0; i < q; ++i) {
    double s = x[i];
    for (int k = 0; k < i; ++k) s -= l[i * q + k] * x[k];
    x[i] = s / l[i * q + i];
  }
  for (int i = q - 1; i >= 0; --i) {
    double s = x[i];
    for (int k = i + 1; k < q; ++k) s -= l[k * q + i] * x[k];
    x[i] = s / l[i * q + i];
  }
}
}  // namespace

bool spd_inverse(int q, const double* h, double* hinv, double* work) {
  if (q == 1) {  // the exp family: one division
    hinv[0] = 1.0 / h[0];
    return h[0] > 0 && std::isfinite(hinv[0]);
  }
  std::copy(h, h + q * q, work);
  if (!cholesky(q, work)) return false;
  for (int j = 0; j < q; ++j) {
    // Column j of the inverse, stored as row j (the inverse is symmetric).
    double* col = hinv + j * q;
    std::fill(col, col + q, 0.0);
    col[j] = 1.0;
    chol_solve(q, work, col);
  }
  // Symmetrise so both ends of a link see an exactly symmetric matrix.
  for (int i = 0; i < q; ++i)
    for (int j = i + 1; j < q; ++j) hinv[j * q + i] = hinv[i * q + j];
  return true;
}

bool spd_solve(int q, const double* h, const double* b, double* x, double* work) {
  if (q == 1) {
    x[0] = b[0] / h[0];
    return h[0] > 0 && std::isfinite(x[0]);
  }
  std::copy(h, h + q * q, work);
  if (!cholesky(q, work)) return false;
  std::copy(b, b + q, x);
  chol_solve(q, work, x);
  return true;
}

double max_abs_error(MPI_Comm comm, const double* x, LocalId rows, const std::vector<double>& xstar) {
  const int q = static_cast<int>(xstar.size());
  double m = 0;
  for (std::int64_t i = 0; i < std::int64_t(rows) * q; ++i) m = std::max(m, std::fabs(x[i] - xstar[i % q]));
  double g = 0;
  MPI_Allreduce(&m, &g, 1, MPI_DOUBLE, MPI_MAX, comm);  // a max: exact in any order
  return g;
}

double objective_at(const NodeGather& g, const LocalObjectives& obj, const double* point) {
  std::vector<double> f(obj.size());
  for (LocalId v = 0; v < static_cast<LocalId>(obj.size()); ++v) f[v] = obj.value(v, point);
  double total = 0;
  g.sum(f.data(), 1, &total);
  return total;
}

double objective_at_average(const NodeGather& g, const LocalObjectives& obj, GlobalId n, const double* x,
                            std::vector<double>* avg) {
  const int q = obj.dim();
  std::vector<double> a(q);
  g.sum(x, q, a.data());
  for (double& v : a) v /= static_cast<double>(n);
  if (avg) *avg = a;
  return objective_at(g, obj, a.data());
}

void write_node_rows(H5File& f, const std::string& name, const NodeGather& g, GlobalId n, const double* owned,
                     int width) {
  const std::vector<double> all = g.to_root(owned, width);
  const bool root = comm_rank(f.comm()) == 0;
  f.write_rows(name, static_cast<std::uint64_t>(n), static_cast<std::uint64_t>(width), 0, all.data(),
               root ? static_cast<std::uint64_t>(n) : 0);
}

void read_node_rows(const H5File& f, const std::string& name, const NodeGather& g, GlobalId n, double* owned,
                    int width) {
  const auto shape = f.shape(name);
  if (shape.size() != 2 || shape[0] != static_cast<std::uint64_t>(n) || shape[1] != static_cast<std::uint64_t>(width))
    throw Error(f.path() + ": checkpoint dataset " + name + " has the wrong shape");
  const std::vector<double> all = f.read_rows_double(name, 0, static_cast<std::uint64_t>(n));
  g.pick(all, width, owned);
}

}  // namespace detail
}  // namespace snl::consensus
