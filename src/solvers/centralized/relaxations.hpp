#pragma once
// The centralized convex relaxations of the ML localization problem (internal
// header), each an SDP in the form of sdp_problem.hpp, built from the whole
// network gathered on one rank. All three relax the ML cost of 003 eq. (1),
//   f(x) = sum_{i~j} (||x_i - x_j|| - d_ij)^2 / 2 + sum_{i,k} (||x_i - a_k|| - r_ik)^2 / 2,
// the same way (Simonetto and Leus 2014, the SDP and ESDP of 003's comparison):
// each term becomes (D_e - 2 d_e delta_e + d_e^2) / 2 with D_e the lifted squared
// distance and [1 delta_e; delta_e D_e] >= 0 (delta_e^2 <= D_e); so each optimum
// is a lower bound on the ML optimum f*. They differ in the lifting of D_e:
//  - sdp  (Biswas and Ye): Z = [I_p X; X' Y] >= 0, D_ij = Y_ii + Y_jj - 2 Y_ij;
//  - esdp (Wang, Zheng, Boyd and Ye): only the (p+2)x(p+2) principal submatrices
//    of Z on the measured pairs, and the (p+1)x(p+1) one of every sensor;
//  - edm  (Oguz-Ekim, Gomes, Xavier and Oliveira): a Gram matrix G >= 0 of all
//    n + m points, centred (1'G1 = 0), the anchors' mutual distances as exact
//    measurements (cost terms; the cost is then over these too);
//    positions by classical MDS (the top p eigenpairs of G), then the
//    orthogonal Procrustes map of the anchors' rows onto the anchors.
#include <cstdint>
#include <string>
#include <vector>

#include "solvers/centralized/sdp_problem.hpp"

namespace snl::detail {

/// The whole network on one rank, in global ids, measurements sorted.
struct GatheredNetwork {
  int p = 2;
  std::int64_t n = 0;
  std::vector<double> anchors;  ///< [m * p]
  struct Edge {
    std::int64_t i, j;  ///< sensor ids, i < j
    double d;
  };
  struct AnchorEdge {
    std::int64_t i;  ///< sensor id
    std::int64_t k;  ///< anchor id
    double r;
  };
  std::vector<Edge> edges;
  std::vector<AnchorEdge> anchor_edges;
  std::int64_t num_anchors() const { return static_cast<std::int64_t>(anchors.size()) / p; }
};

enum class RelaxationKind { kSdp, kEsdp, kEdm };

/// The SDP of a relaxation (its sign and offset give the objective in ML-cost units).
SdpProblem build_relaxation(RelaxationKind kind, const GatheredNetwork& net);

/// Positions [n * p] (sensor order) from the solution of build_relaxation(kind, net).
std::vector<double> relaxation_positions(RelaxationKind kind, const GatheredNetwork& net, const SdpSolution& s);

}  // namespace snl::detail
