// The cost of memory the process has not touched before, against memory it
// has: maps SIZE GiB, writes it twice (memset), unmaps; the first write takes
// every page fault (and, in a VM, the host's backing of the page), the second
// runs at the write bandwidth. With `hugepage` the mapping is advised
// MADV_HUGEPAGE first (what glibc.malloc.hugetlb=1 does for malloc's
// mappings, snl/core/memory.hpp). Every repetition is printed:
//   first_touch [hugepage] SIZE_GIB REPS
//   rep R mode M first_gbs X second_gbs Y
#include <sys/mman.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

int main(int argc, char** argv) {
  int a = 1;
  const bool huge = argc > a && std::string(argv[a]) == "hugepage";
  if (huge) ++a;
  const double gib = argc > a ? std::atof(argv[a]) : 4.0;
  const int reps = argc > a + 1 ? std::atoi(argv[a + 1]) : 3;
  const auto bytes = static_cast<std::size_t>(gib * (1u << 30));
  auto now = [] { return std::chrono::steady_clock::now(); };
  for (int r = 0; r < reps; ++r) {
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) {
      std::perror("mmap");
      return 1;
    }
    if (huge) madvise(p, bytes, MADV_HUGEPAGE);
    const auto t0 = now();
    std::memset(p, 1, bytes);
    const auto t1 = now();
    std::memset(p, 2, bytes);
    const auto t2 = now();
    const double first = std::chrono::duration<double>(t1 - t0).count();
    const double second = std::chrono::duration<double>(t2 - t1).count();
    std::printf("rep %d mode %s first_gbs %.2f second_gbs %.2f\n", r, huge ? "hugepage" : "4k", bytes / first / 1e9,
                bytes / second / 1e9);
    munmap(p, bytes);
  }
  return 0;
}
