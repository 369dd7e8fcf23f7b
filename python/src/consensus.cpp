// snl.consensus's binding: problems from arrays, files or the generator, and
// consensus::solve, the library call `snl consensus solve` makes (so x is the
// CLI's, bit for bit). The pure-Python part is python/snl/consensus.py.
#include <pybind11/stl.h>

#include <cmath>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "binding_util.hpp"
#include "snl/consensus/problem.hpp"
#include "snl/consensus/solver.hpp"

namespace snl_py {

namespace {

namespace sc = snl::consensus;
using snl::GlobalId;

struct PyProblem {
  sc::ProblemData data;
};

// The problem on every rank of comm: each rank's own, or rank 0's broadcast
// where some rank passed None ("given whole on rank 0").
void bcast_problem(MPI_Comm comm, sc::ProblemData& d) {
  std::int64_t head[3] = {d.num_nodes, d.dim, static_cast<std::int64_t>(d.family)};
  snl::bcast_bytes(comm, head, sizeof head);
  snl::bcast_bytes(comm, &d.lambda, sizeof d.lambda);
  d.num_nodes = head[0];
  d.dim = static_cast<int>(head[1]);
  d.family = static_cast<sc::Family>(head[2]);
  bcast_vec(comm, d.edges);
  bcast_vec(comm, d.truth_path);
  for (auto* v : {&d.exp_a, &d.exp_b, &d.exp_c, &d.exp_d, &d.quad_h, &d.quad_r, &d.features, &d.labels})
    bcast_vec(comm, *v);
  bcast_vec(comm, d.owner);
}

const sc::ProblemData& whole_problem(const PyProblem* given, MPI_Comm comm, sc::ProblemData& received) {
  const bool root = snl::comm_rank(comm) == 0;
  std::string err = root && !given ? "the problem must be given on rank 0" : "";
  snl::agree(comm, err);
  if (snl::all_ranks(comm, given != nullptr)) return given->data;
  if (root) received = given->data;
  bcast_problem(comm, received);
  return received;
}

// A problem from arrays (shapes checked in consensus.py), validated as a file is.
PyProblem from_arrays(const std::string& family, GlobalId n, int dim, const py::object& edges,
                      const py::object& truth_path, const py::dict& a, double lambda) {
  PyProblem p;
  sc::ProblemData& d = p.data;
  d.family = sc::parse_family(family);
  d.num_nodes = n;
  d.dim = dim;
  d.edges = to_vec<std::int64_t>(edges);
  d.truth_path = to_vec<std::int64_t>(truth_path);
  auto get = [&](const char* k) { return a.contains(k) ? to_vec<double>(a[k]) : std::vector<double>{}; };
  d.exp_a = get("exp_a"), d.exp_b = get("exp_b"), d.exp_c = get("exp_c"), d.exp_d = get("exp_d");
  d.quad_h = get("quad_h"), d.quad_r = get("quad_r");
  d.features = get("features"), d.labels = get("labels");
  if (a.contains("owner")) d.owner = to_vec<std::int64_t>(a["owner"]);
  d.lambda = lambda;
  sc::validate_problem(d);  // snl::Error (ValueError) with the file reader's message
  return p;
}

sc::SolveOptions options_from(const py::dict& kw) {
  sc::SolveOptions o;
  for (const auto& item : kw) {
    const std::string k = py::str(item.first);
    const py::handle v = item.second;
    if (v.is_none()) continue;
    if (k == "method") o.method = py::str(v);
    else if (k == "dual") o.dual = std::string(py::str(v));
    else if (k == "max_iter") o.max_iter = v.cast<std::int64_t>();
    else if (k == "dual_max_iter") o.dual_max_iter = v.cast<std::int64_t>();
    else if (k == "tol") o.tol = v.cast<double>();
    else if (k == "oracle_tol") o.oracle_tol = v.cast<double>();
    else if (k == "dual_tol") o.dual_tol = v.cast<double>();
    else if (k == "step") {
      if (py::isinstance<py::str>(v))
        o.step_rule = std::string(py::str(v));
      else
        o.step = v.cast<double>();
    } else if (k == "damping") o.damping = v.cast<double>();
    else if (k == "partition") o.partition = py::str(v);
    else
      throw py::type_error("snl.consensus.solve: unknown option '" + k +
                           "' (method, dual, max_iter, dual_max_iter, tol, oracle_tol, dual_tol, step, damping, "
                           "partition)");
  }
  const std::string bad = o.validate();
  if (!bad.empty()) throw snl::Error(bad);
  return o;
}

// Per record: the progress callback on rank 0; Ctrl-C or a raising callback
// on any rank stops every rank at the same record (agreed by an allreduce,
// then thrown on all of them, where no collective is pending).
struct Interrupted {};
class Records {
 public:
  Records(MPI_Comm comm, py::object progress) : guard_(comm), progress_(std::move(progress)) {}
  ~Records() {
    py::gil_scoped_acquire gil;
    progress_ = py::object();
  }
  void operator()(const sc::HistoryRecord& r) {
    int mine;
    {
      py::gil_scoped_acquire gil;
      mine = guard_.poll([&] {
        if (progress_.is_none() || snl::comm_rank(guard_.comm()) != 0) return false;
        py::dict d;
        d["iteration"] = r.iteration;
        d["dual_iterations"] = r.dual_iterations;
        d["F"] = r.objective;
        d["max_abs_error"] = r.max_abs_error;
        d["decrement"] = r.decrement;
        d["messages_per_node"] = r.messages;
        d["elapsed"] = r.elapsed;
        progress_(d);
        return false;
      });
    }
    if (guard_.agree(mine) != PyGuard::kContinue) throw Interrupted{};
  }
  void raise() { guard_.raise_if_needed(); }  // GIL held

 private:
  PyGuard guard_;
  py::object progress_;
};

py::dict solve(const PyProblem* problem, const py::dict& kw, const py::object& comm_handle,
               const py::object& progress) {
  const MPI_Comm comm = to_comm(comm_handle);
  sc::SolveOptions opt;
  std::exception_ptr bad;
  try {
    opt = options_from(kw);
  } catch (...) {
    bad = std::current_exception();
  }
  if (snl::any_rank(comm, bad != nullptr)) {  // agreed before any other collective
    if (bad) std::rethrow_exception(bad);
    throw snl::Error("snl.consensus.solve: invalid options on another rank");
  }
  Records records(comm, progress);
  sc::SolveSummary s;
  std::vector<double> x;
  sc::ProblemData received;
  int q = 0;
  GlobalId n = 0;
  bool interrupted = false;
  {
    py::gil_scoped_release nogil;
    const sc::ProblemData& d = whole_problem(problem, comm, received);
    q = d.dim;
    n = d.num_nodes;
    try {
      s = sc::solve(comm, d, opt, {}, [&](const sc::HistoryRecord& r) { records(r); }, &x);
      bcast_vec(comm, x);  // x on rank 0 only: every rank gets it
    } catch (const Interrupted&) {
      interrupted = true;
    }
  }
  if (interrupted) records.raise();
  py::dict sum;
  sum["method"] = s.method;
  sum["dual"] = s.dual;
  sum["step_rule"] = s.step_rule;
  sum["iterations"] = s.iterations;
  sum["dual_iterations"] = s.dual_iterations;
  sum["line_search_trials"] = s.line_search_trials;
  sum["termination"] = s.termination;
  sum["message"] = s.message;
  sum["converged"] = s.converged;
  sum["max_abs_error"] = s.max_abs_error;
  sum["F"] = s.objective;
  sum["messages_per_node"] = s.messages_per_node;
  sum["reals_per_node"] = s.reals_per_node;
  sum["wall_seconds"] = s.wall_seconds;
  sum["ranks"] = s.ranks;
  sum["partition"] = s.partition;
  sum["tree_depth"] = s.tree_depth;
  sum["x_star"] = to_array(s.x_star, {static_cast<py::ssize_t>(s.x_star.size())});
  sum["x_star_converged"] = s.x_star_converged;
  py::dict hist;
  auto column = [&](const char* name, const std::vector<double>& v) {
    hist[name] = to_array(v, {static_cast<py::ssize_t>(v.size())});
  };
  for (const sc::HistoryColumn& c : sc::history_columns()) {
    std::vector<double> v;
    for (const auto& r : s.history) v.push_back(c.get(r));
    column(c.name, v);
  }
  std::vector<double> elapsed;
  for (const auto& r : s.history) elapsed.push_back(r.elapsed);
  column("elapsed", elapsed);
  py::dict out;
  out["x"] = to_array(x, {static_cast<py::ssize_t>(n), q});
  out["summary"] = sum;
  out["history"] = hist;
  return out;
}

PyProblem generate(GlobalId nodes, const std::string& family, int dim, double avg_degree, bool hamiltonian,
                   std::int64_t seed, std::int64_t samples_per_node, double lambda) {
  if (seed < 0) throw snl::Error("seed must be >= 0");
  sc::GenerateOptions o;
  o.nodes = nodes;
  o.family = sc::parse_family(family);
  o.dim = dim;
  o.avg_degree = avg_degree;
  o.hamiltonian = hamiltonian;
  o.seed = static_cast<std::uint64_t>(seed);
  o.samples_per_node = samples_per_node;
  o.lambda = lambda;
  o.validate();
  PyProblem p;
  py::gil_scoped_release nogil;
  p.data = sc::generate_problem(o);
  return p;
}

template <class T>
py::object opt_array(const std::vector<T>& v, py::ssize_t cols) {
  if (v.empty()) return py::none();
  if (cols <= 1) return to_array(v, {static_cast<py::ssize_t>(v.size())});
  return to_array(v, {static_cast<py::ssize_t>(v.size()) / cols, cols});
}

}  // namespace

void add_consensus(py::module_& m) {
  py::class_<PyProblem>(m, "_ConsensusProblem")
      .def_property_readonly("n_nodes", [](const PyProblem& p) { return p.data.num_nodes; })
      .def_property_readonly("dim", [](const PyProblem& p) { return p.data.dim; })
      .def_property_readonly("family", [](const PyProblem& p) { return std::string(sc::family_name(p.data.family)); })
      .def_property_readonly("lam", [](const PyProblem& p) { return p.data.lambda; })
      .def_property_readonly("edges", [](const PyProblem& p) { return opt_array(p.data.edges, 2); })
      .def_property_readonly("truth_path", [](const PyProblem& p) { return opt_array(p.data.truth_path, 1); })
      .def_property_readonly("features", [](const PyProblem& p) { return opt_array(p.data.features, p.data.dim); })
      .def_property_readonly("labels", [](const PyProblem& p) { return opt_array(p.data.labels, 1); })
      .def_property_readonly("owner", [](const PyProblem& p) { return opt_array(p.data.owner, 1); })
      .def_property_readonly("quad_h", [](const PyProblem& p) { return opt_array(p.data.quad_h, p.data.dim); })
      .def_property_readonly("quad_r", [](const PyProblem& p) { return opt_array(p.data.quad_r, p.data.dim); })
      .def_property_readonly("exp_abcd", [](const PyProblem& p) -> py::object {
        if (p.data.exp_a.empty()) return py::none();
        return py::make_tuple(opt_array(p.data.exp_a, 1), opt_array(p.data.exp_b, 1), opt_array(p.data.exp_c, 1),
                              opt_array(p.data.exp_d, 1));
      })
      .def("save", [](const PyProblem& p, const std::string& path, const py::object& comm) {
        const MPI_Comm c = to_comm(comm);
        py::gil_scoped_release nogil;
        sc::write_problem(c, path, p.data);
      }, py::arg("path"), py::arg("comm") = py::none());
  m.def("consensus_from_arrays", &from_arrays);
  m.def("consensus_read", [](const std::string& path, const py::object& comm) {
    const MPI_Comm c = to_comm(comm);
    PyProblem p;
    py::gil_scoped_release nogil;
    p.data = sc::read_problem(c, path);
    return p;
  });
  m.def("consensus_generate", &generate);
  m.def("consensus_solve", &solve);
}

}  // namespace snl_py
