#pragma once
// Internal (not installed): the seconds of a build's named phases, for the
// setup reports (DistGraph::build_phases, ProblemReport::setup_phases).
#include <mpi.h>

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace snl {

// done(name) records the seconds since the previous mark (or construction) in out.
class PhaseClock {
 public:
  explicit PhaseClock(std::vector<std::pair<std::string, double>>& out) : out_(out), mark_(MPI_Wtime()) {}
  void done(std::string_view name) {
    const double now = MPI_Wtime();
    out_.emplace_back(std::string(name), now - mark_);
    mark_ = now;
  }

 private:
  std::vector<std::pair<std::string, double>>& out_;
  double mark_;
};

}  // namespace snl
