#include "snl/core/mpi_util.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>

namespace snl {

int comm_rank(MPI_Comm comm) {
  int r = 0;
  MPI_Comm_rank(comm, &r);
  return r;
}

int comm_size(MPI_Comm comm) {
  int s = 1;
  MPI_Comm_size(comm, &s);
  return s;
}

bool all_ranks(MPI_Comm comm, bool mine) {
  int in = mine ? 1 : 0, out = 0;
  MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MIN, comm);
  return out == 1;
}

bool any_rank(MPI_Comm comm, bool mine) {
  int in = mine ? 1 : 0, out = 0;
  MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MAX, comm);
  return out != 0;
}

DupComm::DupComm(MPI_Comm comm) { MPI_Comm_dup(comm, &comm_); }

DupComm::~DupComm() {
  if (comm_ == MPI_COMM_NULL) return;
  int finalized = 0;
  MPI_Finalized(&finalized);  // an object outliving MPI_Finalize must not call MPI
  if (!finalized) MPI_Comm_free(&comm_);
}

std::string bcast_string(MPI_Comm comm, const std::string& s, int root) {
  long long len = static_cast<long long>(s.size());
  MPI_Bcast(&len, 1, MPI_LONG_LONG, root, comm);
  std::string out = comm_rank(comm) == root ? s : std::string(static_cast<std::size_t>(len), '\0');
  if (len > 0) bcast_bytes(comm, out.data(), static_cast<std::size_t>(len), root);
  return out;
}

void bcast_bytes(MPI_Comm comm, void* data, std::size_t bytes, int root) {
  char* p = static_cast<char*>(data);
  const std::size_t chunk = static_cast<std::size_t>(INT_MAX / 2);
  while (bytes > 0) {
    const std::size_t c = std::min(bytes, chunk);
    MPI_Bcast(p, static_cast<int>(c), MPI_BYTE, root, comm);
    p += c;
    bytes -= c;
  }
}

std::vector<std::int64_t> gather_to_root(MPI_Comm comm, const std::vector<std::int64_t>& mine, int root) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  long long count = static_cast<long long>(mine.size());
  std::vector<long long> counts(size);
  MPI_Gather(&count, 1, MPI_LONG_LONG, counts.data(), 1, MPI_LONG_LONG, root, comm);
  std::vector<std::int64_t> all;
  constexpr long long kChunk = 1LL << 27;
  if (rank == root) {
    long long total = 0;
    for (auto c : counts) total += c;
    all.resize(static_cast<std::size_t>(total));
    long long pos = 0;
    for (int r = 0; r < size; ++r) {
      if (r == root) {
        std::copy(mine.begin(), mine.end(), all.begin() + pos);
        pos += count;
        continue;
      }
      for (long long left = counts[r]; left > 0;) {
        const int c = static_cast<int>(std::min(left, kChunk));
        MPI_Recv(all.data() + pos, c, MPI_INT64_T, r, 11, comm, MPI_STATUS_IGNORE);
        pos += c;
        left -= c;
      }
    }
  } else {
    long long pos = 0;
    for (long long left = count; left > 0;) {
      const int c = static_cast<int>(std::min(left, kChunk));
      MPI_Send(mine.data() + pos, c, MPI_INT64_T, root, 11, comm);
      pos += c;
      left -= c;
    }
  }
  return all;
}

void agree_first(MPI_Comm comm, std::int64_t key, const std::string& local_error) {
  struct {
    long long key;
    int rank;
  } mine{}, best{};
  const int rank = comm_rank(comm);
  mine.key = local_error.empty() ? std::numeric_limits<long long>::max() : static_cast<long long>(key);
  mine.rank = rank;
  // MPI_MINLOC on (long long, int) is not a predefined pair type, so reduce in two steps.
  long long min_key = 0;
  MPI_Allreduce(&mine.key, &min_key, 1, MPI_LONG_LONG, MPI_MIN, comm);
  if (min_key == std::numeric_limits<long long>::max()) return;
  int cand = (mine.key == min_key) ? rank : INT_MAX;
  MPI_Allreduce(&cand, &best.rank, 1, MPI_INT, MPI_MIN, comm);
  const std::string msg = bcast_string(comm, local_error, best.rank);
  throw Error(msg);
}

void agree(MPI_Comm comm, const std::string& local_error) {
  agree_first(comm, comm_rank(comm), local_error);
}

void abort_all(MPI_Comm comm, const std::string& what) {
  std::fprintf(stderr, "snl: error: rank %d: %s; aborting all ranks\n", comm_rank(comm), what.c_str());
  std::fflush(stderr);
  MPI_Abort(comm, 70);
  std::abort();  // MPI_Abort does not return; keep [[noreturn]] honest
}

void test_delay(const char* env, double units) {
  static std::map<std::string, double> per_unit;  // each variable read once
  auto it = per_unit.find(env);
  if (it == per_unit.end()) {
    const char* v = std::getenv(env);
    it = per_unit.emplace(env, v ? std::atof(v) : 0.0).first;
  }
  if (it->second > 0) std::this_thread::sleep_for(std::chrono::duration<double>(it->second * units));
}

void test_fail_point(const char* point, long long iteration) {
  struct Spec {
    std::string point;
    int rank = -1;
    long long iteration = -1;
  };
  static const Spec spec = [] {
    Spec s;
    const char* env = std::getenv("SNL_TEST_FAIL");
    if (!env || !*env) return s;
    const std::string v = env;
    const auto c1 = v.find(':');
    if (c1 == std::string::npos) return s;
    const auto c2 = v.find(':', c1 + 1);
    s.point = v.substr(0, c1);
    s.rank = std::atoi(v.substr(c1 + 1, c2 == std::string::npos ? std::string::npos : c2 - c1 - 1).c_str());
    if (c2 != std::string::npos) s.iteration = std::atoll(v.substr(c2 + 1).c_str());
    return s;
  }();
  if (spec.rank < 0 || spec.point != point) return;
  if (spec.iteration >= 0 && spec.iteration != iteration) return;
  int world = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &world);
  if (world != spec.rank) return;
  if (spec.point == "alloc") throw std::bad_alloc();
  throw std::runtime_error("injected failure at '" + spec.point + "' on rank " + std::to_string(world) +
                           (spec.iteration >= 0 ? " iteration " + std::to_string(spec.iteration) : std::string()) +
                           " (SNL_TEST_FAIL)");
}

}  // namespace snl
