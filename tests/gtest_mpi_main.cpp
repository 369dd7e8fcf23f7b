// GoogleTest main for snl: initialises MPI, runs the tests on every rank, and
// makes every rank report its own failures (prefixed by the rank); rank 0 prints
// the usual progress. The exit status is non-zero if any rank failed, and
// kSkipped (ctest's SKIP_RETURN_CODE) if none failed but a test was skipped
// on some rank (GTEST_SKIP: it could not run here), so that ctest reports the
// file as skipped rather than passed.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>

namespace {

constexpr int kSkipped = 77;

class RankFailurePrinter : public testing::EmptyTestEventListener {
 public:
  explicit RankFailurePrinter(int rank) : rank_(rank) {}
  void OnTestPartResult(const testing::TestPartResult& r) override {
    if (!r.failed()) return;
    std::fprintf(stderr, "[rank %d] FAILURE %s:%d\n%s\n", rank_, r.file_name() ? r.file_name() : "?",
                 r.line_number(), r.summary());
    std::fflush(stderr);
  }

 private:
  int rank_;
};

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  auto& listeners = testing::UnitTest::GetInstance()->listeners();
  if (rank != 0) delete listeners.Release(listeners.default_result_printer());
  listeners.Append(new RankFailurePrinter(rank));
  int status[2] = {RUN_ALL_TESTS(), testing::UnitTest::GetInstance()->skipped_test_count() > 0 ? 1 : 0};
  MPI_Allreduce(MPI_IN_PLACE, status, 2, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  if (status[0] != 0) return status[0];
  return status[1] ? kSkipped : 0;
}
