#include "snl/core/memory.hpp"

#include <sys/mman.h>

#include <cstdlib>
#include <cstring>
#include <new>
#include <string>

// glibc's malloc is the one tuned; a sanitizer replaces it with its own.
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
#define SNL_GLIBC_MALLOC 1
#include <malloc.h>
#include <unistd.h>
#endif

namespace snl {

namespace {
constexpr const char* kHugetlb = "glibc.malloc.hugetlb";
bool has_hugetlb(const char* tunables) { return tunables && std::strstr(tunables, kHugetlb) != nullptr; }
// Whether GLIBC_TUNABLES sets glibc.malloc.hugetlb to a non-zero value.
bool hugetlb_on(const char* tunables) {
  const char* at = tunables ? std::strstr(tunables, kHugetlb) : nullptr;
  if (!at) return false;
  at += std::strlen(kHugetlb);
  return *at == '=' && at[1] != '\0' && at[1] != '0';
}
// The environment this process started with (tune_allocator records it before
// it adds the tunable; -1: not recorded, read the environment).
int started_with_hugetlb = -1;
bool opted_out() {
  const char* opt = std::getenv("SNL_MALLOC");
  return opt && std::strcmp(opt, "system") == 0;
}
}  // namespace

void tune_allocator(char** argv) {
#if defined(SNL_GLIBC_MALLOC)
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  started_with_hugetlb = hugetlb_on(tunables) ? 1 : 0;
  if (opted_out()) return;
  if (has_hugetlb(tunables) || std::getenv("SNL_MALLOC_REEXEC")) return;  // chosen, or already tried once
  std::string t = tunables && *tunables ? std::string(tunables) + ":" : std::string();
  t += "glibc.malloc.hugetlb=1";
  if (setenv("GLIBC_TUNABLES", t.c_str(), 1) != 0 || setenv("SNL_MALLOC_REEXEC", "1", 1) != 0) return;
  // The binary's own path, not /proc/self/exe: the process name (ps, pkill,
  // a batch system's tracking) is the basename of the path executed.
  char self[4096];
  const ssize_t len = readlink("/proc/self/exe", self, sizeof self - 1);
  if (len <= 0) return;
  self[len] = '\0';
  execv(self, argv);
  // exec failed: run untuned; the guard stays set for children.
#else
  (void)argv;
#endif
}

const char* allocator_choice_error() {
  const char* opt = std::getenv("SNL_MALLOC");
  if (!opt || !*opt || std::strcmp(opt, "system") == 0 || std::strcmp(opt, "hugetlb") == 0) return nullptr;
  return "SNL_MALLOC must be 'hugetlb' (the default) or 'system'";
}

const char* allocator_mode() {
#if defined(SNL_GLIBC_MALLOC)
  const bool on = started_with_hugetlb < 0 ? hugetlb_on(std::getenv("GLIBC_TUNABLES")) : started_with_hugetlb == 1;
  return on ? "hugetlb" : "system";
#else
  return "other";  // a sanitizer's or another C library's allocator
#endif
}

ReuseFreedMemory::ReuseFreedMemory() : active_(!opted_out()) {
#if defined(SNL_GLIBC_MALLOC)
  if (!active_) return;
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, -1);  // mallopt(3): -1 disables trimming
#endif
}

ReuseFreedMemory::~ReuseFreedMemory() {
#if defined(SNL_GLIBC_MALLOC)
  if (!active_) return;
  // glibc's documented defaults (mallopt(3)); the dynamic mmap threshold is
  // not re-enabled, so blocks of 128 KiB and more are mapped from here on.
  mallopt(M_MMAP_MAX, 65536);
  mallopt(M_TRIM_THRESHOLD, 128 * 1024);
#endif
  if (active_) return_free_memory();
}

void return_free_memory() {
#if defined(SNL_GLIBC_MALLOC)
  malloc_trim(0);
#endif
}

void* map_pages(std::size_t bytes) {
  if (bytes == 0) bytes = 1;  // an empty request still gets a page of its own: a unique pointer
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  return p;
}

void unmap_pages(void* p, std::size_t bytes) noexcept {
  if (p) munmap(p, bytes == 0 ? 1 : bytes);
}

}  // namespace snl
