// Communicator hygiene of DistGraph and its halo plan: the graph runs on its
// own duplicate of the caller's communicator (so the caller's messages, even
// with the halo's tag, never match the halo's), a move hands the duplicate on
// (freed once), and a plan refuses a second exchange while one is in flight.
#include <gtest/gtest.h>
#include <mpi.h>

#include <string>
#include <utility>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/graph/dist_graph.hpp"

using namespace snl;

namespace {

constexpr GlobalId kNodes = 30;
constexpr int kCallerTag = 7401;  // the tag HaloPlan uses for its messages (src/graph/halo.cpp)

int world_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

// Block owners of a ring of kNodes nodes.
std::vector<int> ring_owner() {
  std::vector<int> owner(kNodes);
  for (GlobalId g = 0; g < kNodes; ++g) owner[g] = static_cast<int>(g * world_size() / kNodes);
  return owner;
}

// The ring (g, g + 1 mod kNodes), all edges given by rank 0, value 1 each.
DistGraph ring_graph(MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::vector<GlobalId> edges;
  std::vector<double> values;
  if (rank == 0)
    for (GlobalId g = 0; g < kNodes; ++g) {
      edges.push_back(g);
      edges.push_back((g + 1) % kNodes);
      values.push_back(1.0);
    }
  return DistGraph(comm, kNodes, ring_owner(), edges, values, 1, 2);
}

// One double per local node: owned rows hold their global id, ghosts -1.
std::vector<double> gid_field(const DistGraph& g) {
  std::vector<double> f(std::size_t(g.num_local()), -1.0);
  for (LocalId v = 0; v < g.num_owned(); ++v) f[v] = double(g.global_id(v));
  return f;
}

void expect_ghosts_hold_gids(const DistGraph& g, const std::vector<double>& f) {
  for (LocalId v = g.num_owned(); v < g.num_local(); ++v) EXPECT_EQ(f[v], double(g.global_id(v))) << "ghost " << v;
}

}  // namespace

TEST(HaloGuard, GraphCommIsACongruentDuplicate) {
  DistGraph g = ring_graph(MPI_COMM_WORLD);
  int cmp = MPI_UNEQUAL;
  MPI_Comm_compare(g.comm(), MPI_COMM_WORLD, &cmp);
  EXPECT_EQ(cmp, MPI_CONGRUENT);
}

TEST(HaloGuard, BeginTwiceThrows) {
  DistGraph g = ring_graph(MPI_COMM_WORLD);
  std::vector<double> f = gid_field(g);
  HaloPlan& halo = g.halo();
  halo.begin(f.data(), 1);
  EXPECT_TRUE(halo.in_flight());
  try {
    halo.begin(f.data(), 1);
    ADD_FAILURE() << "a second begin() did not throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("in flight"), std::string::npos) << e.what();
  }
  halo.end(f.data(), 1);  // the first exchange is intact
  EXPECT_FALSE(halo.in_flight());
  expect_ghosts_hold_gids(g, f);
}

TEST(HaloGuard, EndWithoutBeginThrows) {
  DistGraph g = ring_graph(MPI_COMM_WORLD);
  std::vector<double> f = gid_field(g);
  EXPECT_THROW(g.halo().end(f.data(), 1), Error);
  g.halo().exchange(f.data(), 1);
  EXPECT_THROW(g.halo().end(f.data(), 1), Error);  // the exchange's end() consumed its begin()
  expect_ghosts_hold_gids(g, f);
}

// The caller sends to each halo neighbour, on its own communicator and with
// the halo's tag, a message of exactly the size of the halo's, and receives
// the neighbours' only after the exchange: on a shared communicator the
// halo's receives would match these earlier messages (MPI's non-overtaking
// order) and the ghosts would get the caller's -7 instead of the owners' values.
TEST(HaloGuard, CallerTrafficWithHaloTagDoesNotInterfere) {
  DistGraph g = ring_graph(MPI_COMM_WORLD);
  const std::vector<int> owner = ring_owner();
  const std::vector<int>& nbrs = g.halo().neighbor_ranks();
  std::vector<std::vector<double>> out(nbrs.size()), in(nbrs.size());
  for (std::size_t r = 0; r < nbrs.size(); ++r) {
    std::size_t count = 0;  // ghosts owned by nbrs[r]: the size of the halo's message from it
    for (LocalId v = g.num_owned(); v < g.num_local(); ++v) count += owner[g.global_id(v)] == nbrs[r];
    out[r].assign(count, -7.0);
    in[r].assign(count, 0.0);
  }
  std::vector<MPI_Request> reqs;
  for (std::size_t r = 0; r < nbrs.size(); ++r) {
    reqs.emplace_back();
    MPI_Isend(out[r].data(), int(out[r].size()), MPI_DOUBLE, nbrs[r], kCallerTag, MPI_COMM_WORLD, &reqs.back());
  }
  std::vector<double> f = gid_field(g);
  g.halo().exchange(f.data(), 1);
  for (std::size_t r = 0; r < nbrs.size(); ++r) {
    reqs.emplace_back();
    MPI_Irecv(in[r].data(), int(in[r].size()), MPI_DOUBLE, nbrs[r], kCallerTag, MPI_COMM_WORLD, &reqs.back());
  }
  MPI_Waitall(int(reqs.size()), reqs.data(), MPI_STATUSES_IGNORE);
  expect_ghosts_hold_gids(g, f);
  for (const auto& msg : in)
    for (double d : msg) EXPECT_EQ(d, -7.0);
}

// A moved graph keeps its duplicate and its halo works; the moved-from one
// holds none; a graph moved onto another frees the latter's duplicate once
// (a double free would make MPI fail the run).
TEST(HaloGuard, MoveHandsTheDuplicateOn) {
  DistGraph a = ring_graph(MPI_COMM_WORLD);
  const MPI_Comm dup = a.comm();
  DistGraph b(std::move(a));
  EXPECT_EQ(b.comm(), dup);
  EXPECT_EQ(a.comm(), MPI_COMM_NULL);
  DistGraph c = ring_graph(MPI_COMM_WORLD);
  c = std::move(b);
  EXPECT_EQ(c.comm(), dup);
  std::vector<double> f = gid_field(c);
  c.halo().exchange(f.data(), 1);
  expect_ghosts_hold_gids(c, f);
}
