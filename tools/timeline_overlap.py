#!/usr/bin/env python3
"""How much of the GPU's busy time in a splitray timeline ran while the host did some
work: `tools/timeline_overlap.py TIMELINE.json [--within SPAN] [SPAN ...]`.

The GPU's busy time is the union of every GPU scope (all streams). Each named host span
(default: CBPT's CPU-thread work, `cbpt sample`, `cbpt light tracing`, `cbpt combine`)
is taken as the union of its slices; the script prints, per span name and for all of
them together, the span's own time, how much of it the GPU was busy, and that as a
share of the GPU's busy time and of the span's time. `--within SPAN` counts only what
falls inside the host spans of that name (e.g. `cbpt steps pipelined`, the step loops of
CBPT with two couples in flight; `cbpt steps synchronous`, without). Only the standard
library is used.
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


def clip(intervals, window):
    """`intervals` cut to `window` (both sorted and disjoint): their intersection."""
    out = []
    i = j = 0
    while i < len(intervals) and j < len(window):
        lo = max(intervals[i][0], window[j][0])
        hi = min(intervals[i][1], window[j][1])
        if hi > lo:
            out.append([lo, hi])
        if intervals[i][1] < window[j][1]:
            i += 1
        else:
            j += 1
    return out


def length(intervals):
    return sum(end - start for start, end in intervals)


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    path = argv[1]
    names = argv[2:]
    within = None
    if names[:1] == ["--within"]:
        if len(names) < 2:
            sys.exit("--within needs a span name")
        within, names = names[1], names[2:]
    names = names or DEFAULT_SPANS
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
    host = [e for e in slices if e["pid"] not in gpu_pids]
    window = None
    if within is not None:
        window = union((e["ts"], e["ts"] + e["dur"]) for e in host if e["name"] == within)
        if not window:
            sys.exit(f"{path}: no host span named '{within}'")

    def spans_of(events):
        spans = union((e["ts"], e["ts"] + e["dur"]) for e in events)
        return spans if window is None else clip(spans, window)

    gpu = spans_of(e for e in slices if e["pid"] in gpu_pids)
    gpu_ms = length(gpu) / 1e3
    inside = "" if window is None else f" inside '{within}' ({length(window) / 1e3:.1f} ms)"
    print(f"{path}: GPU busy {gpu_ms:.1f} ms{inside}")
    every = []
    for name in names + ["all of them"]:
        if name == "all of them":
            spans = spans_of(every)
        else:
            found = [e for e in host if e["name"] == name]
            every += found
            spans = spans_of(found)
        own = length(spans) / 1e3
        both = length(clip(gpu, spans)) / 1e3
        print(
            f"  {name:<20} {own:9.1f} ms, GPU busy during {both:9.1f} ms "
            f"({100 * both / max(gpu_ms, 1e-9):5.1f}% of the GPU's busy time, "
            f"{100 * both / max(own, 1e-9):5.1f}% of the span's)"
        )


if __name__ == "__main__":
    main(sys.argv)
