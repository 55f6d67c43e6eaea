"""Medians of benchmarks/update-builds/bench.sh's output: each build's update step and its
ratio to the copy kernel's bandwidth, and each build's step with events against without.
Usage: python3 summary.py OUT"""
import collections
import json
import statistics
import sys

out = sys.argv[1]
rows = [json.loads(line) for line in open(f"{out}/update.jsonl")]
by = collections.defaultdict(list)
for r in rows:
    x = r["result"]
    if x is not None:
        by[(x["effect"], x["particles"], r["build"])].append(x)
print(f"{'effect':28} {'N':>10} {'build':24} {'ms/step':>9} {'of copy':>8}")
for (effect, n, build), v in sorted(by.items()):
    ms = statistics.median(x["ms_per_step"] for x in v)
    ratio = statistics.median(x["ratio"] for x in v)
    print(f"{effect:28} {n:>10} {build:24} {ms:9.4f} {ratio:8.3f}")
rows = [json.loads(line) for line in open(f"{out}/events.jsonl")]
by = collections.defaultdict(list)
for r in rows:
    x = r["result"]
    if x is not None:
        by[(x["effect"], r["build"])].append(x)
print(f"\n{'effect':28} {'build':24} {'with events':>12} {'without':>9} {'ratio':>6}")
for (effect, build), v in sorted(by.items()):
    step = statistics.median(x["ms_per_step"] for x in v)
    plain = statistics.median(x["plain_ms_per_step"] for x in v)
    print(f"{effect:28} {build:24} {step:12.4f} {plain:9.4f} {step / plain:6.3f}")
