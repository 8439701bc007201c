#!/usr/bin/env python3
"""A/B benchmark of `shadowvol` binaries, alternated to cancel slow drifts of a shared machine.

Usage:
  python3 docs/scripts/abbench.py NAME=BINARY[,NAME=BINARY...] ROUNDS [--separate] [extra bench args...]

Each round runs, for every binary in turn, one call timing 1 and 4 lights (interleaved turns, the
bench's default schedule):
  BINARY bench --scene sphere-1m --backend simd --mode original,robust,ordered,exact \
         --frames 100 --lights 1,4 --format json [extra bench args...]
With --separate (for binaries older than `--lights 1,4`), two calls per round instead, one per
light count. It prints, per binary and light count, the median over the rounds of each mode's
`median_ms` (and of `floor_ms`), the ratios the issue-4 targets use (original/floor,
ordered/original, exact/original, robust/original, 4 lights / 1 light, the last both as a ratio of
the medians and as the median of the per-call ratios), and, for two binaries, the per-round
paired ratios second/first. Needs only the standard library.
"""
import collections
import json
import statistics
import subprocess
import sys

MODES = ["original", "robust", "ordered", "exact"]


def main() -> int:
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    bins = dict(a.split("=", 1) for a in sys.argv[1].split(","))
    rounds = int(sys.argv[2])
    extra = sys.argv[3:]
    separate = "--separate" in extra
    extra = [a for a in extra if a != "--separate"]
    res = collections.defaultdict(list)
    calls = [[1], [4]] if separate else [[1, 4]]
    for r in range(rounds):
        for name, binary in bins.items():
            for counts in calls:
                cmd = [binary, "bench", "--scene", "sphere-1m", "--backend", "simd",
                       "--mode", ",".join(MODES), "--frames", "100",
                       "--lights", ",".join(map(str, counts)), "--format", "json"] + extra
                d = json.loads(subprocess.run(cmd, capture_output=True, text=True,
                                              check=True).stdout)
                floors = {f["lights"]: f["floor_ms"] for f in d.get("floors", [])}
                if not floors:
                    floors = {counts[0]: d["floor_ms"]}
                for lights, f in floors.items():
                    res[(name, lights, "floor")].append(f)
                for rec in d["records"]:
                    res[(name, rec["lights"], rec["mode"])].append(rec["median_ms"])
        print(f"round {r + 1}/{rounds} done", file=sys.stderr, flush=True)
    med = {k: statistics.median(v) for k, v in res.items()}
    print("| build | lights | floor | " + " | ".join(MODES)
          + " | original/floor | ordered/original | exact/original | robust/original |")
    print("|---" * (7 + len(MODES)) + "|")
    for name in bins:
        for lights in (1, 4):
            m = {k: med[(name, lights, k)] for k in ["floor"] + MODES}
            print(f"| {name} | {lights} | {m['floor']:.3f} | "
                  + " | ".join(f"{m[k]:.3f}" for k in MODES)
                  + f" | {m['original'] / m['floor']:.2f} | {m['ordered'] / m['original']:.2f}"
                  + f" | {m['exact'] / m['original']:.2f} | {m['robust'] / m['original']:.2f} |")
    for name in bins:
        print(name, "4 lights / 1 light (ratio of medians):", ", ".join(
            f"{k} {med[(name, 4, k)] / med[(name, 1, k)]:.2f}" for k in MODES))
        print(name, "4 lights / 1 light (median of per-round ratios):", ", ".join(
            f"{k} {statistics.median(y / x for x, y in zip(res[(name, 1, k)], res[(name, 4, k)])):.2f}"
            for k in MODES))
    names = list(bins)
    if len(names) == 2:
        a, b = names
        for lights in (1, 4):
            for k in MODES:
                rr = [y / x for x, y in zip(res[(a, lights, k)], res[(b, lights, k)])]
                print(f"{b}/{a} {lights} light(s) {k}: median {statistics.median(rr):.3f}; "
                      "per round " + " ".join(f"{x:.2f}" for x in rr))
    return 0


if __name__ == "__main__":
    sys.exit(main())
