// Consensus problem files ("snl-consensus" version 1, docs/consensus.md): a
// collective reader (every rank reads the whole file and validates it; the
// checks are deterministic, so every rank reports the same first violation) and
// an atomic writer on rank 0.
#include <cstdint>
#include <new>
#include <string>
#include <vector>

#include "consensus/problem_detail.hpp"
#include "snl/consensus/problem.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/h5file.hpp"

namespace snl::consensus {

const char* family_name(Family f) {
  switch (f) {
    case Family::kExp: return "exp";
    case Family::kQuadratic: return "quadratic";
    case Family::kLogistic: return "logistic";
    case Family::kLeastSquares: return "least_squares";
  }
  return "?";
}

Family parse_family(const std::string& s) {
  if (s == "exp") return Family::kExp;
  if (s == "quadratic") return Family::kQuadratic;
  if (s == "logistic") return Family::kLogistic;
  if (s == "least_squares") return Family::kLeastSquares;
  throw Error("unknown family '" + s + "' (expected exp, quadratic, logistic or least_squares)");
}

namespace {

using Shape = std::vector<std::uint64_t>;

std::string shape_text(const Shape& s) {
  std::string t = "[";
  for (std::size_t k = 0; k < s.size(); ++k) t += (k ? ", " : "") + std::to_string(s[k]);
  return t + "]";
}

std::string attr_where(const H5File& f, const std::string& name) { return f.path() + ": root attribute '" + name + "'"; }

std::int64_t required_int(const H5File& f, const std::string& name) {
  if (!f.has_attr(name)) throw Error(attr_where(f, name) + " is missing");
  return f.attr_int(name);
}

std::string required_string(const H5File& f, const std::string& name) {
  if (!f.has_attr(name)) throw Error(attr_where(f, name) + " is missing");
  return f.attr_string(name);
}

/// Shape of a required dataset, checked against `want` (0 in want: any size,
/// returned in the shape).
Shape required_shape(const H5File& f, const std::string& name, const Shape& want, const std::string& text) {
  if (!f.has_dataset(name)) throw Error(f.path() + ": required dataset '" + name + "' is missing");
  const Shape got = f.shape(name);
  bool ok = got.size() == want.size();
  for (std::size_t k = 0; ok && k < got.size(); ++k) ok = want[k] == 0 || got[k] == want[k];
  if (!ok)
    throw Error(f.path() + ": dataset '" + name + "' has shape " + shape_text(got) + ", expected " + text);
  return got;
}

/// The names of each family's datasets, for the "belongs to another family" check.
struct FamilySets {
  Family family;
  std::vector<const char*> names;
};
const FamilySets kFamilySets[] = {{Family::kExp, {"exp_a", "exp_b", "exp_c", "exp_d"}},
                                  {Family::kQuadratic, {"quad_h", "quad_r"}},
                                  {Family::kLogistic, {"features", "labels", "owner"}},
                                  {Family::kLeastSquares, {"features", "labels", "owner"}}};

/// Whether `name` is one of family f's own datasets.
bool owns(Family f, const char* name) {
  for (const auto& fs : kFamilySets)
    if (fs.family == f)
      for (const char* own : fs.names)
        if (std::string(own) == name) return true;
  return false;
}

/// Root attributes; fills num_nodes, dim, family (and lambda for logistic).
void read_attributes(const H5File& f, ProblemData& d) {
  const std::string format = required_string(f, "format");
  if (format != "snl-consensus")
    throw Error(attr_where(f, "format") + " is '" + format + "', expected 'snl-consensus'");
  const std::int64_t version = required_int(f, "version");
  if (version != 1)
    throw Error(attr_where(f, "version") + " is " + std::to_string(version) +
                ": unsupported consensus format version (this snl reads version 1)");
  d.num_nodes = required_int(f, "num_nodes");
  if (d.num_nodes < 2 || d.num_nodes > kMaxNodes)
    throw Error(attr_where(f, "num_nodes") + " must be in [2, " + std::to_string(kMaxNodes) + "], got " +
                std::to_string(d.num_nodes));
  const std::int64_t dim = required_int(f, "dim");
  if (dim < 1 || dim > kMaxDim)
    throw Error(attr_where(f, "dim") + " must be in [1, " + std::to_string(kMaxDim) + "], got " + std::to_string(dim));
  d.dim = static_cast<int>(dim);
  const std::string fam = required_string(f, "family");
  try {
    d.family = parse_family(fam);
  } catch (const Error&) {
    throw Error(attr_where(f, "family") + " is '" + fam +
                "', expected 'exp', 'quadratic', 'logistic' or 'least_squares'");
  }
  if (d.family == Family::kExp && d.dim != 1)
    throw Error(attr_where(f, "dim") + " must be 1 for family 'exp' (f_p is scalar), got " + std::to_string(d.dim));
  if (has_samples(d.family)) {
    if (!f.has_attr("lambda"))
      throw Error(attr_where(f, "lambda") + " is missing (required by family '" + family_name(d.family) + "')");
    d.lambda = f.attr_double("lambda");
  }
}

/// Datasets: shapes first (nothing is read before every shape is right), then data.
void read_datasets(const H5File& f, ProblemData& d) {
  const auto n = static_cast<std::uint64_t>(d.num_nodes), q = static_cast<std::uint64_t>(d.dim);
  const std::string nq = "[num_nodes, dim] = [" + std::to_string(n) + ", " + std::to_string(q) + "]";
  for (const auto& fs : kFamilySets)
    for (const char* name : fs.names)
      if (fs.family != d.family && !owns(d.family, name) && f.has_dataset(name))
        throw Error(f.path() + ": dataset '" + name + "' belongs to family '" + family_name(fs.family) +
                    "', but attribute 'family' is '" + family_name(d.family) + "'");

  const Shape es = required_shape(f, "edges", {0, 2}, "[E, 2]");
  const bool has_path = f.has_dataset("truth_path");
  if (has_path) required_shape(f, "truth_path", {n}, "[num_nodes] = [" + std::to_string(n) + "]");
  std::uint64_t S = 0;
  switch (d.family) {
    case Family::kExp:
      for (const char* name : {"exp_a", "exp_b", "exp_c", "exp_d"})
        required_shape(f, name, {n}, "[num_nodes] = [" + std::to_string(n) + "]");
      break;
    case Family::kQuadratic:
      required_shape(f, "quad_h", {n, q}, nq);
      required_shape(f, "quad_r", {n, q}, nq);
      break;
    case Family::kLogistic:
    case Family::kLeastSquares:
      S = required_shape(f, "labels", {0}, "[S]")[0];
      required_shape(f, "features", {S, q}, "[S, dim] = [" + std::to_string(S) + ", " + std::to_string(q) + "] (S = rows of labels)");
      required_shape(f, "owner", {S}, "[S] = [" + std::to_string(S) + "] (S = rows of labels)");
      break;
  }

  d.edges = f.read_rows_int("edges", 0, es[0]);
  if (has_path) d.truth_path = f.read_rows_int("truth_path", 0, n);
  switch (d.family) {
    case Family::kExp:
      d.exp_a = f.read_rows_double("exp_a", 0, n);
      d.exp_b = f.read_rows_double("exp_b", 0, n);
      d.exp_c = f.read_rows_double("exp_c", 0, n);
      d.exp_d = f.read_rows_double("exp_d", 0, n);
      break;
    case Family::kQuadratic:
      d.quad_h = f.read_rows_double("quad_h", 0, n);
      d.quad_r = f.read_rows_double("quad_r", 0, n);
      break;
    case Family::kLogistic:
    case Family::kLeastSquares:
      d.labels = f.read_rows_double("labels", 0, S);
      d.features = f.read_rows_double("features", 0, S);
      d.owner = f.read_rows_int("owner", 0, S);
      break;
  }
}

// ---------------------------------------------------------------------------
// Writer: checks only what it needs to write without reading out of bounds;
// content is the reader's business (tests write broken files this way).

void write_vector(H5File& f, const char* name, const std::vector<double>& v, std::uint64_t cols) {
  const std::uint64_t rows = cols ? v.size() / cols : v.size();
  f.write_rows(name, rows, cols, 0, v.data(), rows);
}

void write_serial(const std::string& path, const ProblemData& d) {
  const auto q = static_cast<std::uint64_t>(d.dim);
  const auto fail = [&](const std::string& why) { throw Error("cannot write " + path + ": " + why); };
  if (d.dim < 1) fail("dim must be positive");
  if (d.edges.size() % 2 != 0) fail("edges must hold pairs");
  if (d.quad_h.size() % q != 0 || d.quad_r.size() % q != 0 || d.features.size() % q != 0)
    fail("quad_h, quad_r and features must hold whole rows of dim values");

  H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
  f.set_attr("format", std::string("snl-consensus"));
  f.set_attr("version", std::int64_t{1});
  f.set_attr("num_nodes", std::int64_t{d.num_nodes});
  f.set_attr("dim", std::int64_t{d.dim});
  f.set_attr("family", std::string(family_name(d.family)));
  if (has_samples(d.family)) f.set_attr("lambda", d.lambda);
  const std::uint64_t E = d.edges.size() / 2;
  f.write_rows("edges", E, 2, 0, d.edges.data(), E);
  if (!d.truth_path.empty()) f.write_rows("truth_path", d.truth_path.size(), 0, 0, d.truth_path.data(), d.truth_path.size());
  // A family's own datasets always (even empty); another family's only when present.
  const auto own = [&](Family fam, bool present) { return d.family == fam || present; };
  if (own(Family::kExp, !d.exp_a.empty())) write_vector(f, "exp_a", d.exp_a, 0);
  if (own(Family::kExp, !d.exp_b.empty())) write_vector(f, "exp_b", d.exp_b, 0);
  if (own(Family::kExp, !d.exp_c.empty())) write_vector(f, "exp_c", d.exp_c, 0);
  if (own(Family::kExp, !d.exp_d.empty())) write_vector(f, "exp_d", d.exp_d, 0);
  if (own(Family::kQuadratic, !d.quad_h.empty())) write_vector(f, "quad_h", d.quad_h, q);
  if (own(Family::kQuadratic, !d.quad_r.empty())) write_vector(f, "quad_r", d.quad_r, q);
  const bool samples = has_samples(d.family);
  if (samples || !d.features.empty()) write_vector(f, "features", d.features, q);
  if (samples || !d.labels.empty()) write_vector(f, "labels", d.labels, 0);
  if (samples || !d.owner.empty()) f.write_rows("owner", d.owner.size(), 0, 0, d.owner.data(), d.owner.size());
  f.commit();
}

}  // namespace

ProblemData read_problem(MPI_Comm comm, const std::string& path) {
  ProblemData d;
  H5File f(path, comm, H5File::Mode::kRead);
  collective_try(comm, [&] {
    read_attributes(f, d);
    read_datasets(f, d);
  });
  f.commit();
  // Every rank holds the same data, so every rank finds the same first
  // violation; agree() still guards against a rank-local failure (memory).
  std::string err;
  try {
    err = check_problem(d);
    if (!err.empty()) err = path + ": " + err;
  } catch (const std::bad_alloc&) {
    err = path + ": out of memory while checking the problem";
  }
  agree(comm, err);
  return d;
}

void write_problem(MPI_Comm comm, const std::string& path, const ProblemData& data) {
  collective_try(comm, [&] {
    if (comm_rank(comm) == 0) write_serial(path, data);
  });
}

}  // namespace snl::consensus
