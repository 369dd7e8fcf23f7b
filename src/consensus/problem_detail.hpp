#pragma once
// Internal helpers shared by the consensus problem files (reader, validation,
// generator). Not installed.
#include <cstdint>
#include <string>
#include <vector>

#include "snl/consensus/problem.hpp"

namespace snl::consensus {

/// Limits of the format as this snl reads it: node ids fit a LocalId on one
/// rank, and a q x q Hessian per node stays small.
constexpr GlobalId kMaxNodes = 2147483647;
constexpr int kMaxDim = 4096;

/// Undirected adjacency in CSR form, neighbours sorted (ids already checked).
struct Adjacency {
  Adjacency(GlobalId n, const std::vector<GlobalId>& edges);
  bool linked(GlobalId i, GlobalId j) const;
  std::vector<std::int64_t> offset;  ///< [n + 1]
  std::vector<GlobalId> col;
};

/// The first violated rule of the format, or "" when the problem is valid.
/// Messages name the dataset (or attribute) and the first bad row.
std::string check_problem(const ProblemData& data);

}  // namespace snl::consensus
