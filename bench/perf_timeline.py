#!/usr/bin/python3
"""Per second of a `perf record -g` profile: the samples, those in the kernel's
page clearing (the first touch of fresh memory), and the user frames those
came from, so that the clearing can be placed in the run's phases.

    perf script -i perf0.data -F time,ip,sym > perf0.txt
    /usr/bin/python3 bench/perf_timeline.py perf0.txt

One line per second from the first sample: `second samples clearing [(frame, count), ...]`,
then the total clearing share.
"""
import collections
import re
import sys

KERNEL_CLEAR = "clear_page"


def samples(path):
    cur = None
    with open(path) as f:
        for line in f:
            m = re.match(r"\s*(\d+\.\d+):", line)
            if m:
                if cur:
                    yield cur
                cur = (float(m.group(1)), [])
                continue
            s = line.strip()
            if s and cur is not None:
                ip, _, sym = s.partition(" ")
                cur[1].append((ip, sym.strip()))
    if cur:
        yield cur


def user_frame(stack):
    """The first frame that names a function of the program or its libraries."""
    for ip, sym in stack:
        if ip.startswith("ffffffff") or not sym or sym.startswith("["):
            continue  # a kernel function, or an unknown one
        return sym[:70]
    return "?"


def main():
    every = collections.Counter()
    clearing = collections.Counter()
    frames = collections.defaultdict(collections.Counter)
    t0 = None
    for t, stack in samples(sys.argv[1]):
        t0 = t if t0 is None else t0
        b = int(t - t0)
        every[b] += 1
        if stack and KERNEL_CLEAR in stack[0][1]:
            clearing[b] += 1
            frames[b][user_frame(stack)] += 1
    for b in sorted(every):
        print(b, every[b], clearing[b], frames[b].most_common(2))
    total = sum(every.values())
    print(f"# clearing: {sum(clearing.values())} of {total} samples ({100.0 * sum(clearing.values()) / max(total, 1):.1f}%)")


if __name__ == "__main__":
    main()
