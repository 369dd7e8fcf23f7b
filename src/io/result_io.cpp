// Result files (shared spec: network-format.md, "snl-result" v1) and --init
// position files.
#include "snl/io/result_io.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "snl/io/h5file.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl {

namespace {
const char* const kStandardAttrs[] = {"format", "version", "algorithm", "iterations", "converged", "dim", "num_sensors"};
bool is_standard(const std::string& name) {
  return std::find(std::begin(kStandardAttrs), std::end(kStandardAttrs), name) != std::end(kStandardAttrs);
}
}  // namespace

void write_result(const std::string& path, MPI_Comm comm, const ResultFile& r) {
  // Local argument checks first, agreed, so no rank enters HDF5 with bad input.
  std::string err;
  const int p = r.dim;
  if (p < 1) err = "cannot write " + path + ": dim must be positive";
  else if (r.positions.size() % static_cast<std::size_t>(p) != 0)
    err = "cannot write " + path + ": positions size is not a multiple of dim";
  else if (r.row_offset < 0)
    err = "cannot write " + path + ": negative row offset";
  for (const auto& h : r.history)
    if (h.first.empty() || h.first.find('/') != std::string::npos)
      err = "cannot write " + path + ": bad history series name '" + h.first + "'";
  if (!r.history.empty())
    for (const auto& h : r.history)
      if (h.second.size() != r.history.front().second.size())
        err = "cannot write " + path + ": history series '" + h.first + "' has another length than '" +
              r.history.front().first + "'";
  for (const auto& a : r.double_attrs)
    if (is_standard(a.first)) err = "cannot write " + path + ": attribute '" + a.first + "' is reserved";
  for (const auto& a : r.string_attrs)
    if (is_standard(a.first)) err = "cannot write " + path + ": attribute '" + a.first + "' is reserved";
  agree(comm, err);
  const GlobalId rows = p > 0 ? static_cast<GlobalId>(r.positions.size()) / p : 0;
  long long total = rows;
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_LONG_LONG, MPI_SUM, comm);
  if (total != r.num_sensors)
    throw Error("cannot write " + path + ": the ranks hold " + std::to_string(total) + " position rows, expected " +
                std::to_string(r.num_sensors));

  H5File f(path, comm, H5File::Mode::kCreate);
  f.set_attr("format", std::string("snl-result"));
  f.set_attr("version", std::int64_t{1});
  f.set_attr("algorithm", r.algorithm);
  f.set_attr("iterations", std::int64_t{r.iterations});
  f.set_attr("converged", std::int64_t{r.converged ? 1 : 0});
  f.set_attr("dim", std::int64_t{p});
  f.set_attr("num_sensors", std::int64_t{r.num_sensors});
  for (const auto& a : r.double_attrs) f.set_attr(a.first, a.second);
  for (const auto& a : r.string_attrs) f.set_attr(a.first, a.second);
  f.write_rows("positions", static_cast<std::uint64_t>(r.num_sensors), static_cast<std::uint64_t>(p),
               static_cast<std::uint64_t>(r.row_offset), r.positions.data(), static_cast<std::uint64_t>(rows));
  for (const auto& h : r.history) f.write_replicated("history/" + h.first, h.second);
  f.commit();
}

ResultFile read_result_serial(const std::string& path) {
  H5File f(path, MPI_COMM_SELF, H5File::Mode::kRead);
  if (!f.has_attr("format") || f.attr_string("format") != "snl-result")
    throw Error(path + ": not an snl result file (attribute 'format' is not 'snl-result')");
  const std::int64_t version = f.attr_int("version");
  if (version != 1)
    throw Error(path + ": unsupported result format version " + std::to_string(version) + " (this snl reads version 1)");
  ResultFile r;
  r.algorithm = f.attr_string("algorithm");
  r.iterations = f.attr_int("iterations");
  r.converged = f.attr_int("converged") != 0;
  r.dim = static_cast<int>(f.attr_int("dim"));
  r.num_sensors = f.attr_int("num_sensors");
  r.positions = read_positions(path, MPI_COMM_SELF, r.num_sensors, r.dim, 0, r.num_sensors);
  for (const auto& name : f.list("history"))
    r.history.emplace_back(name, f.read_rows_double("history/" + name, 0, f.shape("history/" + name).at(0)));
  for (const auto& name : f.attr_names(".")) {
    if (is_standard(name)) continue;
    if (f.attr_is_string(name))
      r.string_attrs.emplace_back(name, f.attr_string(name));
    else
      r.double_attrs.emplace_back(name, f.attr_double(name));
  }
  return r;
}

std::vector<double> read_positions(const std::string& path, MPI_Comm comm, GlobalId expected_n, int expected_dim,
                                   GlobalId row_offset, GlobalId rows) {
  H5File f(path, comm, H5File::Mode::kRead);
  if (!f.has_dataset("positions")) throw Error(path + ": dataset 'positions' not found");
  const auto s = f.shape("positions");
  if (s.size() != 2 || s[0] != static_cast<std::uint64_t>(expected_n) || s[1] != static_cast<std::uint64_t>(expected_dim)) {
    std::string t = "[";
    for (std::size_t k = 0; k < s.size(); ++k) t += (k ? ", " : "") + std::to_string(s[k]);
    throw Error(path + ": dataset 'positions' has shape " + t + "], expected [" + std::to_string(expected_n) + ", " +
                std::to_string(expected_dim) + "]");
  }
  std::string err;
  if (row_offset < 0 || rows < 0 || row_offset + rows > expected_n)
    err = path + ": rows [" + std::to_string(row_offset) + ", " + std::to_string(row_offset + rows) +
          ") of 'positions' requested outside [0, " + std::to_string(expected_n) + ")";
  agree(comm, err);
  std::vector<double> pos = f.read_rows_double("positions", static_cast<std::uint64_t>(row_offset),
                                               static_cast<std::uint64_t>(rows));
  f.commit();
  GlobalId bad = -1;
  for (std::size_t k = 0; k < pos.size(); ++k)
    if (!std::isfinite(pos[k])) {
      bad = row_offset + static_cast<GlobalId>(k) / expected_dim;
      err = path + ": positions row " + std::to_string(bad) + " is not finite";
      break;
    }
  agree_first(comm, bad, err);
  return pos;
}

}  // namespace snl
