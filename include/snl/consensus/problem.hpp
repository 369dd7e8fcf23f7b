#pragma once
// Consensus optimisation problems (seed 001): minimise F(x) = sum_p f_p(x) over a
// connected network in which only node p knows its strictly convex f_p.
// This header is the contract between the problem side (file format of
// the shared spec consensus.md, documented in docs/consensus.md; generator, validation, the
// local objectives) and the distributed solvers (src/consensus/*).
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "snl/core/common.hpp"

namespace snl::consensus {

enum class Family { kExp, kQuadratic, kLogistic, kLeastSquares };
const char* family_name(Family f);          ///< "exp" | "quadratic" | "logistic" | "least_squares"
/// Families whose data are samples (features, labels, owner) and lambda.
inline bool has_samples(Family f) { return f == Family::kLogistic || f == Family::kLeastSquares; }
Family parse_family(const std::string& s);  ///< throws snl::Error on anything else

/// Everything a problem file holds, in file order (node ids 0..n-1).
struct ProblemData {
  GlobalId num_nodes = 0;
  int dim = 1;  ///< q, the size of x
  Family family = Family::kExp;
  std::vector<GlobalId> edges;       ///< [E*2] undirected links, each once, i != j
  std::vector<GlobalId> truth_path;  ///< [n] a Hamilton path in path order, or empty
  // family exp (q = 1): f_p(x) = a_p e^(b_p x) + c_p e^(-d_p x)
  std::vector<double> exp_a, exp_b, exp_c, exp_d;  ///< [n] each, all > 0
  // family quadratic: f_p(x) = 1/2 sum_k h_pk (x_k - r_pk)^2
  std::vector<double> quad_h, quad_r;  ///< [n*q] row-major, h > 0
  // family logistic: f_p(x) = sum_{s: owner_s = p} log(1 + e^(-y_s a_s.x)) + (lambda / 2n) x.x
  std::vector<double> features;   ///< [S*q] row-major
  std::vector<double> labels;     ///< [S], each +1 or -1 (logistic), finite (least_squares)
  std::vector<GlobalId> owner;    ///< [S], node ids in [0, n)
  // family least_squares: f_p(x) = sum_{s: owner_s = p} (a_s.x - b_s)^2 + (lambda / 2n) x.x,
  // the same datasets with labels[s] = b_s (any finite real)
  double lambda = 0.0;            ///< > 0 (logistic, least_squares)
  std::int64_t num_samples() const { return static_cast<std::int64_t>(labels.size()); }
};

/// Collective over comm: reads and validates a problem file; every rank gets the
/// whole ProblemData. Throws snl::Error (same message on every rank) naming the
/// dataset and first bad row for any rule of the format, and when the graph is not
/// connected or truth_path is not a Hamilton path of the graph.
ProblemData read_problem(MPI_Comm comm, const std::string& path);

/// Writes a problem file atomically (temporary file + rename). Rank 0 writes;
/// collective so that every rank learns of a failure.
void write_problem(MPI_Comm comm, const std::string& path, const ProblemData& data);

/// Validation without I/O (also used by read_problem and by tests).
void validate_problem(const ProblemData& data);

struct GenerateOptions {
  GlobalId nodes = 100;
  double avg_degree = 6.0;
  Family family = Family::kExp;
  int dim = 1;                  ///< q; must be 1 for exp
  bool hamiltonian = false;     ///< plant a Hamilton path (stored in truth_path)
  std::uint64_t seed = 1;
  std::int64_t samples_per_node = 20;  ///< logistic, least_squares
  double lambda = 1.0;                 ///< logistic, least_squares
  void validate() const;               ///< throws snl::Error
};
/// Random geometric graph in the unit square with the requested average degree,
/// made connected, and the family's parameters; deterministic in the seed.
ProblemData generate_problem(const GenerateOptions& options);

/// What generate_problem did (for the command's summary).
struct GenerateReport {
  double radius = 0;             ///< link radius of the random geometric graph
  GlobalId geometric_links = 0;  ///< links within the radius
  GlobalId path_links = 0;       ///< links added by the planted Hamilton path (not already there)
  GlobalId components = 0;       ///< components before joining (after the path, if any)
  GlobalId connect_links = 0;    ///< links added to join them (nearest pairs)
};
ProblemData generate_problem(const GenerateOptions& options, GenerateReport* report);

/// The local objectives of a set of nodes (a rank's owned nodes, in its local
/// order): f_p, its gradient and Hessian at a q-vector x.
class LocalObjectives {
 public:
  LocalObjectives() = default;
  /// nodes[v] = global id of local node v. Keeps only those nodes' data.
  LocalObjectives(const ProblemData& data, const std::vector<GlobalId>& nodes);
  int dim() const { return dim_; }
  Family family() const { return family_; }
  std::int64_t size() const { return static_cast<std::int64_t>(nodes_.size()); }
  double value(LocalId v, const double* x) const;
  void gradient(LocalId v, const double* x, double* g) const;  ///< g[q]
  void hessian(LocalId v, const double* x, double* h) const;   ///< h[q*q] row-major, SPD

 private:
  Family family_ = Family::kExp;
  int dim_ = 1;
  GlobalId n_global_ = 0;
  double lambda_ = 0.0;
  std::vector<GlobalId> nodes_;
  std::vector<double> p0_, p1_, p2_, p3_;          // exp a, b, c, d or quadratic h, r (per node)
  std::vector<std::int64_t> sample_begin_;          // logistic, least_squares: [size+1] into features_/labels_
  std::vector<double> features_, labels_;
};

}  // namespace snl::consensus
