#pragma once
// A thin RAII layer over parallel HDF5 used by every snl file (network,
// result, checkpoint). All calls are collective over the file's communicator
// unless stated otherwise. Failures throw snl::Error on every rank alike.
#include <mpi.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "snl/core/common.hpp"

namespace snl {

class H5File {
 public:
  enum class Mode { kRead, kCreate };

  /// kRead opens an existing file read-only. kCreate creates a temporary file
  /// next to `path` (same directory); commit() renames it over `path`. A file
  /// that is destroyed without commit() removes its temporary file, so an
  /// existing `path` is never clobbered by a failed write (the HDF5 file is
  /// then left open: see h5_close_failed).
  H5File(const std::string& path, MPI_Comm comm, Mode mode);
  ~H5File();
  H5File(const H5File&) = delete;
  H5File& operator=(const H5File&) = delete;

  const std::string& path() const;
  MPI_Comm comm() const;

  // Attributes of the root (or of a group given as "group/name").
  bool has_attr(const std::string& name) const;
  void set_attr(const std::string& name, const std::string& value);
  void set_attr(const std::string& name, std::int64_t value);
  void set_attr(const std::string& name, double value);
  /// A 1-D array of doubles (e.g. a vector such as x*).
  void set_attr(const std::string& name, const std::vector<double>& values);
  /// A fixed-length string attribute (as MATLAB and Fortran codes write them);
  /// padded with spaces or NULs. For interoperability; set_attr writes the
  /// variable-length strings h5py writes.
  void set_attr_fixed_string(const std::string& name, const std::string& value, bool space_pad = false);
  std::string attr_string(const std::string& name) const;
  std::int64_t attr_int(const std::string& name) const;
  double attr_double(const std::string& name) const;

  bool has_dataset(const std::string& name) const;
  /// Shape of a dataset (empty for a scalar).
  std::vector<std::uint64_t> shape(const std::string& name) const;

  /// Writes rows [row_offset, row_offset + rows) of a [total_rows, cols]
  /// dataset (cols == 0: 1-D [total_rows]); every rank its own slab; slabs may
  /// be empty. Creates intermediate groups as needed.
  void write_rows(const std::string& name, std::uint64_t total_rows, std::uint64_t cols,
                  std::uint64_t row_offset, const double* data, std::uint64_t rows);
  void write_rows(const std::string& name, std::uint64_t total_rows, std::uint64_t cols,
                  std::uint64_t row_offset, const std::int64_t* data, std::uint64_t rows);
  void write_rows(const std::string& name, std::uint64_t total_rows, std::uint64_t cols,
                  std::uint64_t row_offset, const std::uint8_t* data, std::uint64_t rows);
  /// Same data on every rank: rank 0's copy is written (1-D).
  void write_replicated(const std::string& name, const std::vector<double>& v);
  void write_replicated(const std::string& name, const std::vector<std::int64_t>& v);
  void write_scalar(const std::string& name, double v);

  /// Reads rows [row_offset, row_offset + rows) of a 1-D or 2-D dataset
  /// (collective read; each rank its own slab). Throws if the dataset is
  /// missing, of the wrong rank/type class, or the slab is out of range.
  std::vector<double> read_rows_double(const std::string& name, std::uint64_t row_offset, std::uint64_t rows) const;
  std::vector<std::int64_t> read_rows_int(const std::string& name, std::uint64_t row_offset, std::uint64_t rows) const;
  std::vector<std::uint8_t> read_rows_u8(const std::string& name, std::uint64_t row_offset, std::uint64_t rows) const;
  double read_scalar(const std::string& name) const;

  /// Names of the links in a group ("." for the root); empty if it is missing.
  std::vector<std::string> list(const std::string& group) const;
  /// Names of the attributes of an object ("." for the root).
  std::vector<std::string> attr_names(const std::string& object = ".") const;
  /// True if the attribute (which must exist) holds a string.
  bool attr_is_string(const std::string& name) const;

  /// Flushes, closes and (kCreate) renames the temporary file over path().
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Silences HDF5's automatic error stack printing (we report our own errors).
void h5_quiet();

/// True once a file on this process failed to close or was discarded after a
/// write error (left open: closing it would flush HDF5's metadata, which with a
/// full disk parallel HDF5 1.10 fails on some ranks only, a hang; and a failed
/// close leaves an id over a freed object that crashes HDF5's own shutdown in
/// MPI_Finalize or at exit, HDF5 CVE-2020-10812, fixed in 1.14.1). Such a
/// process must end without shutting HDF5 down (apps/snl_main.cpp: _Exit).
bool h5_close_failed();

}  // namespace snl
