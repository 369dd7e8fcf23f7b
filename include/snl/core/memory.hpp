#pragma once
// How the process takes memory from the system. The setup allocates and frees
// several gigabytes at 10M sensors; on hosts where the first touch of a page is
// costly (far slower than a second write, docs/performance.md "Machine and
// yardstick") that, not the arithmetic, sets much of its time.

#include <cstddef>
#include <new>

namespace snl {

/// At the very start of main, before MPI_Init: unless the environment already
/// chooses (GLIBC_TUNABLES names glibc.malloc.hugetlb) or SNL_MALLOC=system
/// opts out, re-executes the program with glibc.malloc.hugetlb=1 added to
/// GLIBC_TUNABLES, so that malloc asks for transparent huge pages on the memory
/// it maps (one fault per 2 MiB instead of per 4 KiB). Returns only when no
/// re-execution happened (not glibc, already tuned, opted out, exec failed).
void tune_allocator(char** argv);

/// Why SNL_MALLOC cannot be honoured (a value other than unset, empty,
/// "hugetlb" or "system"), or nullptr when it can. snl refuses to start then.
const char* allocator_choice_error();

/// Whether this process runs with glibc.malloc.hugetlb set ("hugetlb") or not
/// ("system"); for the solve's JSON.
const char* allocator_mode();

/// Returns malloc's free memory to the system (glibc: malloc_trim, which also
/// releases the pages of free blocks inside the heap); no effect elsewhere.
void return_free_memory();

/// While alive, freed memory stays in the process for reuse instead of going
/// back to the system (glibc: no mmap for large blocks, no trimming), so that
/// the setup's temporaries fault their pages once; on destruction the defaults
/// are restored and the free memory is returned (malloc_trim). With the
/// huge-page tunable it costs 24% of peak resident memory at 10M sensors on 2
/// ranks (fragmentation) and cuts the setup 2.7-4 times (docs/performance.md,
/// "Inputs freed as soon as they are copied"). No effect without glibc or with SNL_MALLOC=system.
class ReuseFreedMemory {
 public:
  ReuseFreedMemory();
  ~ReuseFreedMemory();
  ReuseFreedMemory(const ReuseFreedMemory&) = delete;
  ReuseFreedMemory& operator=(const ReuseFreedMemory&) = delete;

 private:
  bool active_;
};

/// Pages mapped straight from the system (mmap), apart from malloc's heap;
/// throws std::bad_alloc when they cannot be. For MappedAllocator.
void* map_pages(std::size_t bytes);
void unmap_pages(void* p, std::size_t bytes) noexcept;

/// An allocator whose blocks are mapped apart from malloc's heap: for arrays
/// that outlive the setup's temporaries (the owner directory). In the heap
/// such an array sits between blocks that are freed around it and splits
/// their room in two, too small each for a later, larger temporary, which then
/// takes fresh memory: at 10M sensors on 2 ranks the directory's 38 MiB cut
/// 1381 MiB of freed room into 446 and 897, and the 915.5 MiB of the neighbour
/// lists' entries grew the heap (docs/performance.md).
template <class T>
struct MappedAllocator {
  using value_type = T;
  MappedAllocator() = default;
  template <class U>
  MappedAllocator(const MappedAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(map_pages(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { unmap_pages(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const MappedAllocator<U>&) const noexcept { return true; }
  template <class U>
  bool operator!=(const MappedAllocator<U>&) const noexcept { return false; }
};

}  // namespace snl
