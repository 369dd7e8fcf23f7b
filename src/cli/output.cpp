// Output files of the subcommands: the path checks made before any work, and
// atomic writes (a temporary file renamed over the target on success only).
#include <sys/stat.h>
#include <climits>
#include <cstdlib>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "cli/cli_util.hpp"
#include "core/json.hpp"
#include "snl/cli/commands.hpp"

namespace snl {

namespace {

std::string dir_of(const std::string& path) {
  const auto s = path.find_last_of('/');
  if (s == std::string::npos) return ".";
  if (s == 0) return "/";
  return path.substr(0, s);
}

}  // namespace

namespace detail {

std::string read_text_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw Error(path + ": cannot open (" + std::strerror(errno) + ")");
  std::string text;
  char buf[1 << 16];
  std::size_t k = 0;
  while ((k = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, k);
  const int err = std::ferror(f) ? errno : 0;
  std::fclose(f);
  if (err != 0) throw Error(path + ": cannot read (" + std::strerror(err) + ")");
  return text;
}

std::string fmt(double v, int prec) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", prec, v);
  return b;
}

void write_text_on_root(const std::string& path, const std::string& text, MPI_Comm comm) {
  std::string err;
  if (is_root(comm)) {
    try {
      write_text_atomic(path, text);
    } catch (const std::exception& e) {
      err = e.what();
    }
  }
  agree(comm, err);
}

}  // namespace detail

void write_text_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp-" + std::to_string(getpid());
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw Error(path + ": cannot create file (" + std::strerror(errno) + ")");
    f << text;
    f.flush();
    if (!f) {
      std::remove(tmp.c_str());
      throw Error(path + ": write failed (disk full?)");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw Error(path + ": cannot rename temporary file (" + why + ")");
  }
}

namespace {
// Whether a and b name one file: the same inode where both exist, else the
// same name in the same directory.
bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  const bool ea = stat(a.c_str(), &sa) == 0, eb = stat(b.c_str(), &sb) == 0;
  if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (ea != eb) return false;
  auto canon = [](const std::string& p) {
    const std::size_t slash = p.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : p.substr(0, slash + 1);
    char buf[PATH_MAX];
    const std::string d = realpath(dir.c_str(), buf) ? std::string(buf) : dir;
    return d + "/" + (slash == std::string::npos ? p : p.substr(slash + 1));
  };
  return canon(a) == canon(b);
}
}  // namespace

void check_output_path(const std::string& path, MPI_Comm comm, const std::vector<OtherFile>& others) {
  std::string err;
  if (detail::is_root(comm)) {
    const std::string d = dir_of(path);
    if (path.empty())
      err = "empty output path";
    else if (access(d.c_str(), F_OK) != 0)
      err = path + ": directory '" + d + "' does not exist";
    else if (access(d.c_str(), W_OK) != 0)
      err = path + ": directory '" + d + "' is not writable";
    else if (access(path.c_str(), F_OK) == 0 && access(path.c_str(), W_OK) != 0)
      err = path + ": file exists and is not writable";
    else if (struct stat st {}; stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
      err = path + (S_ISDIR(st.st_mode) ? ": is a directory"
                                        : ": exists and is not a regular file (e.g. a device); refusing to replace it");
    for (const auto& o : others)
      if (err.empty() && !o.path.empty() && same_file(path, o.path))
        err = path + ": names the same file as " + o.role + " (" + o.path + "); refusing to overwrite it";
  }
  agree(comm, err);
}

}  // namespace snl
