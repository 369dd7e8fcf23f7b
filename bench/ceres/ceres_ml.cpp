// Peer comparison (docs/ceres.md): the ML localization problem solved centrally by
// Ceres Solver with Levenberg-Marquardt and a sparse Cholesky linear solver.
//
//   f(x) = sum_{(i,j)} 1/2 (|x_i - x_j| - d_ij)^2 + sum_{(i,k)} 1/2 (|x_i - a_k| - r_ik)^2
//
// which is exactly Ceres' cost (1/2 sum of squared residuals) with one scalar
// residual per measurement, so Ceres' final cost is snl's `ml_cost`.
// Reads the network and a start (any file with dataset `positions`, e.g. the
// relaxation result) with snl's public API and writes an snl result file so
// that `snl eval` works on the output. Runs on one process (MPI only for HDF5).
#include <mpi.h>

#include <ceres/ceres.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/json.hpp"
#include "snl/io/network.hpp"
#include "snl/io/result_io.hpp"

namespace {

// Analytic cost functions (the Jacobian of |z| - rho is z^T/|z|; 0 at z = 0,
// as snl's ml_gradient does).
template <int P>
class PairCost final : public ceres::SizedCostFunction<1, P, P> {
 public:
  explicit PairCost(double d) : d_(d) {}
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    double z[P], nz = 0;
    for (int c = 0; c < P; ++c) {
      z[c] = x[0][c] - x[1][c];
      nz += z[c] * z[c];
    }
    nz = std::sqrt(nz);
    r[0] = nz - d_;
    if (J) {
      for (int c = 0; c < P; ++c) {
        const double u = nz > 0 ? z[c] / nz : 0.0;
        if (J[0]) J[0][c] = u;
        if (J[1]) J[1][c] = -u;
      }
    }
    return true;
  }

 private:
  double d_;
};

template <int P>
class AnchorCost final : public ceres::SizedCostFunction<1, P> {
 public:
  AnchorCost(const double* a, double rho) : rho_(rho) {
    for (int c = 0; c < P; ++c) a_[c] = a[c];
  }
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    double z[P], nz = 0;
    for (int c = 0; c < P; ++c) {
      z[c] = x[0][c] - a_[c];
      nz += z[c] * z[c];
    }
    nz = std::sqrt(nz);
    r[0] = nz - rho_;
    if (J && J[0])
      for (int c = 0; c < P; ++c) J[0][c] = nz > 0 ? z[c] / nz : 0.0;
    return true;
  }

 private:
  double a_[P];
  double rho_;
};

template <int P>
void add_residuals(ceres::Problem& problem, const snl::Network& net, std::vector<double>& x) {
  const std::size_t E = net.sensor_ranges.size(), Ea = net.anchor_ranges.size();
  for (std::size_t e = 0; e < E; ++e) {
    const auto i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    problem.AddResidualBlock(new PairCost<P>(net.sensor_ranges[e]), nullptr, &x[i * P], &x[j * P]);
  }
  for (std::size_t e = 0; e < Ea; ++e) {
    const auto i = net.anchor_edges[2 * e], k = net.anchor_edges[2 * e + 1];
    problem.AddResidualBlock(new AnchorCost<P>(&net.anchors[k * P], net.anchor_ranges[e]), nullptr, &x[i * P]);
  }
}

double ml_cost(const snl::Network& net, const std::vector<double>& x) {
  const int p = net.dim;
  double f = 0;
  auto term = [&](const double* a, const double* b, double rho) {
    double s = 0;
    for (int c = 0; c < p; ++c) s += (a[c] - b[c]) * (a[c] - b[c]);
    const double t = std::sqrt(s) - rho;
    f += 0.5 * t * t;
  };
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e)
    term(&x[net.sensor_edges[2 * e] * p], &x[net.sensor_edges[2 * e + 1] * p], net.sensor_ranges[e]);
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e)
    term(&x[net.anchor_edges[2 * e] * p], &net.anchors[net.anchor_edges[2 * e + 1] * p], net.anchor_ranges[e]);
  return f;
}

// RMSE over all sensors; with only_localizable, over sensors without a
// localizability flag (as snl's rmse_localizable; NaN when no flags are stored).
double rmse(const snl::Network& net, const std::vector<double>& x, bool only_localizable = false) {
  if (!net.has_truth) return std::nan("");
  if (only_localizable && net.localizability.size() != std::size_t(net.num_sensors)) return std::nan("");
  const int p = net.dim;
  double s = 0, cnt = 0;
  for (snl::GlobalId i = 0; i < net.num_sensors; ++i) {
    if (only_localizable && net.localizability[i]) continue;
    for (int c = 0; c < p; ++c) s += (x[i * p + c] - net.truth[i * p + c]) * (x[i * p + c] - net.truth[i * p + c]);
    cnt += 1;
  }
  return cnt > 0 ? std::sqrt(s / cnt) : std::nan("");
}

int run(int argc, char** argv) {
  std::string network, init, output, json, linalg = "suitesparse";
  int max_iter = 100, threads = 2;
  double tol = 1e-6, gradient_tol = 1e-10, parameter_tol = 1e-8;  // Ceres' defaults but tol
  bool quiet = false;
  CLI::App app{"ML sensor network localization with Ceres Solver (LM, sparse normal Cholesky)"};
  app.add_option("network", network, "network file")->required();
  app.add_option("init", init, "start: a file with dataset positions [n,p] (e.g. the relaxation result)")->required();
  app.add_option("-o,--output", output, "result file (snl-result format)")->required();
  app.add_option("--json", json, "write a JSON summary (fields as `snl solve --json`)");
  app.add_option("--max-iter", max_iter, "LM iteration limit")->capture_default_str();
  app.add_option("--tol", tol, "Ceres function_tolerance (relative cost decrease)")->capture_default_str();
  app.add_option("--gradient-tol", gradient_tol, "Ceres gradient_tolerance (max-norm of the projected gradient)")
      ->capture_default_str();
  app.add_option("--parameter-tol", parameter_tol, "Ceres parameter_tolerance (relative step size)")
      ->capture_default_str();
  app.add_option("--threads", threads, "Ceres threads (Jacobian evaluation)")->capture_default_str();
  app.add_option("--linear-algebra", linalg, "suitesparse (CHOLMOD) | eigen (Eigen SimplicialLDLT)")
      ->capture_default_str();
  app.add_flag("-q,--quiet", quiet, "no per-iteration output");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  const double t0 = MPI_Wtime();
  snl::Network net = snl::read_network_serial(network);
  const auto merged = snl::merge_duplicates(net.sensor_edges, net.sensor_ranges, net.anchor_edges, net.anchor_ranges);
  const int p = net.dim;
  const snl::GlobalId n = net.num_sensors;
  std::vector<double> x = snl::read_positions(init, MPI_COMM_SELF, n, p, 0, n);
  const double t_read = MPI_Wtime();

  ceres::Problem problem;  // owns the cost functions
  if (p == 2)
    add_residuals<2>(problem, net, x);
  else if (p == 3)
    add_residuals<3>(problem, net, x);
  else
    throw snl::Error("dimension " + std::to_string(p) + " not supported");
  const double t_setup = MPI_Wtime();

  ceres::Solver::Options opt;
  opt.minimizer_type = ceres::TRUST_REGION;
  opt.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  opt.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  if (linalg == "suitesparse")
    opt.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  else if (linalg == "eigen")
    opt.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  else
    throw snl::Error("--linear-algebra must be suitesparse or eigen");
  opt.max_num_iterations = max_iter;
  opt.function_tolerance = tol;
  opt.gradient_tolerance = gradient_tol;
  opt.parameter_tolerance = parameter_tol;
  opt.num_threads = threads;
  opt.minimizer_progress_to_stdout = !quiet;
  opt.logging_type = quiet ? ceres::SILENT : ceres::PER_MINIMIZER_ITERATION;
  std::string why;
  if (!opt.IsValid(&why)) throw snl::Error("Ceres options: " + why);

  ceres::Solver::Summary sum;
  ceres::Solve(opt, &problem, &sum);
  const double t_solve = MPI_Wtime();

  const double f = ml_cost(net, x), e = rmse(net, x);
  // LM iterations = accepted + rejected steps, each one sparse factorization
  // (Ceres counts its iteration 0, the start, as a successful step).
  std::int64_t iters = 0, accepted = 0;
  for (const auto& it : sum.iterations)
    if (it.iteration > 0) {
      ++iters;
      accepted += it.step_is_successful ? 1 : 0;
    }

  snl::ResultFile r;
  r.algorithm = "ceres-lm";
  r.iterations = iters;
  r.converged = sum.termination_type == ceres::CONVERGENCE;
  r.dim = p;
  r.num_sensors = n;
  r.row_offset = 0;
  r.positions = x;
  // Ceres prints a rejected step's candidate cost; the history keeps the
  // iterate's cost (unchanged by a rejected step), as snl's histories do.
  std::vector<double> hi, hc, ht, hs;
  for (const auto& it : sum.iterations) {
    const bool keep = it.iteration == 0 || it.step_is_successful;
    hi.push_back(it.iteration);
    hc.push_back(keep || hc.empty() ? it.cost : hc.back());
    ht.push_back(it.cumulative_time_in_seconds);
    hs.push_back(keep ? 1.0 : 0.0);
  }
  r.history = {{"iteration", hi}, {"ml_cost", hc}, {"elapsed", ht}, {"step_accepted", hs}};
  r.string_attrs = {{"termination", ceres::TerminationTypeToString(sum.termination_type)},
                    {"message", sum.message},
                    {"network", network},
                    {"linear_solver", "SPARSE_NORMAL_CHOLESKY/" + linalg}};
  r.double_attrs = {{"ml_cost", f}, {"solve_seconds", t_solve - t_setup}, {"initial_ml_cost", sum.initial_cost}};
  if (net.has_truth) r.double_attrs.push_back({"rmse", e});
  snl::write_result(output, MPI_COMM_SELF, r);
  const double t_write = MPI_Wtime();
  r.double_attrs.clear();

  if (!quiet) std::printf("%s\n", sum.FullReport().c_str());
  std::printf(
      "ceres_ml: n=%lld p=%d, %zu sensor pairs, %zu anchor pairs (%lld+%lld duplicates merged)\n"
      "  %s after %lld LM iterations (%lld accepted), %s\n"
      "  ML cost %.10g -> %.10g, RMSE %.6g\n"
      "  time: read %.3f s, setup %.3f s, solve %.3f s, write %.3f s, wall %.3f s\n",
      static_cast<long long>(n), p, net.sensor_ranges.size(), net.anchor_ranges.size(),
      static_cast<long long>(merged.merged_sensor_pairs), static_cast<long long>(merged.merged_anchor_pairs),
      ceres::TerminationTypeToString(sum.termination_type), static_cast<long long>(iters), static_cast<long long>(accepted),
      sum.message.c_str(), sum.initial_cost, f, e, t_read - t0, t_setup - t_read,
      t_solve - t_setup, t_write - t_solve, t_write - t0);

  if (!json.empty()) {
    snl::JsonObject j;
    j.add("algorithm", "ceres-lm")
        .add("iterations", iters)
        .add("accepted_steps", accepted)
        .add_bool("converged", r.converged)
        .add("termination", ceres::TerminationTypeToString(sum.termination_type))
        .add("message", sum.message)
        .add("initial_ml_cost", sum.initial_cost)
        .add("ml_cost", f)
        .add("wall_seconds", t_write - t0)
        .add("solve_seconds", t_solve - t_setup)
        .add("read_seconds", t_read - t0)
        .add("setup_seconds", t_setup - t_read)
        .add("write_seconds", t_write - t_solve)
        .add("linear_solver_seconds", sum.linear_solver_time_in_seconds)
        .add("jacobian_seconds", sum.jacobian_evaluation_time_in_seconds)
        .add("function_tolerance", tol)
        .add("gradient_tolerance", gradient_tol)
        .add("parameter_tolerance", parameter_tol)
        .add("threads", threads)
        .add("linear_algebra", linalg)
        .add("num_sensors", static_cast<std::int64_t>(n))
        .add("sensor_pairs", static_cast<std::int64_t>(net.sensor_ranges.size()))
        .add("anchor_pairs", static_cast<std::int64_t>(net.anchor_ranges.size()));
    if (net.has_truth) j.add("rmse", e).add("rmse_localizable", rmse(net, x, true));
    std::FILE* fp = std::fopen(json.c_str(), "w");
    if (!fp) throw snl::Error("cannot write " + json);
    const std::string s = j.str();
    std::fwrite(s.data(), 1, s.size(), fp);
    std::fclose(fp);
  }
  return r.converged || sum.termination_type == ceres::NO_CONVERGENCE ? 0 : 4;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rc = 0;
  try {
    rc = run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ceres_ml: error: %s\n", e.what());
    rc = 1;
  }
  MPI_Finalize();
  return rc;
}
