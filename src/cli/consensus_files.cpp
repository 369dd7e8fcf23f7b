// `snl info` and `snl export` on consensus files (docs/consensus.md): a problem
// (format snl-consensus) or a result of `snl consensus solve` (format
// snl-consensus-result). Serial, on the calling rank.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "cli/cli_util.hpp"
#include "core/json.hpp"
#include "snl/consensus/problem.hpp"
#include "snl/io/h5file.hpp"

namespace snl::detail {

std::string hdf5_format(const std::string& path) {
  try {
    H5File f(path, MPI_COMM_SELF, H5File::Mode::kRead);
    if (!f.has_attr("format") || !f.attr_is_string("format")) return "";
    return f.attr_string("format");
  } catch (const Error&) {
    return "";  // not an HDF5 file (or none): the command's own reader says why
  }
}

namespace {

std::string yes_no(bool b) { return b ? "yes" : "no"; }

/// x [n, q] and the attributes of a consensus result.
struct ConsensusResult {
  std::int64_t n = 0, q = 0;
  std::vector<double> x;
};

ConsensusResult read_consensus_x(const H5File& f) {
  ConsensusResult r;
  const std::string& path = f.path();
  for (const char* a : {"num_nodes", "dim"})
    if (!f.has_attr(a)) throw Error(path + ": root attribute '" + std::string(a) + "' is missing");
  r.n = f.attr_int("num_nodes");
  r.q = f.attr_int("dim");
  if (!f.has_dataset("x")) throw Error(path + ": required dataset 'x' is missing");
  const auto shape = f.shape("x");
  if (r.n < 1 || r.q < 1 || shape.size() != 2 || shape[0] != static_cast<std::uint64_t>(r.n) ||
      shape[1] != static_cast<std::uint64_t>(r.q))
    throw Error(path + ": dataset 'x' does not have shape [num_nodes, dim] = [" + std::to_string(r.n) + ", " +
                std::to_string(r.q) + "]");
  r.x = f.read_rows_double("x", 0, static_cast<std::uint64_t>(r.n));
  return r;
}

std::string attr_text(const H5File& f, const std::string& name) {
  if (!f.has_attr(name)) return "n/a";
  if (f.attr_is_string(name)) return f.attr_string(name);
  const double v = f.attr_double(name);
  return std::isfinite(v) ? fmt(v, 10) : "not known";  // NaN: e.g. the error against an unconverged x*
}

}  // namespace

std::string consensus_info(const std::string& path, const std::string& format, std::string* json) {
  std::ostringstream os;
  JsonObject j;
  j.add("file", path).add("format", format);
  if (format == "snl-consensus") {
    const consensus::ProblemData d = consensus::read_problem(MPI_COMM_SELF, path);  // every rule checked
    const auto E = static_cast<std::int64_t>(d.edges.size() / 2);
    const bool samples = consensus::has_samples(d.family);
    os << path << ": valid snl-consensus v1 (consensus problem)\n"
       << "  family " << consensus::family_name(d.family) << ", nodes n = " << d.num_nodes << ", dimension q = " << d.dim
       << "\n"
       << "  links = " << E << " (mean degree " << fmt(2.0 * static_cast<double>(E) / static_cast<double>(d.num_nodes), 4)
       << ")\n";
    if (samples) {
      std::vector<char> has(static_cast<std::size_t>(d.num_nodes), 0);
      for (GlobalId v : d.owner) has[v] = 1;
      const auto empty = std::count(has.begin(), has.end(), 0);
      os << "  samples = " << d.num_samples() << " (" << empty << " nodes without samples), lambda = "
         << fmt(d.lambda, 10) << "\n";
      j.add("samples", d.num_samples()).add("nodes_without_samples", static_cast<std::int64_t>(empty)).add("lambda", d.lambda);
    }
    os << "  Hamilton path (truth_path): " << yes_no(!d.truth_path.empty());
    j.add("family", consensus::family_name(d.family))
        .add("num_nodes", static_cast<std::int64_t>(d.num_nodes))
        .add("dim", d.dim)
        .add("links", E)
        .add_bool("hamilton_path", !d.truth_path.empty());
  } else {
    const H5File f(path, MPI_COMM_SELF, H5File::Mode::kRead);
    const ConsensusResult r = read_consensus_x(f);
    // Disagreement between the nodes' copies: max over nodes and coordinates of |x_p - x_0|.
    double spread = 0;
    for (std::int64_t p = 1; p < r.n; ++p)
      for (std::int64_t k = 0; k < r.q; ++k)
        spread = std::max(spread, std::abs(r.x[static_cast<std::size_t>(p * r.q + k)] - r.x[static_cast<std::size_t>(k)]));
    const bool converged = f.has_attr("converged") && f.attr_int("converged") != 0;
    os << path << ": snl-consensus-result v1 (result of snl consensus solve)\n"
       << "  problem " << attr_text(f, "problem") << ", nodes n = " << r.n << ", dimension q = " << r.q << "\n"
       << "  method " << attr_text(f, "method") << " (dual " << attr_text(f, "dual") << ", step "
       << attr_text(f, "step_rule") << "), termination " << attr_text(f, "termination") << ", converged "
       << yes_no(converged) << "\n"
       << "  iterations " << attr_text(f, "iterations") << ", dual iterations " << attr_text(f, "dual_iterations")
       << ", messages per node " << attr_text(f, "messages_per_node") << "\n"
       << "  F = " << attr_text(f, "F") << ", max |x_p - x*| = " << attr_text(f, "max_abs_error")
       << ", max |x_p - x_0| = " << fmt(spread, 4) << "\n"
       << "  x at node 0:";
    for (std::int64_t k = 0; k < r.q && k < 8; ++k) os << " " << fmt(r.x[static_cast<std::size_t>(k)], 10);
    if (r.q > 8) os << " ...";
    j.add("num_nodes", r.n)
        .add("dim", r.q)
        .add("method", attr_text(f, "method"))
        .add("termination", attr_text(f, "termination"))
        .add_bool("converged", converged)
        .add("max_node_disagreement", spread);
  }
  if (json) *json = j.str();
  return os.str();
}

std::string consensus_x_csv(const std::string& path, int index_base, std::int64_t* nodes, std::int64_t* dim) {
  const H5File f(path, MPI_COMM_SELF, H5File::Mode::kRead);
  const ConsensusResult r = read_consensus_x(f);
  std::string out = "node";
  for (std::int64_t k = 0; k < r.q; ++k) out += ",x" + std::to_string(k);
  out += '\n';
  char buf[64];
  for (std::int64_t p = 0; p < r.n; ++p) {
    out += std::to_string(p + index_base);
    for (std::int64_t k = 0; k < r.q; ++k) {
      std::snprintf(buf, sizeof buf, ",%.17g", r.x[static_cast<std::size_t>(p * r.q + k)]);
      out += buf;
    }
    out += '\n';
  }
  *nodes = r.n;
  *dim = r.q;
  return out;
}

}  // namespace snl::detail
