// The setup's own work, apart from the cost of fresh memory: reads a network
// and builds the LocalizationProblem REPS times in one process, with freed
// memory kept in the process for the whole run (no trimming, no mmap for large
// blocks), so that from the second repetition on the setup runs on pages the
// process has already touched. On a VM whose host backs fresh memory slowly
// (docs/performance.md, "The AVX2 host: where the setup's time goes") the
// first repetition's setup is mostly page faults; the later ones are the
// setup's loops and messages. Every repetition is printed, as one JSON line
// from rank 0:
//   mpirun -np 2 snl_setup_warm NET.h5 [PARTITION [REPS]]
// {"rep": R, "ranks": P, "read_seconds": .., "setup_seconds": (largest over the
//  ranks), "phases": {rank 0's setup phases}, "graph_build_bytes": .., "peak_rss_bytes": (largest)}
#include <mpi.h>

#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
#include <malloc.h>
#define SNL_BENCH_GLIBC 1
#endif

#include "snl/core/memory.hpp"
#include "snl/io/network.hpp"
#include "snl/problem/problem.hpp"

namespace {

double max_over_ranks(double x, MPI_Comm comm) {
  double m = 0;
  MPI_Allreduce(&x, &m, 1, MPI_DOUBLE, MPI_MAX, comm);
  return m;
}

long long peak_rss_bytes(MPI_Comm comm) {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  long long mine = static_cast<long long>(ru.ru_maxrss) * 1024, m = 0;
  MPI_Allreduce(&mine, &m, 1, MPI_LONG_LONG, MPI_MAX, comm);
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  snl::tune_allocator(argv);  // the huge-page tunable, as snl runs
  MPI_Init(&argc, &argv);
  MPI_Comm comm = MPI_COMM_WORLD;
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  if (argc < 2) {
    if (rank == 0) std::fprintf(stderr, "usage: snl_setup_warm NET.h5 [PARTITION [REPS]]\n");
    MPI_Finalize();
    return 2;
  }
  const std::string net = argv[1];
  const std::string method = argc > 2 ? argv[2] : "bfs";
  const int reps = argc > 3 ? std::atoi(argv[3]) : 3;
#if defined(SNL_BENCH_GLIBC)
  // Freed memory stays in the process for the whole run; the setup's own
  // scope (ReuseFreedMemory) would return it at its end, so it is opted out.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, -1);
  setenv("SNL_MALLOC", "system", 1);
#else
  if (rank == 0) std::fprintf(stderr, "snl_setup_warm: not glibc's malloc; freed memory may leave the process\n");
#endif
  try {
    const snl::PartitionMethod pm = snl::parse_partition_method(method);  // partition_nodes resolves `auto`
    for (int r = 0; r < reps; ++r) {
      MPI_Barrier(comm);
      const double t0 = MPI_Wtime();
      snl::Network slab = snl::read_network(net, comm);
      const double t1 = MPI_Wtime();
      snl::ProblemReport rep;
      long long build_bytes = 0;
      double t2 = 0;
      {
        const snl::LocalizationProblem prob(comm, std::move(slab), pm, &rep);
        t2 = MPI_Wtime();
        for (const auto& b : rep.setup_bytes)
          if (b.first == "graph_build") build_bytes = b.second;
      }
      const double read_s = max_over_ranks(t1 - t0, comm), setup_s = max_over_ranks(t2 - t1, comm);
      long long build_max = 0;
      MPI_Allreduce(&build_bytes, &build_max, 1, MPI_LONG_LONG, MPI_MAX, comm);
      const long long rss = peak_rss_bytes(comm);
      if (rank == 0) {
        std::printf("{\"rep\": %d, \"ranks\": %d, \"partition\": \"%s\", \"read_seconds\": %.3f, \"setup_seconds\": %.3f, "
                    "\"phases\": {",
                    r, size, rep.partition.method.c_str(), read_s, setup_s);
        for (std::size_t k = 0; k < rep.setup_phases.size(); ++k)
          std::printf("%s\"%s\": %.3f", k ? ", " : "", rep.setup_phases[k].first.c_str(), rep.setup_phases[k].second);
        std::printf("}, \"graph_build_bytes\": %lld, \"peak_rss_bytes\": %lld}\n", build_max, rss);
        std::fflush(stdout);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "snl_setup_warm: %s\n", e.what());
    MPI_Abort(comm, 1);
  }
  MPI_Finalize();
  return 0;
}
