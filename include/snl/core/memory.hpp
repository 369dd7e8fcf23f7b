#pragma once
// How the process takes memory from the system. The setup allocates and frees
// several gigabytes at 10M sensors; on hosts where the first touch of a page is
// costly (0.6-1.0 GB/s on this project's VMs against 21 GB/s for a second
// write, docs/performance.md "Memory first touch") that, not the arithmetic,
// set about 40% of its time.

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

}  // namespace snl
