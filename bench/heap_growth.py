#!/usr/bin/python3
"""Reads a bench/malloc_trace.cpp log (one rank's) and prints each large
allocation and free with its place relative to the heap's first block and
the heap's top after it, marking the allocations that grew the heap (fresh
pages) and summing them. Blocks outside the heap (mmap: those made before
the setup's ReuseFreedMemory scope) show as 'mmap'.
  /usr/bin/python3 bench/heap_growth.py W/heap.0
"""
import sys

MIB = 2.0 ** 20

def main(path):
    base = prev_top = None
    grown = 0.0
    peak = 0.0
    for line in open(path):
        what, p, n, _, top = line.split()
        p, n, top = int(p, 16), int(n), int(top, 16)
        in_heap = p < top  # below the program break; mmap'd blocks lie far above it
        if base is None and in_heap:
            base = p
            prev_top = p
        where = f"{(p - base) / MIB:8.1f}" if (in_heap and base is not None) else "    mmap"
        note = ""
        if base is not None and prev_top is not None and top != prev_top:
            d = (top - prev_top) / MIB
            note = f"heap {d:+.0f} MiB"
            if d > 0:
                grown += d
        if base is not None:
            prev_top = top
            peak = max(peak, (top - base) / MIB)
        top_rel = (top - base) / MIB if base is not None else 0.0
        print(f"{what} {n / MIB:8.1f} MiB at {where}  top {top_rel:8.1f}  {note}")
    print(f"# heap grown by {grown:.0f} MiB in all; its top at most {peak:.0f} MiB above its first block")


if __name__ == "__main__":
    main(sys.argv[1])
