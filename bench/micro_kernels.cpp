// Google Benchmark micro-benchmarks of the iteration kernels, through the
// public API: the gradient of f_hat (003, Alg. 1), one MM iteration (000,
// Alg. 1; halo and norms included), one mm-accel iteration (with its costs),
// one relaxation iteration, one pass of S
// iterations with temporal blocking, and the halo pack/exchange/unpack. Each
// kernel runs with the RCM local order and with the global-id order (arg 1 =
// rcm, 0 = gid), to measure the locality effect (BM_Pass: arg = S, RCM).
//
//   build/bench/snl_micro [--benchmark_filter=...]          (1 rank)
//   mpirun -np 2 build/bench/snl_micro --benchmark_filter=Halo (2 ranks)
// SNL_MICRO_SENSORS sets n (default 1,000,000: well out of cache),
// SNL_MICRO_DIM the dimension (default 2), SNL_MICRO_NETWORK the network:
// "default" (the generator's defaults: degree 16 in 2D, 24 in 3D, corners
// plus 1% anchors, sigma 0.01 in the reference square's units) or "degree6"
// (the older records': degree 6, sigma 0.01, 4 corner anchors, unit square).
// Iteration counts are fixed so that every rank runs the same collectives.
#include <benchmark/benchmark.h>
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>

#include "snl/problem/generate.hpp"
#include "snl/problem/metrics.hpp"
#include "snl/problem/problem.hpp"
#include "snl/solvers/solver.hpp"

namespace {

using namespace snl;

GlobalId bench_sensors() {
  const char* s = std::getenv("SNL_MICRO_SENSORS");
  return s ? std::atoll(s) : 1000000;
}

// "default" or "degree6" (see the header); anything else is refused in main.
std::string bench_network() {
  const char* s = std::getenv("SNL_MICRO_NETWORK");
  return s ? s : "default";
}

int bench_dim() {
  const char* s = std::getenv("SNL_MICRO_DIM");
  return s ? std::atoi(s) : 2;
}

// One problem per local ordering, built once (generation and setup take
// seconds); cleared before MPI_Finalize (the halo plans hold MPI requests).
std::map<bool, std::unique_ptr<LocalizationProblem>> g_problems;

LocalizationProblem& problem(bool rcm) {
  auto& slot = g_problems[rcm];
  if (!slot) {
    static Network whole = [] {
      GenerateOptions opt;
      opt.sensors = bench_sensors();
      opt.dim = bench_dim();
      if (bench_network() == "degree6") {
        opt.avg_degree = 6;
        opt.sigma = 0.01;
        opt.num_random_anchors = 0;
        opt.side = 1.0;
      }
      // The kernels' cost does not depend on localizability: no redraws.
      opt.localizable = GenerateOptions::Localizable::kNo;
      return generate_network(opt);
    }();
    setenv("SNL_TEST_LOCAL_ORDER", rcm ? "rcm" : "gid", 1);
    slot = std::make_unique<LocalizationProblem>(MPI_COMM_WORLD, network_slab(whole, MPI_COMM_WORLD),
                                                 PartitionMethod::kMetis, nullptr);
    unsetenv("SNL_TEST_LOCAL_ORDER");
  }
  return *slot;
}

// Owned rows followed by the ghosts' rows, filled by a halo exchange.
std::vector<double> with_ghosts(LocalizationProblem& prob, const std::vector<double>& owned) {
  const int p = prob.dim();
  std::vector<double> x(std::size_t(prob.num_local()) * p, 0.0);
  std::copy(owned.begin(), owned.begin() + std::ptrdiff_t(prob.num_owned()) * p, x.begin());
  prob.graph().halo().exchange(x.data(), p);
  return x;
}

std::vector<double> local_positions(LocalizationProblem& prob) {
  return with_ghosts(prob, random_initial_positions(prob, 1));
}

void report(benchmark::State& st, const LocalizationProblem& prob) {
  const auto edges = static_cast<std::int64_t>(prob.graph().adjacency().size());
  st.SetItemsProcessed(st.iterations() * edges);  // directed edge visits
  st.counters["owned"] = prob.num_owned();
  st.counters["s_per_edge"] =
      benchmark::Counter(double(edges), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_RelaxedGradient(benchmark::State& st) {
  auto& prob = problem(st.range(0) != 0);
  auto x = local_positions(prob);
  std::vector<double> g(std::size_t(prob.num_owned()) * prob.dim());
  for (auto _ : st) {
    relaxed_gradient(prob, x.data(), g.data(), 0, prob.num_owned());
    benchmark::DoNotOptimize(g.data());
  }
  report(st, prob);
}

template <const char* kName>
void BM_Iteration(benchmark::State& st) {
  auto& prob = problem(st.range(0) != 0);
  SolverOptions opt;
  auto alg = make_algorithm(kName, prob, opt);
  alg->start(random_initial_positions(prob, 1));
  for (auto _ : st) alg->iterate();
  report(st, prob);
}
constexpr char kMM[] = "mm";
constexpr char kMMAccel[] = "mm-accel";
constexpr char kRelax[] = "relaxation";

// One pass of S = range(0) iterations with temporal blocking (RCM order):
// the time shown is per pass; s_per_iteration divides it by S.
template <const char* kName>
void BM_Pass(benchmark::State& st) {
  auto& prob = problem(true);
  SolverOptions opt;
  opt.temporal_block = static_cast<int>(st.range(0));
  auto alg = make_algorithm(kName, prob, opt);
  alg->start(random_initial_positions(prob, 1));
  for (auto _ : st) alg->iterate_levels(opt.temporal_block);
  st.counters["s_per_iteration"] = benchmark::Counter(
      double(opt.temporal_block), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// Fraction of directed sensor edges whose current length is within the range
// (|x_v - x_u| <= rho: the disk term is zero); it grows from ~0 at a random
// start towards 1, and says which state an iteration was timed in (2D).
double inside_fraction(LocalizationProblem& prob, const std::vector<double>& owned_x) {
  const auto x = with_ghosts(prob, owned_x);
  const auto& g = prob.graph();
  const auto& off = g.offsets();
  const auto& adj = g.adjacency();
  const auto& rho = g.edge_values();
  std::int64_t in = 0;
  for (LocalId v = 0; v < g.num_owned(); ++v)
    for (auto k = off[v]; k < off[v + 1]; ++k) {
      const double dx = x[2 * v] - x[2 * std::size_t(adj[k])], dy = x[2 * v + 1] - x[2 * std::size_t(adj[k]) + 1];
      in += dx * dx + dy * dy <= rho[k] * rho[k];
    }
  return double(in) / double(std::max<std::size_t>(1, adj.size()));
}

// One iteration after range(1) warm-up iterations from the random start (RCM
// order): the state a long run spends most of its time in.
template <const char* kName>
void BM_IterationAfter(benchmark::State& st) {
  auto& prob = problem(true);
  SolverOptions opt;
  auto alg = make_algorithm(kName, prob, opt);
  alg->start(random_initial_positions(prob, 1));
  for (std::int64_t i = 0; i < st.range(0); ++i) alg->iterate();
  st.counters["inside"] = inside_fraction(prob, alg->positions());
  for (auto _ : st) alg->iterate();
  report(st, prob);
}

void BM_HaloExchange(benchmark::State& st) {
  auto& prob = problem(st.range(0) != 0);
  auto x = local_positions(prob);
  auto& halo = prob.graph().halo();
  for (auto _ : st) {
    halo.exchange(x.data(), prob.dim());  // pack, send/recv, unpack
    benchmark::DoNotOptimize(x.data());
  }
  st.counters["ghosts"] = prob.graph().num_ghosts();
  st.counters["send_nodes"] = double(halo.send_volume());
}

BENCHMARK(BM_RelaxedGradient)->Arg(1)->Arg(0)->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Iteration, kRelax)->Arg(1)->Arg(0)->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Iteration, kMM)->Arg(1)->Arg(0)->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Iteration, kMMAccel)->Arg(1)->Arg(0)->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_IterationAfter, kRelax)->Arg(100)->Arg(300)->Arg(1000)->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_IterationAfter, kMM)->Arg(300)->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_IterationAfter, kMMAccel)->Arg(300)->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Pass, kRelax)->Arg(1)->Arg(4)->Arg(8)->Iterations(10)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Pass, kMM)->Arg(1)->Arg(4)->Arg(8)->Iterations(10)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HaloExchange)->Arg(1)->Iterations(2000)->Unit(benchmark::kMicrosecond);

class NullReporter : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>&) override {}
};

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  benchmark::Initialize(&argc, argv);
  // The same environment on every rank, so every rank takes this exit.
  if (bench_sensors() < 100 || (bench_dim() != 2 && bench_dim() != 3) ||
      (bench_network() != "default" && bench_network() != "degree6")) {
    if (rank == 0)
      std::fprintf(stderr,
                   "snl_micro: SNL_MICRO_SENSORS must be >= 100, SNL_MICRO_DIM 2 or 3, "
                   "SNL_MICRO_NETWORK default or degree6\n");
    MPI_Finalize();
    return 2;
  }
  if (rank == 0) {
    benchmark::RunSpecifiedBenchmarks();
  } else {
    NullReporter null;
    benchmark::RunSpecifiedBenchmarks(&null);
  }
  benchmark::Shutdown();
  g_problems.clear();
  MPI_Finalize();
  return 0;
}
