// ReuseFreedMemory (snl/core/memory.hpp): while alive, a large block comes from
// the heap and stays there when freed; afterwards glibc maps large blocks again
// and the free memory is returned. MappedAllocator's blocks stay out of the heap.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <vector>

#include "snl/core/memory.hpp"

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
#include <malloc.h>
#define SNL_TEST_GLIBC_MALLOC 1
#endif

namespace {

#if defined(SNL_TEST_GLIBC_MALLOC)
constexpr std::size_t kBig = std::size_t(64) << 20;  // far above glibc's largest mmap threshold (32 MiB)
// Through volatile pointers, so that the compiler cannot drop the pair.
void* (*volatile big_alloc)(std::size_t) = std::malloc;
void (*volatile big_free)(void*) = std::free;

void* touch(void* p) {
  std::memset(p, 1, kBig);
  return p;
}
#endif

TEST(Memory, ReuseFreedMemoryKeepsLargeBlocksInTheHeap) {
#if !defined(SNL_TEST_GLIBC_MALLOC)
  GTEST_SKIP() << "not glibc's allocator (a sanitizer build or another C library)";
#else
  unsetenv("SNL_MALLOC");
  std::size_t held = 0;  // the heap's size at the end of the scope
  {
    const snl::ReuseFreedMemory reuse;
    const struct mallinfo2 before = mallinfo2();
    void* p = touch(big_alloc(kBig));
    const struct mallinfo2 during = mallinfo2();
    EXPECT_EQ(during.hblkhd, before.hblkhd) << "a large block was mapped while freed memory is to be reused";
    big_free(p);
    const struct mallinfo2 freed = mallinfo2();
    EXPECT_GE(freed.fordblks, before.fordblks + kBig) << "the freed block did not stay in the heap";
    void* q = touch(big_alloc(kBig));  // reuses it: the heap does not grow
    EXPECT_LE(mallinfo2().arena, freed.arena);
    big_free(q);
    held = mallinfo2().arena;
  }
  const struct mallinfo2 base = mallinfo2();
  EXPECT_LE(base.arena + kBig / 2, held) << "the free memory was not returned at the end";
  void* r = touch(big_alloc(kBig));
  EXPECT_GE(mallinfo2().hblkhd, base.hblkhd + kBig) << "large blocks are not mapped again after the scope";
  big_free(r);
#endif
}

TEST(Memory, SystemOptOutLeavesTheAllocatorAlone) {
#if !defined(SNL_TEST_GLIBC_MALLOC)
  GTEST_SKIP() << "not glibc's allocator (a sanitizer build or another C library)";
#else
  setenv("SNL_MALLOC", "system", 1);
  {
    const snl::ReuseFreedMemory reuse;
    const struct mallinfo2 before = mallinfo2();
    void* p = touch(big_alloc(kBig));
    EXPECT_GE(mallinfo2().hblkhd, before.hblkhd + kBig) << "SNL_MALLOC=system: the block should be mapped";
    big_free(p);
  }
  unsetenv("SNL_MALLOC");
#endif
}

TEST(Memory, MappedAllocatorKeepsItsBlocksOutOfTheHeap) {
  // Any C library: too large a count is refused, and an empty block is a block.
  snl::MappedAllocator<double> alloc;
  EXPECT_THROW(alloc.allocate(SIZE_MAX / 4), std::bad_alloc);
  double* e = alloc.allocate(0);
  EXPECT_NE(e, nullptr);
  alloc.deallocate(e, 0);
#if !defined(SNL_TEST_GLIBC_MALLOC)
  GTEST_SKIP() << "not glibc's allocator (a sanitizer build or another C library): the heap is not observed";
#else
  unsetenv("SNL_MALLOC");
  const snl::ReuseFreedMemory reuse;  // malloc maps nothing now: what it gives comes from the heap
  const struct mallinfo2 before = mallinfo2();
  {
    std::vector<char, snl::MappedAllocator<char>> v(kBig, 1);
    EXPECT_EQ(v[kBig - 1], 1);
    const struct mallinfo2 during = mallinfo2();
    EXPECT_LT(during.uordblks, before.uordblks + kBig / 2) << "the mapped vector came from the heap";
    EXPECT_LT(during.arena, before.arena + kBig / 2) << "the mapped vector grew the heap";
  }
  {  // the control: the same vector with the default allocator does come from the heap
    std::vector<char> w(kBig, 1);
    EXPECT_GE(mallinfo2().uordblks, before.uordblks + kBig);
  }
#endif
}

}  // namespace
