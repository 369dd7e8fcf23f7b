#pragma once
// Helpers of the distributed solver tests (tests/mpi/test_{halo,problem,
// relaxation,mm,pm_async,temporal_block,solver}_mpi.cpp): a network with its
// duplicates merged as the problem merges them, a fixed-length solve from the
// tests' common start, and the world rank and size for sub-communicators.
#include <mpi.h>

#include <cmath>
#include <string>
#include <vector>

#include "snl/solvers/solver.hpp"
#include "test_networks.hpp"

namespace snl::test {

/// `w` with its duplicate rows merged as LocalizationProblem merges them.
inline Network merged(Network w) {
  merge_duplicates(w.sensor_edges, w.sensor_ranges, w.anchor_edges, w.anchor_ranges);
  w.total_sensor_edges = w.local_sensor_edges();
  w.total_anchor_edges = w.local_anchor_edges();
  return w;
}

/// Positions (global order) after `iters` iterations of `alg` on `comm`, with
/// up to `block` iterations per pass over memory (SolverOptions::temporal_block),
/// from random_initial_positions(prob, 3).
inline std::vector<double> run(MPI_Comm comm, const Network& whole, const std::string& alg, int iters,
                               PartitionMethod pm = PartitionMethod::kMetis, int block = 1) {
  LocalizationProblem prob(comm, slab_of(whole, comm), pm, nullptr);
  SolverOptions opt;
  opt.algorithm = alg;
  opt.max_iter = iters;
  opt.tol = 0;
  opt.history_every = 1000000;
  opt.temporal_block = block;
  Solver solver(prob, opt);
  std::vector<double> x;
  solver.solve(random_initial_positions(prob, 3), &x);
  return allgather_positions(prob, x);
}

/// A whole solve's summary and its positions (global order).
struct Outcome {
  Summary s;
  std::vector<double> x;
};

/// `opt` solved on `comm` from random_initial_positions(prob, 3).
inline Outcome solve_outcome(MPI_Comm comm, const Network& whole, const SolverOptions& opt) {
  LocalizationProblem prob(comm, slab_of(whole, comm), PartitionMethod::kMetis, nullptr);
  Solver solver(prob, opt);
  Outcome o;
  std::vector<double> x;
  o.s = solver.solve(random_initial_positions(prob, 3), &x);
  o.x = allgather_positions(prob, x);
  return o;
}

/// A method's own value in a summary (Summary::method_values), NaN if absent.
inline double method_value(const Summary& s, const std::string& key) {
  for (const auto& v : s.method_values)
    if (v.first == key) return v.second;
  return NAN;
}

inline int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
inline int world_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

}  // namespace snl::test
