// STREAM triad a[i] = b[i] + s * c[i] (McCalpin), one MPI process per core,
// arrays far larger than the caches. The bandwidth bound of docs/performance.md
// is memory traffic per second, counted the way the solver's traffic model
// counts it: every array once, a written array as one transfer. The kernels
// write their rows with non-temporal stores (src/kernels/avx2.cpp,
// avx512.cpp: store_own), which move exactly those bytes, so the yardstick is
// a triad with non-temporal stores, 3 x 8 bytes per element: triad_nt_gbs.
//
// The plain-store triad is timed too and printed in two ways, for relating the
// records taken before this yardstick: plain_24B_gbs = 24 bytes per element
// (the figure STREAM reports and the old bench printed as triad_gbs; its
// stores read each line for ownership first, so the memory moves 32 bytes per
// element) and plain_32B_gbs = the same time with that write-allocate counted.
// docs/performance.md "The bandwidth yardstick" gives the conversion.
//
// Output, one line from rank 0 (scripts read the 2nd field):
//   triad_nt_gbs X ranks R n_per_rank N best_s T plain_24B_gbs Y plain_32B_gbs Z chk C
// Best over reps of each kind, the two kinds alternated rep by rep.
#include <emmintrin.h>  // _mm_stream_pd, _mm_sfence (SSE2, in every x86-64)
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

// 64-byte aligned array filled with v (aligned_alloc: the stores need 16-byte
// alignment; a line start avoids split lines).
double* make_array(long n, double v) {
  const size_t bytes = ((size_t(n) * sizeof(double) + 63) / 64) * 64;
  auto* p = static_cast<double*>(std::aligned_alloc(64, bytes));
  if (p == nullptr) {
    std::fprintf(stderr, "stream_triad: cannot allocate %zu bytes\n", bytes);
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  std::fill(p, p + n, v);
  return p;
}

void triad_plain(double* a, const double* b, const double* c, double s, long n) {
  for (long i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
}

// The same triad with non-temporal stores: lines are written without being
// read first, as the kernels write their rows.
void triad_nt(double* a, const double* b, const double* c, double s, long n) {
  const __m128d vs = _mm_set1_pd(s);
  long i = 0;
  for (; i + 2 <= n; i += 2) {
    const __m128d v = _mm_add_pd(_mm_load_pd(b + i), _mm_mul_pd(vs, _mm_load_pd(c + i)));
    _mm_stream_pd(a + i, v);
  }
  for (; i < n; ++i) a[i] = b[i] + s * c[i];
  _mm_sfence();  // the streamed lines are globally visible before the clock stops
}

// Wall time of one triad on all ranks at once (barrier before and after).
template <class F>
double timed(F&& f) {
  MPI_Barrier(MPI_COMM_WORLD);
  const double t0 = MPI_Wtime();
  f();
  MPI_Barrier(MPI_COMM_WORLD);
  return MPI_Wtime() - t0;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  // Elements per rank (default 40M: 3 arrays x 320 MB per rank).
  const long n = argc > 1 ? std::atol(argv[1]) : 40000000L;
  const int reps = argc > 2 ? std::atoi(argv[2]) : 10;
  double* a = make_array(n, 1.0);
  double* b = make_array(n, 2.0);
  double* c = make_array(n, 0.5);
  const double s = 3.0;
  double best_nt = 1e300, best_plain = 1e300;
  for (int r = 0; r < reps; ++r) {
    best_nt = std::min(best_nt, timed([&] { triad_nt(a, b, c, s, n); }));
    best_plain = std::min(best_plain, timed([&] { triad_plain(a, b, c, s, n); }));
  }
  double chk = 0;
  for (long i = 0; i < n; i += 4096) chk += a[i];
  const double elems = double(n) * size;
  const double nt = 24.0 * elems / best_nt / 1e9;
  const double plain24 = 24.0 * elems / best_plain / 1e9;
  const double plain32 = 32.0 * elems / best_plain / 1e9;
  if (rank == 0)
    std::printf("triad_nt_gbs %.3f ranks %d n_per_rank %ld best_s %.5f plain_24B_gbs %.3f plain_32B_gbs %.3f chk %g\n",
                nt, size, n, best_nt, plain24, plain32, chk);
  std::free(a);
  std::free(b);
  std::free(c);
  MPI_Finalize();
  return 0;
}
