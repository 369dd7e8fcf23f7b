// STREAM triad a[i] = b[i] + s * c[i] (McCalpin), one MPI process per core,
// arrays far larger than the caches. Prints the best aggregate bandwidth over
// all ranks in GB/s (10^9 bytes), counting 3 x 8 bytes per element (no
// write-allocate traffic, as STREAM reports it). Used by bench/scaling.sh as
// the memory-bandwidth bound of the iteration phase.
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  // Elements per rank (default 40M: 3 arrays x 320 MB per rank).
  const long n = argc > 1 ? std::atol(argv[1]) : 40000000L;
  const int reps = argc > 2 ? std::atoi(argv[2]) : 10;
  std::vector<double> a(n, 1.0), b(n, 2.0), c(n, 0.5);
  const double s = 3.0;
  double best = 1e300;
  for (int r = 0; r < reps; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double t0 = MPI_Wtime();
    for (long i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    MPI_Barrier(MPI_COMM_WORLD);
    const double t = MPI_Wtime() - t0;
    best = std::min(best, t);
  }
  double chk = 0;
  for (long i = 0; i < n; i += 4096) chk += a[i];
  const double gbs = 3.0 * 8.0 * double(n) * size / best / 1e9;
  if (rank == 0) std::printf("triad_gbs %.3f ranks %d n_per_rank %ld best_s %.5f chk %g\n", gbs, size, n, best, chk);
  MPI_Finalize();
  return 0;
}
