"""Medians of benchmarks/lit/bench.sh's lit.jsonl: each effect's raster draw and compute renderer
at 1M particles, 1280x720, and their ratios to the unlit smoke of the same run.
Usage: python3 summary.py LIT.JSONL"""
import collections
import json
import statistics
import sys

rows = [json.loads(line) for line in open(sys.argv[1])]
by = collections.defaultdict(list)
for r in rows:
    # Files written by older builds name the compute renderer's time splat_ms.
    by[r["effect"]].append((r["draw"]["ms"], r["draw"].get("compute_ms", r["draw"].get("splat_ms"))))
base = by["benchmarks/lit/smoke-unlit.ron"] if "benchmarks/lit/smoke-unlit.ron" in by else next(
    v for k, v in by.items() if k.endswith("smoke-unlit.ron"))
med = lambda v, i: statistics.median(x[i] for x in v)
print(f"{'effect':42} {'raster ms':>10} {'ratio':>6} {'splat ms':>9} {'ratio':>6}")
for k, v in by.items():
    print(f"{k:42} {med(v, 0):10.2f} {med(v, 0) / med(base, 0):6.2f} {med(v, 1):9.3f} {med(v, 1) / med(base, 1):6.2f}")
