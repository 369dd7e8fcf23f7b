// Consensus problems (docs/consensus.md): the local objectives against finite
// differences, the file round trip, one test per validation rule (the message
// must name the dataset or attribute), and the generator's promises
// (deterministic, connected, degree near the target, planted Hamilton path).
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "snl/consensus/problem.hpp"
#include "snl/io/h5file.hpp"
#include "test_util.hpp"

using namespace snl;
using namespace snl::consensus;

namespace {

std::string scratch(const std::string& name) { return test::scratch_dir(MPI_COMM_SELF) + "/" + name; }

GenerateOptions small(Family f, int dim = 1, GlobalId n = 40) {
  GenerateOptions o;
  o.nodes = n;
  o.avg_degree = std::min(6.0, static_cast<double>(n - 1));
  o.family = f;
  o.dim = dim;
  o.seed = 7;
  o.samples_per_node = 5;
  o.lambda = 0.5;
  return o;
}

/// The message of the snl::Error that f throws ("" if none).
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string validation_error(const ProblemData& d) {
  return error_of([&] { validate_problem(d); });
}

// ---------------------------------------------------------------------------
// Local objectives: gradient and Hessian against central differences.

void check_derivatives(const ProblemData& d, double xscale) {
  std::vector<GlobalId> nodes(static_cast<std::size_t>(d.num_nodes));
  std::iota(nodes.begin(), nodes.end(), GlobalId{0});
  const LocalObjectives obj(d, nodes);
  const int q = d.dim;
  const double h = 1e-5;
  std::vector<double> x(q), xp(q), xm(q), g(q), gp(q), gm(q), H(q * q);
  for (LocalId v = 0; v < static_cast<LocalId>(obj.size()); v += 3) {
    for (int k = 0; k < q; ++k) x[k] = xscale * std::sin(1.0 + v + 2.3 * k);
    obj.gradient(v, x.data(), g.data());
    obj.hessian(v, x.data(), H.data());
    for (int k = 0; k < q; ++k) {
      xp = x, xm = x;
      xp[k] += h, xm[k] -= h;
      const double fd = (obj.value(v, xp.data()) - obj.value(v, xm.data())) / (2 * h);
      EXPECT_NEAR(g[k], fd, 1e-6 * (1 + std::abs(fd))) << "node " << v << " coordinate " << k;
      obj.gradient(v, xp.data(), gp.data());
      obj.gradient(v, xm.data(), gm.data());
      for (int i = 0; i < q; ++i) {
        const double fdh = (gp[i] - gm[i]) / (2 * h);
        EXPECT_NEAR(H[i * q + k], fdh, 1e-6 * (1 + std::abs(fdh))) << "node " << v << " entry " << i << "," << k;
      }
    }
    for (int i = 0; i < q; ++i) {
      EXPECT_GT(H[i * q + i], 0) << "Hessian diagonal must be positive";
      for (int k = 0; k < q; ++k) EXPECT_EQ(H[i * q + k], H[k * q + i]) << "Hessian must be symmetric";
    }
  }
}

TEST(ConsensusObjectives, ExpMatchesFiniteDifferences) { check_derivatives(generate_problem(small(Family::kExp)), 1.5); }

TEST(ConsensusObjectives, QuadraticMatchesFiniteDifferences) {
  check_derivatives(generate_problem(small(Family::kQuadratic, 3)), 2.0);
}

TEST(ConsensusObjectives, LogisticMatchesFiniteDifferences) {
  check_derivatives(generate_problem(small(Family::kLogistic, 3)), 1.0);
}

TEST(ConsensusObjectives, LeastSquaresMatchesFiniteDifferences) {
  check_derivatives(generate_problem(small(Family::kLeastSquares, 3)), 1.0);
}

TEST(ConsensusObjectives, ValuesFollowTheFormulas) {
  ProblemData d = generate_problem(small(Family::kExp, 1, 4));
  const LocalObjectives e(d, {2});
  const double x = 0.3;
  EXPECT_DOUBLE_EQ(e.value(0, &x), d.exp_a[2] * std::exp(d.exp_b[2] * x) + d.exp_c[2] * std::exp(-d.exp_d[2] * x));

  d = generate_problem(small(Family::kQuadratic, 2, 4));
  const LocalObjectives qd(d, {3, 1});
  const double y[2] = {0.5, -0.25};
  double want = 0;
  for (int k = 0; k < 2; ++k) want += 0.5 * d.quad_h[2 + k] * (y[k] - d.quad_r[2 + k]) * (y[k] - d.quad_r[2 + k]);
  EXPECT_DOUBLE_EQ(qd.value(1, y), want);

  // Logistic: node 1's samples found wherever they lie in the file.
  d = generate_problem(small(Family::kLogistic, 2, 4));
  std::reverse(d.owner.begin(), d.owner.end());
  const LocalObjectives lg(d, {1});
  want = 0.5 * d.lambda / 4.0 * (y[0] * y[0] + y[1] * y[1]);
  for (std::size_t s = 0; s < d.owner.size(); ++s)
    if (d.owner[s] == 1)
      want += std::log(1 + std::exp(-d.labels[s] * (d.features[2 * s] * y[0] + d.features[2 * s + 1] * y[1])));
  EXPECT_NEAR(lg.value(0, y), want, 1e-12 * std::abs(want));

  // Least squares: sum over node 1's samples of (a.x - b)^2 + lambda/2n x.x, and its gradient.
  d = generate_problem(small(Family::kLeastSquares, 2, 4));
  std::reverse(d.owner.begin(), d.owner.end());
  const LocalObjectives ls(d, {1});
  want = 0.5 * d.lambda / 4.0 * (y[0] * y[0] + y[1] * y[1]);
  double gwant[2] = {d.lambda / 4.0 * y[0], d.lambda / 4.0 * y[1]};
  for (std::size_t s = 0; s < d.owner.size(); ++s)
    if (d.owner[s] == 1) {
      const double r = d.features[2 * s] * y[0] + d.features[2 * s + 1] * y[1] - d.labels[s];
      want += r * r;
      for (int k = 0; k < 2; ++k) gwant[k] += 2 * r * d.features[2 * s + k];
    }
  EXPECT_NEAR(ls.value(0, y), want, 1e-12 * std::abs(want));
  double g[2];
  ls.gradient(0, y, g);
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(g[k], gwant[k], 1e-12 * (1 + std::abs(gwant[k])));
}

TEST(ConsensusObjectives, LogisticIsStableForLargeMargins) {
  ProblemData d = generate_problem(small(Family::kLogistic, 1, 4));
  const LocalObjectives obj(d, {0});
  for (double x : {-1e4, 1e4}) {
    double g = 0, h = 0;
    const double f = obj.value(0, &x);
    obj.gradient(0, &x, &g);
    obj.hessian(0, &x, &h);
    EXPECT_TRUE(std::isfinite(f) && std::isfinite(g) && std::isfinite(h)) << "x = " << x;
    EXPECT_GT(h, 0);
  }
}

// ---------------------------------------------------------------------------
// Round trip.

void expect_same(const ProblemData& a, const ProblemData& b) {
  EXPECT_EQ(a.num_nodes, b.num_nodes);
  EXPECT_EQ(a.dim, b.dim);
  EXPECT_EQ(a.family, b.family);
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(a.truth_path, b.truth_path);
  EXPECT_EQ(a.exp_a, b.exp_a);
  EXPECT_EQ(a.exp_b, b.exp_b);
  EXPECT_EQ(a.exp_c, b.exp_c);
  EXPECT_EQ(a.exp_d, b.exp_d);
  EXPECT_EQ(a.quad_h, b.quad_h);
  EXPECT_EQ(a.quad_r, b.quad_r);
  EXPECT_EQ(a.features, b.features);
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.owner, b.owner);
  EXPECT_EQ(a.lambda, b.lambda);
}

TEST(ConsensusFile, RoundTripEveryFamily) {
  for (Family f : {Family::kExp, Family::kQuadratic, Family::kLogistic, Family::kLeastSquares}) {
    GenerateOptions o = small(f, f == Family::kExp ? 1 : 3);
    o.hamiltonian = f != Family::kQuadratic;
    const ProblemData d = generate_problem(o);
    const std::string path = scratch(std::string("rt_") + family_name(f) + ".h5");
    write_problem(MPI_COMM_SELF, path, d);
    expect_same(d, read_problem(MPI_COMM_SELF, path));
  }
}

TEST(ConsensusFile, FamilyNames) {
  for (Family f : {Family::kExp, Family::kQuadratic, Family::kLogistic, Family::kLeastSquares})
    EXPECT_EQ(parse_family(family_name(f)), f);
  EXPECT_NE(error_of([] { parse_family("cubic"); }).find("cubic"), std::string::npos);
}

// ---------------------------------------------------------------------------
// Validation in memory: one test per rule; each message names the dataset.

ProblemData good(Family f = Family::kExp, int dim = 1) {
  GenerateOptions o = small(f, dim, 12);
  o.hamiltonian = true;
  return generate_problem(o);
}

void expect_refused(const ProblemData& d, const std::string& name, const std::string& what = "") {
  const std::string m = validation_error(d);
  EXPECT_NE(m.find("'" + name + "'"), std::string::npos) << "message does not name '" << name << "': " << m;
  if (!what.empty()) EXPECT_NE(m.find(what), std::string::npos) << "message lacks '" << what << "': " << m;
}

TEST(ConsensusValidate, GeneratedProblemsAreValid) {
  for (Family f : {Family::kExp, Family::kQuadratic, Family::kLogistic, Family::kLeastSquares})
    EXPECT_EQ(validation_error(good(f, f == Family::kExp ? 1 : 2)), "");
}

TEST(ConsensusValidate, TooFewNodes) {
  ProblemData d = good();
  d.num_nodes = 1;
  expect_refused(d, "num_nodes");
}

TEST(ConsensusValidate, BadDim) {
  ProblemData d = good(Family::kQuadratic, 2);
  d.dim = 0;
  expect_refused(d, "dim");
  d = good();
  d.dim = 2;  // exp is scalar
  expect_refused(d, "dim", "exp");
}

TEST(ConsensusValidate, EdgeNodeOutOfRange) {
  ProblemData d = good();
  d.edges[2 * 3 + 1] = 12;
  expect_refused(d, "edges", "row 3");
  d = good();
  d.edges[2 * 4] = -1;
  expect_refused(d, "edges", "row 4");
}

TEST(ConsensusValidate, SelfLoop) {
  ProblemData d = good();
  d.edges[2 * 5 + 1] = d.edges[2 * 5];
  expect_refused(d, "edges", "self-loop");
}

TEST(ConsensusValidate, DuplicateLinkEvenReversed) {
  ProblemData d = good();
  d.edges.push_back(d.edges[2 * 2 + 1]);
  d.edges.push_back(d.edges[2 * 2]);
  const GlobalId last = static_cast<GlobalId>(d.edges.size() / 2 - 1);
  expect_refused(d, "edges", "row " + std::to_string(last) + ": link");
  EXPECT_NE(validation_error(d).find("repeats row 2"), std::string::npos) << validation_error(d);
}

TEST(ConsensusValidate, FirstDuplicateInRowOrder) {
  ProblemData d = good();
  const std::vector<GlobalId> e0(d.edges.begin(), d.edges.begin() + 2), e1(d.edges.begin() + 2, d.edges.begin() + 4);
  d.edges.insert(d.edges.end(), e1.begin(), e1.end());  // row E: repeats row 1
  d.edges.insert(d.edges.end(), e0.begin(), e0.end());  // row E+1: repeats row 0
  const GlobalId E = static_cast<GlobalId>(d.edges.size() / 2 - 2);
  expect_refused(d, "edges", "row " + std::to_string(E) + ": link");
}

TEST(ConsensusValidate, ExpParametersPositiveAndFinite) {
  const char* names[] = {"exp_a", "exp_b", "exp_c", "exp_d"};
  for (int k = 0; k < 4; ++k) {
    ProblemData d = good();
    std::vector<double>* v[] = {&d.exp_a, &d.exp_b, &d.exp_c, &d.exp_d};
    (*v[k])[5] = 0.0;
    expect_refused(d, names[k], "row 5");
    (*v[k])[5] = -1.0;
    expect_refused(d, names[k], "row 5");
    (*v[k])[5] = std::nan("");
    expect_refused(d, names[k], "row 5");
    v[k]->pop_back();
    expect_refused(d, names[k], "num_nodes");
  }
}

TEST(ConsensusValidate, QuadraticCurvaturePositiveAndFinite) {
  ProblemData d = good(Family::kQuadratic, 2);
  d.quad_h[2 * 3 + 1] = 0.0;
  expect_refused(d, "quad_h", "row 3");
  d.quad_h[2 * 3 + 1] = INFINITY;
  expect_refused(d, "quad_h", "row 3");
  d = good(Family::kQuadratic, 2);
  d.quad_r[2 * 7] = -INFINITY;
  expect_refused(d, "quad_r", "row 7");
  d = good(Family::kQuadratic, 2);
  d.quad_r.resize(d.quad_r.size() - 2);
  expect_refused(d, "quad_r");
}

TEST(ConsensusValidate, LogisticLabelsOwnersFeaturesLambda) {
  ProblemData d = good(Family::kLogistic, 2);
  d.labels[4] = 0.5;
  expect_refused(d, "labels", "row 4");
  d.labels[4] = 0.0;
  expect_refused(d, "labels", "row 4");
  d = good(Family::kLogistic, 2);
  d.owner[9] = 12;
  expect_refused(d, "owner", "row 9");
  d.owner[9] = -1;
  expect_refused(d, "owner", "row 9");
  d = good(Family::kLogistic, 2);
  d.features[2 * 6 + 1] = std::nan("");
  expect_refused(d, "features", "row 6");
  d = good(Family::kLogistic, 2);
  d.features.pop_back();
  expect_refused(d, "features");
  d = good(Family::kLogistic, 2);
  d.owner.pop_back();
  expect_refused(d, "owner");
  for (double lambda : {0.0, -1.0, double(NAN), double(INFINITY)}) {
    d = good(Family::kLogistic, 2);
    d.lambda = lambda;
    expect_refused(d, "lambda");
  }
}

TEST(ConsensusValidate, LeastSquaresTargetsOwnersFeaturesLambda) {
  ProblemData d = good(Family::kLeastSquares, 2);
  d.labels[4] = 0.5;  // any finite target is fine
  d.labels[5] = -1e3;
  EXPECT_EQ(validation_error(d), "");
  for (double bad : {double(NAN), double(INFINITY)}) {
    d.labels[4] = bad;
    expect_refused(d, "labels", "row 4");
  }
  d = good(Family::kLeastSquares, 2);
  d.owner[9] = 12;
  expect_refused(d, "owner", "row 9");
  d = good(Family::kLeastSquares, 2);
  d.features[2 * 6 + 1] = std::nan("");
  expect_refused(d, "features", "row 6");
  for (double lambda : {0.0, -1.0, double(NAN), double(INFINITY)}) {
    d = good(Family::kLeastSquares, 2);
    d.lambda = lambda;
    expect_refused(d, "lambda");
  }
  d = good(Family::kLeastSquares, 2);
  d.labels[3] = 1e200;  // finite, but (a.x - b)^2 at x = 0 overflows
  EXPECT_NE(validation_error(d).find("overflows"), std::string::npos) << validation_error(d);
  d = good(Family::kLeastSquares, 2);
  d.quad_h.assign(24, 1.0);
  expect_refused(d, "quad_h", "family");
}

TEST(ConsensusValidate, DataOfAnotherFamily) {
  ProblemData d = good();
  d.quad_h.assign(12, 1.0);
  expect_refused(d, "quad_h", "family");
}

TEST(ConsensusValidate, TruthPathNotAPermutation) {
  ProblemData d = good();
  d.truth_path[6] = d.truth_path[2];
  expect_refused(d, "truth_path", "row 6");
  d = good();
  d.truth_path[3] = 99;
  expect_refused(d, "truth_path", "row 3");
  d = good();
  d.truth_path.pop_back();
  expect_refused(d, "truth_path");
}

TEST(ConsensusValidate, TruthPathNotAPathOfTheGraph) {
  ProblemData d = good();
  // Remove the link between path positions 4 and 5 (the rest stays connected
  // through the geometric links or not: either way the path rule fires first).
  const GlobalId u = std::min(d.truth_path[4], d.truth_path[5]), v = std::max(d.truth_path[4], d.truth_path[5]);
  for (std::size_t e = 0; e < d.edges.size(); e += 2)
    if (d.edges[e] == u && d.edges[e + 1] == v) d.edges.erase(d.edges.begin() + e, d.edges.begin() + e + 2);
  expect_refused(d, "truth_path", "row 5");
}

TEST(ConsensusValidate, TooFewLinksForAConnectedGraph) {
  ProblemData d = good(Family::kLogistic, 2);
  d.truth_path.clear();
  d.num_nodes = 2000000000;  // logistic ties no dataset to n: refused before anything is sized by n
  d.owner.assign(d.owner.size(), 0);
  expect_refused(d, "edges", "at least 1999999999 links");
}

TEST(ConsensusValidate, DisconnectedGraph) {
  ProblemData d = good();
  d.truth_path.clear();
  // Cut node 11 off: drop every link that touches it.
  std::vector<GlobalId> kept;
  for (std::size_t e = 0; e < d.edges.size(); e += 2)
    if (d.edges[e] != 11 && d.edges[e + 1] != 11) kept.insert(kept.end(), {d.edges[e], d.edges[e + 1]});
  d.edges = kept;
  expect_refused(d, "edges", "not connected");
  EXPECT_NE(validation_error(d).find("node 11"), std::string::npos) << validation_error(d);
}

// ---------------------------------------------------------------------------
// Validation of files: attributes, types and shapes (messages name them and the file).

/// Writes `d` as write_problem does, then lets `tamper` change the root
/// attributes and datasets before commit (`skip` leaves the named ones out).
void write_tampered(const std::string& path, const ProblemData& d,
                    const std::function<void(H5File&)>& tamper, const std::vector<std::string>& skip = {}) {
  const auto wanted = [&](const std::string& n) { return std::find(skip.begin(), skip.end(), n) == skip.end(); };
  H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
  for (const char* a : {"format", "version", "num_nodes", "dim", "family", "lambda"}) {
    if (!wanted(a)) continue;
    const std::string n = a;
    if (n == "format") f.set_attr(n, std::string("snl-consensus"));
    if (n == "version") f.set_attr(n, std::int64_t{1});
    if (n == "num_nodes") f.set_attr(n, std::int64_t{d.num_nodes});
    if (n == "dim") f.set_attr(n, std::int64_t{d.dim});
    if (n == "family") f.set_attr(n, std::string(family_name(d.family)));
    if (n == "lambda" && d.family == Family::kLogistic) f.set_attr(n, d.lambda);
  }
  const std::uint64_t E = d.edges.size() / 2, n = static_cast<std::uint64_t>(d.num_nodes);
  if (wanted("edges")) f.write_rows("edges", E, 2, 0, d.edges.data(), E);
  if (wanted("truth_path") && !d.truth_path.empty()) f.write_rows("truth_path", n, 0, 0, d.truth_path.data(), n);
  const std::pair<const char*, const std::vector<double>*> exp[] = {
      {"exp_a", &d.exp_a}, {"exp_b", &d.exp_b}, {"exp_c", &d.exp_c}, {"exp_d", &d.exp_d}};
  for (const auto& [name, v] : exp)
    if (wanted(name) && !v->empty()) f.write_rows(name, v->size(), 0, 0, v->data(), v->size());
  tamper(f);
  f.commit();
}

std::string read_error(const std::string& path) {
  return error_of([&] { read_problem(MPI_COMM_SELF, path); });
}

void expect_file_refused(const std::string& tag, const std::function<void(H5File&)>& tamper,
                         const std::vector<std::string>& skip, const std::string& name) {
  const std::string path = scratch("bad_" + tag + ".h5");
  write_tampered(path, good(), tamper, skip);
  const std::string m = read_error(path);
  EXPECT_NE(m.find(path), std::string::npos) << tag << ": message does not name the file: " << m;
  EXPECT_NE(m.find("'" + name + "'"), std::string::npos) << tag << ": message does not name '" << name << "': " << m;
}

TEST(ConsensusFileValidate, TamperedWriterProducesAValidFileUntouched) {
  const std::string path = scratch("untampered.h5");
  write_tampered(path, good(), [](H5File&) {});
  EXPECT_EQ(read_error(path), "");
}

TEST(ConsensusFileValidate, RootAttributes) {
  for (const char* a : {"format", "version", "num_nodes", "dim", "family"})
    expect_file_refused(std::string("missing_") + a, [](H5File&) {}, {a}, a);
  expect_file_refused("format_value", [](H5File& f) { f.set_attr("format", std::string("snl-network")); }, {"format"},
                      "format");
  expect_file_refused("format_type", [](H5File& f) { f.set_attr("format", std::int64_t{1}); }, {"format"}, "format");
  expect_file_refused("version_value", [](H5File& f) { f.set_attr("version", std::int64_t{2}); }, {"version"},
                      "version");
  expect_file_refused("num_nodes_type", [](H5File& f) { f.set_attr("num_nodes", std::string("12")); }, {"num_nodes"},
                      "num_nodes");
  expect_file_refused("num_nodes_value", [](H5File& f) { f.set_attr("num_nodes", std::int64_t{1}); }, {"num_nodes"},
                      "num_nodes");
  expect_file_refused("dim_fraction", [](H5File& f) { f.set_attr("dim", 1.5); }, {"dim"}, "dim");
  expect_file_refused("dim_exp", [](H5File& f) { f.set_attr("dim", std::int64_t{2}); }, {"dim"}, "dim");
  expect_file_refused("family_value", [](H5File& f) { f.set_attr("family", std::string("cubic")); }, {"family"},
                      "family");
  expect_file_refused("family_type", [](H5File& f) { f.set_attr("family", 1.0); }, {"family"}, "family");
}

TEST(ConsensusFileValidate, DatasetsAndShapes) {
  expect_file_refused("missing_edges", [](H5File&) {}, {"edges"}, "edges");
  expect_file_refused("missing_exp_c", [](H5File&) {}, {"exp_c"}, "exp_c");
  expect_file_refused(
      "edges_shape", [](H5File& f) {
        const std::vector<std::int64_t> e = {0, 1, 2, 1, 2, 3};
        f.write_rows("edges", 2, 3, 0, e.data(), 2);
      },
      {"edges"}, "edges");
  expect_file_refused(
      "edges_float", [](H5File& f) {
        const std::vector<double> e = {0, 1, 1, 2};
        f.write_rows("edges", 2, 2, 0, e.data(), 2);
      },
      {"edges"}, "edges");
  expect_file_refused(
      "exp_b_shape", [](H5File& f) {
        const std::vector<double> v(11, 1.0);
        f.write_rows("exp_b", 11, 0, 0, v.data(), 11);
      },
      {"exp_b"}, "exp_b");
  expect_file_refused(
      "truth_path_shape", [](H5File& f) {
        const std::vector<std::int64_t> v = {0, 1, 2};
        f.write_rows("truth_path", 3, 0, 0, v.data(), 3);
      },
      {"truth_path"}, "truth_path");
  expect_file_refused(
      "foreign", [](H5File& f) {
        const std::vector<double> v(12, 1.0);
        f.write_rows("quad_h", 12, 1, 0, v.data(), 12);
      },
      {}, "quad_h");
}

TEST(ConsensusFileValidate, ContentRulesNameTheFileAndRow) {
  ProblemData d = good();
  d.exp_d[8] = -0.5;
  const std::string path = scratch("bad_content.h5");
  write_problem(MPI_COMM_SELF, path, d);
  const std::string m = read_error(path);
  EXPECT_NE(m.find(path + ": dataset 'exp_d' row 8"), std::string::npos) << m;
}

TEST(ConsensusFileValidate, LogisticNeedsLambdaAndConsistentShapes) {
  const ProblemData d = good(Family::kLogistic, 2);
  const std::string path = scratch("logistic_shapes.h5");
  const auto logistic_file = [&](bool with_lambda, std::uint64_t owner_rows) {
    H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
    f.set_attr("format", std::string("snl-consensus"));
    f.set_attr("version", std::int64_t{1});
    f.set_attr("num_nodes", std::int64_t{d.num_nodes});
    f.set_attr("dim", std::int64_t{2});
    f.set_attr("family", std::string("logistic"));
    if (with_lambda) f.set_attr("lambda", d.lambda);
    const std::uint64_t E = d.edges.size() / 2, S = d.labels.size();
    f.write_rows("edges", E, 2, 0, d.edges.data(), E);
    f.write_rows("features", S, 2, 0, d.features.data(), S);
    f.write_rows("labels", S, 0, 0, d.labels.data(), S);
    f.write_rows("owner", owner_rows, 0, 0, d.owner.data(), owner_rows);
    f.commit();
  };
  logistic_file(false, d.labels.size());
  EXPECT_NE(read_error(path).find("'lambda'"), std::string::npos) << read_error(path);
  logistic_file(true, d.labels.size() - 1);
  EXPECT_NE(read_error(path).find("'owner'"), std::string::npos) << read_error(path);
  logistic_file(true, d.labels.size());
  EXPECT_EQ(read_error(path), "");
}

TEST(ConsensusFile, MissingFileIsAnError) {
  EXPECT_NE(read_error(scratch("does_not_exist.h5")), "");
}

// ---------------------------------------------------------------------------
// Generator.

TEST(ConsensusGenerate, DeterministicInTheSeed) {
  GenerateOptions o = small(Family::kLogistic, 2, 300);
  o.hamiltonian = true;
  const ProblemData a = generate_problem(o), b = generate_problem(o);
  expect_same(a, b);
  o.seed = 8;
  const ProblemData c = generate_problem(o);
  EXPECT_NE(a.edges, c.edges);
  EXPECT_NE(a.features, c.features);
}

TEST(ConsensusGenerate, ConnectedSortedAndNearTheTargetDegree) {
  for (double deg : {4.0, 6.0, 10.0}) {
    GenerateOptions o = small(Family::kExp, 1, 20000);
    o.avg_degree = deg;
    GenerateReport rep;
    const ProblemData d = generate_problem(o, &rep);
    EXPECT_EQ(validation_error(d), "") << "degree " << deg;  // includes connectivity
    // The geometric links alone are near the target; joining adds components - 1.
    const double geo = 2.0 * static_cast<double>(rep.geometric_links) / static_cast<double>(d.num_nodes);
    EXPECT_NEAR(geo, deg, 0.02 * deg) << "average degree of the geometric links";
    EXPECT_LT(rep.connect_links, d.num_nodes / 10);
    EXPECT_EQ(rep.geometric_links + rep.connect_links, static_cast<GlobalId>(d.edges.size() / 2));
    EXPECT_EQ(rep.connect_links, rep.components - 1);
    for (std::size_t e = 0; e < d.edges.size(); e += 2) {
      ASSERT_LT(d.edges[e], d.edges[e + 1]);
      if (e) ASSERT_LT(std::make_pair(d.edges[e - 2], d.edges[e - 1]), std::make_pair(d.edges[e], d.edges[e + 1]));
    }
  }
}

TEST(ConsensusGenerate, SparseGraphsAreJoined) {
  for (double deg : {0.0, 0.5, 2.0}) {
    GenerateOptions o = small(Family::kQuadratic, 2, 500);
    o.avg_degree = deg;
    GenerateReport rep;
    const ProblemData d = generate_problem(o, &rep);
    EXPECT_EQ(validation_error(d), "") << "degree " << deg;
    EXPECT_GT(rep.components, 1);
    EXPECT_EQ(rep.connect_links, rep.components - 1);
  }
}

TEST(ConsensusGenerate, DenseRequestGivesTheCompleteGraph) {
  GenerateOptions o = small(Family::kExp, 1, 6);
  o.avg_degree = 5;
  EXPECT_EQ(generate_problem(o).edges.size() / 2, 15u);
}

TEST(ConsensusGenerate, PlantedHamiltonPath) {
  GenerateOptions o = small(Family::kExp, 1, 2000);
  o.hamiltonian = true;
  GenerateReport rep;
  const ProblemData d = generate_problem(o, &rep);
  ASSERT_EQ(d.truth_path.size(), 2000u);
  EXPECT_EQ(validation_error(d), "");  // permutation whose consecutive pairs are links
  EXPECT_EQ(rep.components, 1);
  EXPECT_GT(rep.path_links, 1500);  // a random permutation's pairs are rarely geometric links
  std::vector<GlobalId> sorted = d.truth_path;
  std::sort(sorted.begin(), sorted.end());
  for (GlobalId k = 0; k < 2000; ++k) ASSERT_EQ(sorted[k], k);
}

TEST(ConsensusGenerate, FamilyParametersInTheirDocumentedRanges) {
  const ProblemData e = generate_problem(small(Family::kExp, 1, 500));
  for (const auto* v : {&e.exp_a, &e.exp_b, &e.exp_c, &e.exp_d}) {
    EXPECT_GE(*std::min_element(v->begin(), v->end()), 0.5);
    EXPECT_LE(*std::max_element(v->begin(), v->end()), 1.5);
  }
  const ProblemData q = generate_problem(small(Family::kQuadratic, 3, 500));
  EXPECT_GE(*std::min_element(q.quad_h.begin(), q.quad_h.end()), 0.5);
  EXPECT_LE(*std::max_element(q.quad_h.begin(), q.quad_h.end()), 2.0);
  EXPECT_GE(*std::min_element(q.quad_r.begin(), q.quad_r.end()), -1.0);
  EXPECT_LE(*std::max_element(q.quad_r.begin(), q.quad_r.end()), 1.0);
  const ProblemData l = generate_problem(small(Family::kLogistic, 3, 50));
  EXPECT_EQ(l.num_samples(), 250);
  for (std::int64_t s = 0; s < l.num_samples(); ++s) ASSERT_EQ(l.owner[s], s / 5);
  const double pos = static_cast<double>(std::count(l.labels.begin(), l.labels.end(), 1.0));
  EXPECT_GT(pos, 25.0);
  EXPECT_LT(pos, 225.0);
  // Least squares: the same ownership; targets a.x_true + small noise, so not labels of +-1.
  const ProblemData ls = generate_problem(small(Family::kLeastSquares, 3, 50));
  EXPECT_EQ(ls.num_samples(), 250);
  for (std::int64_t s = 0; s < ls.num_samples(); ++s) ASSERT_EQ(ls.owner[s], s / 5);
  EXPECT_LT(std::count(ls.labels.begin(), ls.labels.end(), 1.0) + std::count(ls.labels.begin(), ls.labels.end(), -1.0),
            5);
}

TEST(ConsensusGenerate, OptionsAreChecked) {
  const auto refused = [](const std::function<void(GenerateOptions&)>& change, const std::string& option) {
    GenerateOptions o;
    change(o);
    const std::string m = error_of([&] { o.validate(); });
    EXPECT_NE(m.find(option), std::string::npos) << "'" << m << "' does not name " << option;
  };
  refused([](GenerateOptions& o) { o.nodes = 1; }, "--nodes");
  refused([](GenerateOptions& o) { o.avg_degree = -1; }, "--avg-degree");
  refused([](GenerateOptions& o) { o.avg_degree = 100; }, "--avg-degree");
  refused([](GenerateOptions& o) { o.dim = 2; }, "--dim");
  refused([](GenerateOptions& o) { o.family = Family::kQuadratic, o.dim = 0; }, "--dim");
  refused([](GenerateOptions& o) { o.family = Family::kLogistic, o.lambda = 0; }, "--lambda");
  refused([](GenerateOptions& o) { o.family = Family::kLogistic, o.samples_per_node = -1; }, "--samples-per-node");
  refused([](GenerateOptions& o) { o.family = Family::kLeastSquares, o.lambda = 0; }, "--lambda");
  refused([](GenerateOptions& o) { o.family = Family::kLeastSquares, o.samples_per_node = -1; }, "--samples-per-node");
  EXPECT_EQ(error_of([] { GenerateOptions().validate(); }), "");
}

}  // namespace
