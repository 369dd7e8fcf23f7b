// An LD_PRELOAD shim that logs every allocation and free of at least 16 MiB
// with its address and the heap's top (sbrk(0)) after it, one file per MPI
// rank: where the setup's heap grows, and which buffers reuse freed ones
// (docs/performance.md, "Rows that stay on their rank"). Built with
// -DSNL_BUILD_BENCH=ON; bench/heap_growth.py reads the logs.
//   mpirun -np 2 -x LD_PRELOAD=build-bench/bin/libmalloc_trace.so
//     -x MALLOC_TRACE_OUT=W/heap snl solve ...     (logs W/heap.<rank>)
#include <dlfcn.h>
#include <fcntl.h>
#include <malloc.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace {
using MallocFn = void* (*)(std::size_t);
using FreeFn = void (*)(void*);
using ReallocFn = void* (*)(void*, std::size_t);
MallocFn real_malloc = nullptr;
FreeFn real_free = nullptr;
ReallocFn real_realloc = nullptr;
int out = -1;  // -1: not opened yet, -2: no output
constexpr std::size_t kBig = std::size_t(16) << 20;

void init() {
  real_malloc = reinterpret_cast<MallocFn>(dlsym(RTLD_NEXT, "malloc"));
  real_free = reinterpret_cast<FreeFn>(dlsym(RTLD_NEXT, "free"));
  real_realloc = reinterpret_cast<ReallocFn>(dlsym(RTLD_NEXT, "realloc"));
}

void log_line(char what, void* p, std::size_t n) {
  if (out == -1) {
    const char* path = std::getenv("MALLOC_TRACE_OUT");
    const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
    char name[4096];
    out = -2;
    if (path && std::snprintf(name, sizeof name, "%s.%s", path, rank ? rank : "0") < static_cast<int>(sizeof name))
      out = open(name, O_WRONLY | O_CREAT | O_TRUNC, 0644);  // (open, not fopen: no allocation in here)
    if (out < 0) out = -2;
  }
  if (out < 0) return;
  char buf[128];
  const int len = std::snprintf(buf, sizeof buf, "%c %p %zu top %p\n", what, p, n, sbrk(0));
  if (len > 0 && write(out, buf, static_cast<std::size_t>(len)) < 0) out = -2;
}
}  // namespace

extern "C" {
void* malloc(std::size_t n) {
  if (!real_malloc) init();
  void* p = real_malloc(n);
  if (n >= kBig) log_line('M', p, n);
  return p;
}
void* realloc(void* q, std::size_t n) {
  if (!real_malloc) init();
  void* p = real_realloc(q, n);
  if (n >= kBig) log_line('R', p, n);
  return p;
}
void free(void* p) {
  if (!real_malloc) init();
  if (p) {
    const std::size_t n = malloc_usable_size(p);
    if (n >= kBig) log_line('F', p, n);
  }
  real_free(p);
}
}
