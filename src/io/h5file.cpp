// Parallel HDF5 layer (see include/snl/h5file.hpp). Every public method is
// collective and ends with agree(), so a failure seen by one rank becomes the
// same snl::Error on all ranks and nobody is left waiting in a collective.
// One file because every method shares the same agree-and-close discipline
// around the HDF5 C API (error stack, property lists, atomic replace).
#include "snl/io/h5file.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <type_traits>

#include "snl/core/mpi_util.hpp"

namespace snl {

namespace {

// Largest transfer per H5Dread/H5Dwrite call: keeps MPI-IO counts far below
// INT_MAX bytes whatever the slab size.
constexpr std::uint64_t kMaxIoBytes = std::uint64_t{256} << 20;

/// Closes an HDF5 handle of any kind on scope exit.
struct Hid {
  hid_t id = -1;
  Hid() = default;
  explicit Hid(hid_t i) : id(i) {}
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  Hid(Hid&& o) noexcept : id(o.id) { o.id = -1; }
  Hid& operator=(Hid&& o) noexcept {
    if (this != &o) {
      reset();
      id = o.id;
      o.id = -1;
    }
    return *this;
  }
  ~Hid() { reset(); }
  void reset() {
    if (id >= 0) {
      H5Idec_ref(id);
      id = -1;
    }
  }
  bool ok() const { return id >= 0; }
  operator hid_t() const { return id; }  // NOLINT: a handle is used where hid_t is
};

/// The innermost message of HDF5's error stack (the most specific cause).
herr_t walk_cb(unsigned n, const H5E_error2_t* e, void* data) {
  auto* out = static_cast<std::string*>(data);
  if (n == 0 && e && e->desc) *out = e->desc;
  return 0;
}
std::string h5_detail() {
  std::string d;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk_cb, &d);
  H5Eclear2(H5E_DEFAULT);
  return d;
}

/// Splits "group/name" into ("group", "name"); a bare name lives at the root.
void split_name(const std::string& full, std::string& obj, std::string& leaf) {
  const auto slash = full.rfind('/');
  if (slash == std::string::npos) {
    obj = ".";
    leaf = full;
  } else {
    obj = slash == 0 ? "/" : full.substr(0, slash);
    leaf = full.substr(slash + 1);
  }
}

/// True if every link on the path exists (H5Lexists fails on a missing parent).
bool link_exists(hid_t file, const std::string& path) {
  if (path == "." || path == "/") return true;
  std::size_t pos = 0;
  while (true) {
    const auto slash = path.find('/', pos);
    const std::string prefix = path.substr(0, slash);
    if (!prefix.empty() && H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
    if (slash == std::string::npos) return true;
    pos = slash + 1;
  }
}

const char* class_name(H5T_class_t c) {
  switch (c) {
    case H5T_INTEGER: return "integer";
    case H5T_FLOAT: return "floating point";
    case H5T_STRING: return "string";
    case H5T_COMPOUND: return "compound";
    case H5T_ENUM: return "enum";
    case H5T_ARRAY: return "array";
    case H5T_VLEN: return "variable-length";
    case H5T_REFERENCE: return "reference";
    case H5T_OPAQUE: return "opaque";
    case H5T_BITFIELD: return "bitfield";
    default: return "unknown";
  }
}

std::string errno_text(int e) { return std::strerror(e); }

std::string dir_of(const std::string& path) {
  const auto slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

/// Allocates the blocks of bytes [0, size) of `file`, so that HDF5's metadata
/// flush at close, which writes inside the space it has already addressed,
/// cannot fail with ENOSPC. Parallel HDF5 1.10 does not survive a flush that
/// fails on one rank only (that rank leaves a barrier the others wait in), so
/// a full disk must be seen here, before the close. Returns "" or the reason;
/// a file system without fallocate is not reserved (and not protected).
std::string reserve_space(const std::string& file, hid_t h5) {
  hsize_t size = 0;
  if (H5Fget_filesize(h5, &size) < 0) {
    H5Eclear2(H5E_DEFAULT);
    return "";
  }
  const int fd = ::open(file.c_str(), O_WRONLY);
  if (fd < 0) return errno_text(errno);
  int rc = 0;
  if (size > 0 && ::fallocate(fd, 0, 0, static_cast<off_t>(size)) != 0) rc = errno;
  ::close(fd);
  if (rc == 0 || rc == EOPNOTSUPP || rc == ENOSYS || rc == EINVAL) return "";
  return errno_text(rc);
}

template <class T>
hid_t native_type() {
  if constexpr (std::is_same_v<T, double>) return H5T_NATIVE_DOUBLE;
  if constexpr (std::is_same_v<T, std::int64_t>) return H5T_NATIVE_INT64;
  if constexpr (std::is_same_v<T, std::uint8_t>) return H5T_NATIVE_UINT8;
}

template <class T>
hid_t file_type() {
  if constexpr (std::is_same_v<T, double>) return H5T_IEEE_F64LE;
  if constexpr (std::is_same_v<T, std::int64_t>) return H5T_STD_I64LE;
  if constexpr (std::is_same_v<T, std::uint8_t>) return H5T_STD_U8LE;
}

}  // namespace

void h5_quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

namespace {
bool g_close_failed = false;  // see h5_close_failed()
}  // namespace

bool h5_close_failed() { return g_close_failed; }

// The state lives outside the class so that helpers in this file can use it.
struct H5FileState {
  std::string path;
  std::string tmp;  // kCreate: the file actually written until commit()
  MPI_Comm comm = MPI_COMM_NULL;
  H5File::Mode mode = H5File::Mode::kRead;
  int rank = 0;
  hid_t file = -1;
  bool committed = false;

  std::string where(const std::string& name) const { return path + ": " + name; }

  void need_open() const {
    if (file < 0) throw Error(path + ": file already closed");
  }
  void need_write() const {
    need_open();
    if (mode != H5File::Mode::kCreate) throw Error(path + ": file is open read-only");
  }

  Hid open_dataset(const std::string& name) const {
    if (!link_exists(file, name)) throw Error(path + ": dataset '" + name + "' not found");
    Hid d(H5Dopen2(file, name.c_str(), H5P_DEFAULT));
    if (!d.ok()) throw Error(path + ": '" + name + "' is not a readable dataset (" + h5_detail() + ")");
    return d;
  }

  Hid open_attr(const std::string& full) const {
    std::string obj, leaf;
    split_name(full, obj, leaf);
    if (!link_exists(file, obj) || H5Aexists_by_name(file, obj.c_str(), leaf.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      throw Error(path + ": attribute '" + full + "' not found");
    }
    Hid a(H5Aopen_by_name(file, obj.c_str(), leaf.c_str(), H5P_DEFAULT, H5P_DEFAULT));
    if (!a.ok()) throw Error(path + ": cannot open attribute '" + full + "' (" + h5_detail() + ")");
    Hid space(H5Aget_space(a));
    const hssize_t npts = H5Sget_simple_extent_npoints(space);
    if (npts != 1)
      throw Error(path + ": attribute '" + full + "' has " + std::to_string(npts) +
                  " values, expected a single value");
    return a;
  }

  /// Reads a one-value numeric attribute converted to T; integers only when
  /// !allow_float (a float attribute is accepted if its value is integral:
  /// MATLAB writes numeric literals as double).
  template <class T>
  T attr_number(const std::string& full) const {
    need_open();
    Hid a = open_attr(full);
    Hid t(H5Aget_type(a));
    const H5T_class_t c = H5Tget_class(t);
    if (c == H5T_INTEGER && std::is_integral_v<T>) {
      T v{};
      if (H5Aread(a, native_type<T>(), &v) < 0) throw Error(path + ": cannot read attribute '" + full + "'");
      return v;
    }
    if (c != H5T_INTEGER && c != H5T_FLOAT)
      throw Error(path + ": attribute '" + full + "' has type " + class_name(c) + ", expected a number");
    double v = 0;
    if (H5Aread(a, H5T_NATIVE_DOUBLE, &v) < 0) throw Error(path + ": cannot read attribute '" + full + "'");
    if constexpr (std::is_integral_v<T>) {
      if (!std::isfinite(v) || v != std::floor(v) || std::fabs(v) > 9.0e15)
        throw Error(path + ": attribute '" + full + "' = " + std::to_string(v) + " is not an integer");
      return static_cast<T>(v);
    } else {
      return v;
    }
  }

  ~H5FileState() {
    // Never throws: the destructor may run during unwinding on every rank.
    if (mode == H5File::Mode::kCreate && !committed && file >= 0) {
      // Discarding a file being written, after an error (agreed on every
      // rank). Closing it would flush HDF5's metadata, and with a full disk
      // parallel HDF5 1.10 fails that flush on some ranks only, which then
      // leave a barrier the others wait in (a hang), or it crashes later in
      // its shutdown. The file is left open instead (the temporary is removed
      // below) and the process ends without HDF5's shutdown (h5_close_failed).
      g_close_failed = true;
      file = -1;
    }
    if (file >= 0) {
      if (H5Fclose(file) < 0) g_close_failed = true;
      file = -1;
    }
    if (mode == H5File::Mode::kCreate && !committed && rank == 0 && !tmp.empty()) std::remove(tmp.c_str());
    H5Eclear2(H5E_DEFAULT);
  }
};

struct H5File::Impl : H5FileState {};

H5File::H5File(const std::string& path, MPI_Comm comm, Mode mode) : impl_(std::make_unique<Impl>()) {
  h5_quiet();
  Impl& m = *impl_;
  m.path = path;
  m.comm = comm;
  m.mode = mode;
  m.rank = comm_rank(comm);

  Hid fapl(H5Pcreate(H5P_FILE_ACCESS));
  std::string err;
  if (!fapl.ok() || H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) < 0)
    err = path + ": cannot set up MPI-IO file access (" + h5_detail() + ")";
  agree(comm, err);

  if (mode == Mode::kRead) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
      err = errno == ENOENT ? path + ": no such file" : path + ": " + errno_text(errno);
    else if (S_ISDIR(st.st_mode))
      err = path + ": is a directory, not an HDF5 file";
    else if (::access(path.c_str(), R_OK) != 0)
      err = path + ": cannot read (" + errno_text(errno) + ")";
    agree(comm, err);
    m.file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
    if (m.file < 0) {
      const std::string d = h5_detail();
      err = path + ": not a readable HDF5 file" + (d.empty() ? "" : " (" + d + ")");
    }
    agree(comm, err);
    return;
  }

  // kCreate: check the directory first, for a clearer message than HDF5's.
  if (m.rank == 0) {
    const std::string dir = dir_of(path);
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0)
      err = "cannot write " + path + ": directory " + dir + " does not exist";
    else if (!S_ISDIR(st.st_mode))
      err = "cannot write " + path + ": " + dir + " is not a directory";
    else if (::access(dir.c_str(), W_OK) != 0)
      err = "cannot write " + path + ": directory " + dir + " is not writable";
    else if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
      err = "cannot write " + path + ": it is a directory";
    else if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
      err = "cannot write " + path + ": it is not a regular file (it would be replaced)";
  }
  agree(comm, err);
  long long pid = m.rank == 0 ? static_cast<long long>(::getpid()) : 0;
  MPI_Bcast(&pid, 1, MPI_LONG_LONG, 0, comm);
  m.tmp = path + ".tmp-" + std::to_string(pid);
  Hid fcpl(H5Pcreate(H5P_FILE_CREATE));
  // Metadata written collectively: fewer small writes on a parallel file system.
  H5Pset_coll_metadata_write(fapl, 1);
  m.file = H5Fcreate(m.tmp.c_str(), H5F_ACC_TRUNC, fcpl, fapl);
  if (m.file < 0) err = "cannot create " + m.tmp + " (" + h5_detail() + ")";
  agree(comm, err);
}

H5File::~H5File() = default;

const std::string& H5File::path() const { return impl_->path; }
MPI_Comm H5File::comm() const { return impl_->comm; }

bool H5File::has_attr(const std::string& name) const {
  const Impl& m = *impl_;
  std::string err;
  bool found = false;
  try {
    m.need_open();
    std::string obj, leaf;
    split_name(name, obj, leaf);
    found = link_exists(m.file, obj) && H5Aexists_by_name(m.file, obj.c_str(), leaf.c_str(), H5P_DEFAULT) > 0;
    H5Eclear2(H5E_DEFAULT);
  } catch (const std::exception& e) {
    err = e.what();
  }
  agree(m.comm, err);
  return found;
}

// Before writing attribute obj/leaf: create the object's groups if missing and
// drop an existing attribute of that name (attributes cannot change type).
static void prepare_attr(const H5FileState& m, const std::string& obj, const std::string& leaf) {
  if (!link_exists(m.file, obj)) {
    Hid lcpl(H5Pcreate(H5P_LINK_CREATE));
    H5Pset_create_intermediate_group(lcpl, 1);
    Hid g(H5Gcreate2(m.file, obj.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT));
    if (!g.ok()) throw Error(m.where("cannot create group '" + obj + "' (" + h5_detail() + ")"));
  }
  if (H5Aexists_by_name(m.file, obj.c_str(), leaf.c_str(), H5P_DEFAULT) > 0)
    H5Adelete_by_name(m.file, obj.c_str(), leaf.c_str(), H5P_DEFAULT);
}

void H5File::set_attr(const std::string& name, const std::string& value) {
  collective_try(impl_->comm, [&] {
    const Impl& m = *impl_;
    m.need_write();
    std::string obj, leaf;
    split_name(name, obj, leaf);
    prepare_attr(m, obj, leaf);
    // Variable-length UTF-8: what h5py writes, and it reads back as str.
    Hid t(H5Tcopy(H5T_C_S1));
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    Hid space(H5Screate(H5S_SCALAR));
    Hid a(H5Acreate_by_name(m.file, obj.c_str(), leaf.c_str(), t, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    const char* p = value.c_str();
    if (!a.ok() || H5Awrite(a, t, &p) < 0)
      throw Error(m.where("cannot write attribute '" + name + "' (" + h5_detail() + ")"));
  });
}

void H5File::set_attr_fixed_string(const std::string& name, const std::string& value, bool space_pad) {
  collective_try(impl_->comm, [&] {
    const H5FileState& m = *impl_;
    m.need_write();
    std::string obj, leaf;
    split_name(name, obj, leaf);
    if (!link_exists(m.file, obj)) throw Error(m.where("object '" + obj + "' not found"));
    if (H5Aexists_by_name(m.file, obj.c_str(), leaf.c_str(), H5P_DEFAULT) > 0)
      H5Adelete_by_name(m.file, obj.c_str(), leaf.c_str(), H5P_DEFAULT);
    // Stored with two pad characters so that the reader's trimming is exercised.
    std::string buf = value + std::string(2, space_pad ? ' ' : '\0');
    Hid t(H5Tcopy(H5T_C_S1));
    H5Tset_size(t, buf.size());
    H5Tset_strpad(t, space_pad ? H5T_STR_SPACEPAD : H5T_STR_NULLPAD);
    Hid space(H5Screate(H5S_SCALAR));
    Hid a(H5Acreate_by_name(m.file, obj.c_str(), leaf.c_str(), t, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (!a.ok() || H5Awrite(a, t, buf.data()) < 0)
      throw Error(m.where("cannot write attribute '" + name + "' (" + h5_detail() + ")"));
  });
}

namespace {
template <class T>
void set_number_attr(const H5FileState& m, const std::string& name, T value) {
  m.need_write();
  std::string obj, leaf;
  split_name(name, obj, leaf);
  prepare_attr(m, obj, leaf);
  Hid space(H5Screate(H5S_SCALAR));
  Hid a(H5Acreate_by_name(m.file, obj.c_str(), leaf.c_str(), file_type<T>(), space, H5P_DEFAULT, H5P_DEFAULT,
                          H5P_DEFAULT));
  if (!a.ok() || H5Awrite(a, native_type<T>(), &value) < 0)
    throw Error(m.where("cannot write attribute '" + name + "' (" + h5_detail() + ")"));
}
}  // namespace

void H5File::set_attr(const std::string& name, std::int64_t value) {
  collective_try(impl_->comm, [&] { set_number_attr(*impl_, name, value); });
}

void H5File::set_attr(const std::string& name, double value) {
  collective_try(impl_->comm, [&] { set_number_attr(*impl_, name, value); });
}

void H5File::set_attr(const std::string& name, const std::vector<double>& values) {
  collective_try(impl_->comm, [&] {
    const H5FileState& m = *impl_;
    m.need_write();
    std::string obj, leaf;
    split_name(name, obj, leaf);
    prepare_attr(m, obj, leaf);
    const hsize_t len = values.size();
    Hid space(H5Screate_simple(1, &len, nullptr));
    Hid a(H5Acreate_by_name(m.file, obj.c_str(), leaf.c_str(), file_type<double>(), space, H5P_DEFAULT, H5P_DEFAULT,
                            H5P_DEFAULT));
    if (!a.ok() || H5Awrite(a, native_type<double>(), values.data()) < 0)
      throw Error(m.where("cannot write attribute '" + name + "' (" + h5_detail() + ")"));
  });
}

std::string H5File::attr_string(const std::string& name) const {
  const Impl& m = *impl_;
  std::string out;
  collective_try(m.comm, [&] {
    m.need_open();
    Hid a = m.open_attr(name);
    Hid t(H5Aget_type(a));
    const H5T_class_t c = H5Tget_class(t);
    if (c != H5T_STRING)
      throw Error(m.where("attribute '" + name + "' has type " + class_name(c) + ", expected a string"));
    const H5T_cset_t cset = H5Tget_cset(t);
    if (H5Tis_variable_str(t) > 0) {
      Hid mt(H5Tcopy(H5T_C_S1));
      H5Tset_size(mt, H5T_VARIABLE);
      H5Tset_cset(mt, cset);
      char* p = nullptr;
      if (H5Aread(a, mt, &p) < 0) throw Error(m.where("cannot read attribute '" + name + "'"));
      out = p ? p : "";
      if (p) H5free_memory(p);
    } else {
      // Fixed length (MATLAB, Fortran, h5py with np.bytes_): pad by NULs or spaces.
      const std::size_t size = H5Tget_size(t);
      const H5T_str_t pad = H5Tget_strpad(t);
      Hid mt(H5Tcopy(H5T_C_S1));
      H5Tset_size(mt, size);
      H5Tset_cset(mt, cset);
      H5Tset_strpad(mt, H5T_STR_NULLPAD);
      std::string buf(size, '\0');
      if (H5Aread(a, mt, buf.data()) < 0) throw Error(m.where("cannot read attribute '" + name + "'"));
      out = buf.substr(0, buf.find('\0'));
      if (pad == H5T_STR_SPACEPAD) out.erase(out.find_last_not_of(' ') + 1);
    }
  });
  return out;
}

std::int64_t H5File::attr_int(const std::string& name) const {
  std::int64_t v = 0;
  collective_try(impl_->comm, [&] { v = impl_->attr_number<std::int64_t>(name); });
  return v;
}

double H5File::attr_double(const std::string& name) const {
  double v = 0;
  collective_try(impl_->comm, [&] { v = impl_->attr_number<double>(name); });
  return v;
}

bool H5File::has_dataset(const std::string& name) const {
  const Impl& m = *impl_;
  bool found = false;
  collective_try(m.comm, [&] {
    m.need_open();
    if (!link_exists(m.file, name)) return;
    Hid o(H5Oopen(m.file, name.c_str(), H5P_DEFAULT));
    found = o.ok() && H5Iget_type(o) == H5I_DATASET;
    H5Eclear2(H5E_DEFAULT);
  });
  return found;
}

std::vector<std::uint64_t> H5File::shape(const std::string& name) const {
  const Impl& m = *impl_;
  std::vector<std::uint64_t> out;
  collective_try(m.comm, [&] {
    m.need_open();
    Hid d = m.open_dataset(name);
    Hid s(H5Dget_space(d));
    const int nd = H5Sget_simple_extent_ndims(s);
    if (nd < 0) throw Error(m.where("cannot read the shape of '" + name + "'"));
    std::vector<hsize_t> dims(static_cast<std::size_t>(nd));
    H5Sget_simple_extent_dims(s, dims.data(), nullptr);
    out.assign(dims.begin(), dims.end());
  });
  return out;
}

namespace {

/// Selects rows [first, first+count) x all columns, or nothing when count == 0.
void select_rows(hid_t space, int ndims, hsize_t first, hsize_t count, hsize_t cols) {
  if (count == 0) {
    H5Sselect_none(space);
    return;
  }
  hsize_t start[2] = {first, 0};
  hsize_t cnt[2] = {count, cols};
  H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, cnt, nullptr);
  (void)ndims;
}

/// Collective transfer of this rank's rows in pieces of <= kMaxIoBytes; every
/// rank makes the same number of calls (empty selections once done).
template <class T, bool kWrite>
std::string transfer_rows(MPI_Comm comm, hid_t dset, hid_t memtype, int ndims, std::uint64_t cols,
                          std::uint64_t row_offset, T* data, std::uint64_t rows) {
  const std::uint64_t row_bytes = std::max<std::uint64_t>(cols, 1) * sizeof(T);
  const std::uint64_t piece = std::max<std::uint64_t>(1, kMaxIoBytes / row_bytes);
  unsigned long long pieces = (rows + piece - 1) / piece, all_pieces = 0;
  MPI_Allreduce(&pieces, &all_pieces, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, comm);
  const hsize_t c = std::max<std::uint64_t>(cols, 1);
  Hid dxpl(H5Pcreate(H5P_DATASET_XFER));
  H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
  std::string err;
  T dummy{};
  for (unsigned long long k = 0; k < all_pieces; ++k) {
    const std::uint64_t first = std::min<std::uint64_t>(rows, k * piece);
    const std::uint64_t count = std::min(rows - first, piece);
    Hid fspace(H5Dget_space(dset));
    select_rows(fspace, ndims, row_offset + first, count, c);
    hsize_t mdim = std::max<hsize_t>(count * c, 1);
    Hid mspace(H5Screate_simple(1, &mdim, nullptr));
    if (count == 0) H5Sselect_none(mspace);
    T* p = count ? data + first * c : &dummy;
    herr_t st;
    if constexpr (kWrite)
      st = H5Dwrite(dset, memtype, mspace, fspace, dxpl, p);
    else
      st = H5Dread(dset, memtype, mspace, fspace, dxpl, p);
    if (st < 0 && err.empty()) err = h5_detail();
  }
  return err;
}

}  // namespace

template <class T>
static void write_rows_impl(const H5FileState& m, const std::string& name, std::uint64_t total_rows,
                            std::uint64_t cols, std::uint64_t row_offset, const T* data, std::uint64_t rows) {
  std::string err;
  try {
    m.need_write();
    if (row_offset > total_rows || rows > total_rows - row_offset)
      err = m.where("rows [" + std::to_string(row_offset) + ", " + std::to_string(row_offset + rows) +
                    ") of '" + name + "' lie outside [0, " + std::to_string(total_rows) + ")");
    if (rows > 0 && data == nullptr) err = m.where("no data given for '" + name + "'");
  } catch (const std::exception& e) {
    err = e.what();
  }
  agree(m.comm, err);
  // The shape is collective metadata: every rank must pass the same one.
  unsigned long long mine[2] = {total_rows, cols}, lo[2], hi[2];
  MPI_Allreduce(mine, lo, 2, MPI_UNSIGNED_LONG_LONG, MPI_MIN, m.comm);
  MPI_Allreduce(mine, hi, 2, MPI_UNSIGNED_LONG_LONG, MPI_MAX, m.comm);
  if (lo[0] != hi[0] || lo[1] != hi[1])
    throw Error(m.where("ranks disagree on the shape of '" + name + "'"));

  const int ndims = cols == 0 ? 1 : 2;
  Hid dset;
  try {
    if (link_exists(m.file, name)) {
      dset = m.open_dataset(name);
      Hid s(H5Dget_space(dset));
      hsize_t dims[2] = {0, 0};
      const int nd = H5Sget_simple_extent_ndims(s);
      H5Sget_simple_extent_dims(s, dims, nullptr);
      if (nd != ndims || dims[0] != total_rows || (ndims == 2 && dims[1] != cols))
        throw Error(m.where("dataset '" + name + "' exists with another shape"));
    } else {
      hsize_t dims[2] = {total_rows, cols};
      Hid space(H5Screate_simple(ndims, dims, nullptr));
      Hid lcpl(H5Pcreate(H5P_LINK_CREATE));
      H5Pset_create_intermediate_group(lcpl, 1);
      Hid dcpl(H5Pcreate(H5P_DATASET_CREATE));
      // Contiguous, no fill: every element is written once, so skip the fill pass.
      H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER);
      dset = Hid(H5Dcreate2(m.file, name.c_str(), file_type<T>(), space, lcpl, dcpl, H5P_DEFAULT));
      if (!dset.ok()) throw Error(m.where("cannot create dataset '" + name + "' (" + h5_detail() + ")"));
    }
  } catch (const std::exception& e) {
    err = e.what();
  }
  agree(m.comm, err);
  err = transfer_rows<T, true>(m.comm, dset, native_type<T>(), ndims, cols, row_offset, const_cast<T*>(data), rows);
  if (!err.empty()) err = m.where("cannot write dataset '" + name + "' (" + err + ")");
  agree(m.comm, err);
}

void H5File::write_rows(const std::string& name, std::uint64_t total_rows, std::uint64_t cols,
                        std::uint64_t row_offset, const double* data, std::uint64_t rows) {
  write_rows_impl(*impl_, name, total_rows, cols, row_offset, data, rows);
}
void H5File::write_rows(const std::string& name, std::uint64_t total_rows, std::uint64_t cols,
                        std::uint64_t row_offset, const std::int64_t* data, std::uint64_t rows) {
  write_rows_impl(*impl_, name, total_rows, cols, row_offset, data, rows);
}
void H5File::write_rows(const std::string& name, std::uint64_t total_rows, std::uint64_t cols,
                        std::uint64_t row_offset, const std::uint8_t* data, std::uint64_t rows) {
  write_rows_impl(*impl_, name, total_rows, cols, row_offset, data, rows);
}

template <class T>
static void write_replicated_impl(const H5FileState& m, const std::string& name, const std::vector<T>& v) {
  const std::uint64_t n = v.size();
  unsigned long long lo = n, hi = n;
  MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_UNSIGNED_LONG_LONG, MPI_MIN, m.comm);
  MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, m.comm);
  if (lo != hi) throw Error(m.where("ranks disagree on the length of '" + name + "'"));
  const bool root = m.rank == 0;
  write_rows_impl<T>(m, name, n, 0, 0, root ? v.data() : nullptr, root ? n : 0);
}

void H5File::write_replicated(const std::string& name, const std::vector<double>& v) {
  write_replicated_impl(*impl_, name, v);
}
void H5File::write_replicated(const std::string& name, const std::vector<std::int64_t>& v) {
  write_replicated_impl(*impl_, name, v);
}

void H5File::write_scalar(const std::string& name, double v) {
  const Impl& m = *impl_;
  collective_try(m.comm, [&] {
    m.need_write();
    if (link_exists(m.file, name)) throw Error(m.where("dataset '" + name + "' already exists"));
    Hid space(H5Screate(H5S_SCALAR));
    Hid lcpl(H5Pcreate(H5P_LINK_CREATE));
    H5Pset_create_intermediate_group(lcpl, 1);
    Hid d(H5Dcreate2(m.file, name.c_str(), H5T_IEEE_F64LE, space, lcpl, H5P_DEFAULT, H5P_DEFAULT));
    if (!d.ok()) throw Error(m.where("cannot create dataset '" + name + "' (" + h5_detail() + ")"));
    // Rank 0 writes the value; the others take part with empty selections.
    Hid fspace(H5Dget_space(d));
    Hid mspace(H5Screate(H5S_SCALAR));
    if (m.rank != 0) {
      H5Sselect_none(fspace);
      H5Sselect_none(mspace);
    }
    Hid dxpl(H5Pcreate(H5P_DATASET_XFER));
    H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
    if (H5Dwrite(d, H5T_NATIVE_DOUBLE, mspace, fspace, dxpl, &v) < 0)
      throw Error(m.where("cannot write dataset '" + name + "' (" + h5_detail() + ")"));
  });
}

template <class T>
static std::vector<T> read_rows_impl(const H5FileState& m, const std::string& name, std::uint64_t row_offset,
                                     std::uint64_t rows) {
  std::string err;
  Hid dset;
  int ndims = 0;
  hsize_t dims[2] = {0, 0};
  std::vector<T> out;
  try {
    m.need_open();
    dset = m.open_dataset(name);
    Hid t(H5Dget_type(dset));
    const H5T_class_t c = H5Tget_class(t);
    const bool ok = c == H5T_INTEGER || (c == H5T_FLOAT && std::is_floating_point_v<T>);
    if (!ok)
      throw Error(m.where("dataset '" + name + "' has type " + class_name(c) + ", expected " +
                          (std::is_floating_point_v<T> ? "floating point" : "integer")));
    Hid s(H5Dget_space(dset));
    ndims = H5Sget_simple_extent_ndims(s);
    if (ndims < 1 || ndims > 2)
      throw Error(m.where("dataset '" + name + "' has " + std::to_string(ndims) +
                          " dimensions, expected 1 or 2"));
    H5Sget_simple_extent_dims(s, dims, nullptr);
    if (row_offset > dims[0] || rows > dims[0] - row_offset)
      throw Error(m.where("rows [" + std::to_string(row_offset) + ", " + std::to_string(row_offset + rows) +
                          ") of '" + name + "' lie outside [0, " + std::to_string(dims[0]) + ")"));
    const std::uint64_t cols = ndims == 2 ? dims[1] : 1;
    out.resize(rows * cols);
  } catch (const std::bad_alloc&) {
    err = m.where("out of memory reading '" + name + "'");
  } catch (const std::exception& e) {
    err = e.what();
  }
  agree(m.comm, err);
  err = transfer_rows<T, false>(m.comm, dset, native_type<T>(), ndims, ndims == 2 ? dims[1] : 0, row_offset,
                                out.data(), rows);
  if (!err.empty()) err = m.where("cannot read dataset '" + name + "' (" + err + ")");
  agree(m.comm, err);
  return out;
}

std::vector<double> H5File::read_rows_double(const std::string& name, std::uint64_t row_offset,
                                             std::uint64_t rows) const {
  return read_rows_impl<double>(*impl_, name, row_offset, rows);
}
std::vector<std::int64_t> H5File::read_rows_int(const std::string& name, std::uint64_t row_offset,
                                                std::uint64_t rows) const {
  return read_rows_impl<std::int64_t>(*impl_, name, row_offset, rows);
}
std::vector<std::uint8_t> H5File::read_rows_u8(const std::string& name, std::uint64_t row_offset,
                                               std::uint64_t rows) const {
  return read_rows_impl<std::uint8_t>(*impl_, name, row_offset, rows);
}

double H5File::read_scalar(const std::string& name) const {
  const Impl& m = *impl_;
  double v = 0;
  collective_try(m.comm, [&] {
    m.need_open();
    Hid d = m.open_dataset(name);
    Hid t(H5Dget_type(d));
    const H5T_class_t c = H5Tget_class(t);
    if (c != H5T_INTEGER && c != H5T_FLOAT)
      throw Error(m.where("dataset '" + name + "' has type " + class_name(c) + ", expected a number"));
    Hid s(H5Dget_space(d));
    const hssize_t npts = H5Sget_simple_extent_npoints(s);
    if (npts != 1)
      throw Error(m.where("dataset '" + name + "' has " + std::to_string(npts) + " values, expected a scalar"));
    if (H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v) < 0)
      throw Error(m.where("cannot read dataset '" + name + "' (" + h5_detail() + ")"));
  });
  return v;
}

std::vector<std::string> H5File::list(const std::string& group) const {
  const Impl& m = *impl_;
  std::vector<std::string> names;
  collective_try(m.comm, [&] {
    m.need_open();
    if (!link_exists(m.file, group)) return;
    auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
      static_cast<std::vector<std::string>*>(data)->emplace_back(name);
      return 0;
    };
    if (H5Literate_by_name(m.file, group.c_str(), H5_INDEX_NAME, H5_ITER_INC, nullptr, cb, &names, H5P_DEFAULT) < 0)
      throw Error(m.where("cannot list group '" + group + "' (" + h5_detail() + ")"));
  });
  return names;
}

std::vector<std::string> H5File::attr_names(const std::string& object) const {
  const Impl& m = *impl_;
  std::vector<std::string> names;
  collective_try(m.comm, [&] {
    m.need_open();
    if (!link_exists(m.file, object)) throw Error(m.where("object '" + object + "' not found"));
    auto cb = [](hid_t, const char* name, const H5A_info_t*, void* data) -> herr_t {
      static_cast<std::vector<std::string>*>(data)->emplace_back(name);
      return 0;
    };
    if (H5Aiterate_by_name(m.file, object.c_str(), H5_INDEX_NAME, H5_ITER_INC, nullptr, cb, &names,
                           H5P_DEFAULT) < 0)
      throw Error(m.where("cannot list attributes of '" + object + "' (" + h5_detail() + ")"));
  });
  return names;
}

bool H5File::attr_is_string(const std::string& name) const {
  const Impl& m = *impl_;
  bool s = false;
  collective_try(m.comm, [&] {
    m.need_open();
    Hid a = m.open_attr(name);
    Hid t(H5Aget_type(a));
    s = H5Tget_class(t) == H5T_STRING;
  });
  return s;
}

void H5File::commit() {
  Impl& m = *impl_;
  std::string err;
  if (m.file < 0) throw Error(m.path + ": file already closed");
  if (m.mode == Mode::kCreate && m.rank == 0) {
    const std::string why = reserve_space(m.tmp, m.file);
    if (!why.empty()) err = "cannot write " + m.path + " (" + why + ")";
  }
  agree(m.comm, err);  // on error the destructor discards the file
  if (H5Fclose(m.file) < 0) {
    g_close_failed = true;
    err = "cannot write " + m.path + " (closing failed: " + h5_detail() + ")";
  }
  m.file = -1;
  agree(m.comm, err);
  if (m.mode != Mode::kCreate) return;
  if (m.rank == 0) {
    // Flush to disk before the rename, or a crash could leave an empty file under the final name.
    const int fd = ::open(m.tmp.c_str(), O_RDONLY);
    if (fd >= 0) {
      ::fsync(fd);
      ::close(fd);
    }
    if (std::rename(m.tmp.c_str(), m.path.c_str()) != 0)
      err = "cannot write " + m.path + " (rename from " + m.tmp + " failed: " + errno_text(errno) + ")";
  }
  agree(m.comm, err);  // also the barrier: nobody reads path before the rename
  m.committed = true;
}

}  // namespace snl
