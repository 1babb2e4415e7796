#!/usr/bin/env python3
"""Summarises scripts/ab_bench.sh output: per estimator, the baseline's median samples per
CPU-second and, per other variant, its median and the median (min-max) over rounds of
its ratio to the baseline in the same round.

Usage: python3 scripts/ab_summary.py AB_OUTPUT [BASELINE_NAME (default: base)]
"""
import collections
import statistics
import sys


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    base = sys.argv[2] if len(sys.argv) > 2 else "base"
    runs = collections.defaultdict(lambda: collections.defaultdict(dict))
    with open(sys.argv[1]) as f:
        for line in f:
            parts = line.split()
            if len(parts) != 4:
                continue
            name, rnd, algo, value = parts
            runs[algo][name][int(rnd)] = float(value)
    for algo, variants in runs.items():
        if base not in variants:
            print(f"{algo}: no baseline {base!r}")
            continue
        b = variants[base]
        print(f"{algo}: {base} median {statistics.median(b.values()):.0f}")
        for name, rounds in variants.items():
            if name == base:
                continue
            ratios = [v / b[r] for r, v in rounds.items() if r in b]
            if ratios:
                print(
                    f"   {name}: median {statistics.median(rounds.values()):.0f}  "
                    f"ratio median {statistics.median(ratios):.3f} "
                    f"range {min(ratios):.3f}-{max(ratios):.3f} n={len(ratios)}"
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
