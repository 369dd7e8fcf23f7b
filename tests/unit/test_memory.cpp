// ReuseFreedMemory (snl/core/memory.hpp): while alive, a large block comes from
// the heap and stays there when freed; afterwards glibc maps large blocks again
// and the free memory is returned.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

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

}  // namespace
