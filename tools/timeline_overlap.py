#!/usr/bin/env python3
"""How much of the GPU's busy time in a splitray timeline ran while the host did some
work: `tools/timeline_overlap.py TIMELINE.json [SPAN ...]`.

The GPU's busy time is the union of every GPU scope (all streams). Each named host span
(default: CBPT's CPU-thread work, `cbpt sample`, `cbpt light tracing`, `cbpt combine`)
is taken as the union of its slices; the script prints, per span name and for all of
them together, the span's own time, how much of it the GPU was busy, and that as a
share of the GPU's busy time and of the span's time. Only the standard library is used.
"""

import json
import sys

DEFAULT_SPANS = ["cbpt sample", "cbpt light tracing", "cbpt combine"]


def union(intervals):
    """Sorted, disjoint intervals covering `intervals`."""
    out = []
    for start, end in sorted(intervals):
        if out and start <= out[-1][1]:
            out[-1][1] = max(out[-1][1], end)
        else:
            out.append([start, end])
    return out


def length(intervals):
    return sum(end - start for start, end in intervals)


def intersection(a, b):
    """The length of the intersection of two sorted, disjoint interval lists."""
    i = j = 0
    total = 0.0
    while i < len(a) and j < len(b):
        lo = max(a[i][0], b[j][0])
        hi = min(a[i][1], b[j][1])
        if hi > lo:
            total += hi - lo
        if a[i][1] < b[j][1]:
            i += 1
        else:
            j += 1
    return total


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    path = argv[1]
    names = argv[2:] or DEFAULT_SPANS
    try:
        with open(path) as f:
            events = json.load(f)["traceEvents"]
    except (OSError, ValueError, KeyError) as e:
        sys.exit(f"{path}: not a splitray timeline ({e})")
    gpu_pids = {
        e["pid"]
        for e in events
        if e.get("ph") == "M"
        and e.get("name") == "process_name"
        and e["args"]["name"].startswith("GPU")
    }
    slices = [e for e in events if e.get("ph") == "X"]
    gpu = union((e["ts"], e["ts"] + e["dur"]) for e in slices if e["pid"] in gpu_pids)
    gpu_ms = length(gpu) / 1e3
    print(f"{path}: GPU busy {gpu_ms:.1f} ms")
    every = []
    for name in names + ["all of them"]:
        if name == "all of them":
            spans = union(every)
        else:
            found = [
                (e["ts"], e["ts"] + e["dur"])
                for e in slices
                if e["pid"] not in gpu_pids and e["name"] == name
            ]
            every += found
            spans = union(found)
        own = length(spans) / 1e3
        both = intersection(gpu, spans) / 1e3
        print(
            f"  {name:<20} {own:9.1f} ms, GPU busy during {both:9.1f} ms "
            f"({100 * both / max(gpu_ms, 1e-9):5.1f}% of the GPU's busy time, "
            f"{100 * both / max(own, 1e-9):5.1f}% of the span's)"
        )


if __name__ == "__main__":
    main(sys.argv)
