// Per-sensor CRLB covariances added to an existing result file (group "crlb").
// The result file itself is written collectively by write_result; this edits a
// copy serially and renames it over the original, so a failure never leaves a
// half-written result file behind.
#include <hdf5.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "snl/io/h5file.hpp"
#include "snl/io/result_io.hpp"

namespace snl {

namespace {

// Closes an HDF5 id on scope exit.
struct Id {
  hid_t id = -1;
  herr_t (*close)(hid_t) = nullptr;
  Id(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
  ~Id() {
    if (id >= 0 && close) close(id);
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  operator hid_t() const { return id; }
  bool ok() const { return id >= 0; }
};

void check(bool ok, const std::string& what) {
  if (!ok) throw Error(what);
}

void write_dataset(hid_t group, const char* name, hid_t type, int rank, const hsize_t* dims, const void* data,
                   const std::string& where) {
  Id space(H5Screate_simple(rank, dims, nullptr), H5Sclose);
  check(space.ok(), where + ": cannot create a dataspace");
  Id ds(H5Dcreate2(group, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  check(ds.ok(), where + ": cannot create dataset crlb/" + name);
  check(H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0, where + ": cannot write dataset crlb/" + name);
}

void write_attr(hid_t obj, const char* name, const std::string& v, const std::string& where) {
  Id type(H5Tcopy(H5T_C_S1), H5Tclose);
  check(type.ok() && H5Tset_size(type, H5T_VARIABLE) >= 0, where + ": cannot make a string type");
  Id space(H5Screate(H5S_SCALAR), H5Sclose);
  Id a(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  const char* s = v.c_str();
  check(a.ok() && H5Awrite(a, type, &s) >= 0, where + ": cannot write attribute crlb/" + name);
}

void write_attr(hid_t obj, const char* name, double v, const std::string& where) {
  Id space(H5Screate(H5S_SCALAR), H5Sclose);
  Id a(H5Acreate2(obj, name, H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  check(a.ok() && H5Awrite(a, H5T_NATIVE_DOUBLE, &v) >= 0, where + ": cannot write attribute crlb/" + name);
}

void write_group(const std::string& tmp, const std::string& where, const ResultCovariance& c) {
  Id file(H5Fopen(tmp.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
  check(file.ok(), where + ": cannot open the result file for writing");
  if (H5Lexists(file, "crlb", H5P_DEFAULT) > 0)
    check(H5Ldelete(file, "crlb", H5P_DEFAULT) >= 0, where + ": cannot replace group crlb");
  Id g(H5Gcreate2(file, "crlb", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check(g.ok(), where + ": cannot create group crlb");
  const hsize_t n = static_cast<hsize_t>(c.num_sensors), p = static_cast<hsize_t>(c.dim);
  const hsize_t dc[3] = {n, p, p}, dm[1] = {n};
  write_dataset(g, "covariance", H5T_NATIVE_DOUBLE, 3, dc, c.covariance.data(), where);
  write_dataset(g, "covered", H5T_NATIVE_UINT8, 1, dm, c.covered.data(), where);
  write_attr(g, "at", c.at, where);
  write_attr(g, "sigma_model", c.sigma_model, where);
  write_attr(g, "sigma", c.sigma, where);
  write_attr(g, "rmse", c.rmse, where);
  check(H5Fflush(file, H5F_SCOPE_GLOBAL) >= 0, where + ": cannot flush the result file");
  const hid_t f = file.id;
  file.id = -1;
  check(H5Fclose(f) >= 0, where + ": cannot close the result file");
}

}  // namespace

void add_covariance_to_result(const std::string& path, const ResultCovariance& c) {
  const std::string where = "cannot add the CRLB covariances to " + path;
  const auto n = static_cast<std::size_t>(c.num_sensors), p = static_cast<std::size_t>(c.dim);
  check(c.dim >= 1 && c.covariance.size() == n * p * p && c.covered.size() == n, where + ": inconsistent sizes");
  h5_quiet();
  namespace fs = std::filesystem;
  const std::string tmp = path + ".crlb-tmp";  // next to it: the rename stays on one file system
  std::error_code ec;
  fs::copy_file(path, tmp, fs::copy_options::overwrite_existing, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(where + ": cannot copy it (" + ec.message() + ")");
  }
  try {
    write_group(tmp, where, c);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ec2;
    fs::remove(tmp, ec2);
    throw Error(where + ": cannot rename the edited copy over it (" + ec.message() + ")");
  }
}

}  // namespace snl
