#pragma once
// Helpers that make every rank agree on errors, so a failure on one rank never
// leaves the others hanging in a collective.
#include <mpi.h>

#include <cstdint>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "snl/core/common.hpp"

namespace snl {

int comm_rank(MPI_Comm comm);
int comm_size(MPI_Comm comm);

/// Collective: whether `mine` holds on every rank / on some rank.
bool all_ranks(MPI_Comm comm, bool mine);
bool any_rank(MPI_Comm comm, bool mine);

/// A private duplicate of a communicator (MPI_Comm_dup, as PetscCommDuplicate
/// does), freed once by its owner: messages an object sends on it cannot match
/// the caller's traffic on the original, whatever the tags. Move-only; a move
/// swaps, so the duplicate is freed exactly once by whoever ends up with it.
class DupComm {
 public:
  DupComm() = default;
  /// Collective over comm.
  explicit DupComm(MPI_Comm comm);
  ~DupComm();
  DupComm(const DupComm&) = delete;
  DupComm& operator=(const DupComm&) = delete;
  DupComm(DupComm&& o) noexcept { std::swap(comm_, o.comm_); }
  DupComm& operator=(DupComm&& o) noexcept {
    std::swap(comm_, o.comm_);
    return *this;
  }
  MPI_Comm get() const { return comm_; }

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
};

/// Collective. If any rank passes a non-empty message, every rank throws
/// snl::Error carrying the message of the lowest such rank.
void agree(MPI_Comm comm, const std::string& local_error);

/// Collective. Like agree(), but the message chosen is the one with the smallest
/// key (e.g. the first offending row of a dataset across all ranks' slabs).
void agree_first(MPI_Comm comm, std::int64_t key, const std::string& local_error);

/// Collective. Runs f(); an exception on any rank becomes an snl::Error on all.
template <class F>
void collective_try(MPI_Comm comm, F&& f) {
  std::string err;
  try {
    f();
  } catch (const std::bad_alloc&) {
    err = "out of memory";
  } catch (const std::exception& e) {
    err = e.what();
    if (err.empty()) err = "unknown error";
  }
  agree(comm, err);
}

/// Prints "snl: error: rank R: <what>; aborting all ranks" on stderr and calls
/// MPI_Abort (status 70). For failures that only some ranks see inside code
/// that runs collectives, where agreeing on the error would itself hang.
[[noreturn]] void abort_all(MPI_Comm comm, const std::string& what);

/// Runs f(), code with collectives inside. snl::Error is raised identically on
/// every rank (agreed), so it propagates; any other exception (std::bad_alloc,
/// a bug) is rank-local and cannot be agreed on without a hang: abort_all().
template <class F>
void abort_on_local_failure(MPI_Comm comm, const char* stage, F&& f) {
  try {
    f();
  } catch (const Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    abort_all(comm, std::string("out of memory during ") + stage);
  } catch (const std::exception& e) {
    abort_all(comm, std::string(e.what()) + " (during " + stage + ")");
  }
}

/// Fault-injection hook for tests. With SNL_TEST_FAIL=<point>:<rank>[:<iter>]
/// in the environment, the process of that MPI_COMM_WORLD rank throws when it
/// reaches test_fail_point(point) (and, if <iter> is given, iteration == iter):
/// std::bad_alloc for the point "alloc", std::runtime_error otherwise. A no-op
/// (one getenv at the first call) when the variable is unset.
void test_fail_point(const char* point, long long iteration = -1);

/// Slow-down hook for tests: sleeps `units` times the seconds given by the
/// environment variable `env` (e.g. SNL_TEST_ITERATION_DELAY, per iteration),
/// so that a run of known length meets a time limit or a signal whatever the
/// machine's load. A no-op when the variable is unset.
void test_delay(const char* env, double units = 1.0);

/// Broadcast a string from root.
std::string bcast_string(MPI_Comm comm, const std::string& s, int root = 0);

/// Concatenation of every rank's vector on `root` (empty elsewhere), in rank
/// order; counts may exceed INT_MAX in total.
std::vector<std::int64_t> gather_to_root(MPI_Comm comm, const std::vector<std::int64_t>& mine, int root = 0);

/// Large-count helpers (counts above INT_MAX are split into chunks).
void bcast_bytes(MPI_Comm comm, void* data, std::size_t bytes, int root = 0);

}  // namespace snl
