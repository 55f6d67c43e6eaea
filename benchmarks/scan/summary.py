"""Medians of benchmarks/scan/bench.sh's output: per case and build, the figures the shared
workgroup scan could move, old against new; and rain's step with its splashes reported
against without. Usage: python3 benchmarks/scan/summary.py OUT_DIR"""
import json
import statistics
import sys
from collections import defaultdict

out = sys.argv[1]
rows = [json.loads(l) for l in open(f"{out}/scan-ab.jsonl") if l.strip()]


def figures(r):
    case = r["case"]
    if case == "sort":
        f = {"depth sort ms": r["sort_stages_ms"]["sort"]}
        for s in r["sort_alone"]:
            f[f"{s['key_bits']}-bit pairs ms ({s.get('ranking', '')})"] = s["ms"]
        return f
    if case.startswith("events"):
        return {"step ms": r["ms_per_step"], "plain step ms": r["plain_ms_per_step"]}
    if case.startswith("splat"):
        d = r["draw"]
        return {k: v for k, v in d.items() if isinstance(v, (int, float)) and k.endswith("ms")}
    if case == "flock":
        return {"step ms": r["ms_per_step"]}
    return {}


table = defaultdict(lambda: defaultdict(list))
for r in rows:
    for name, v in figures(r).items():
        table[(r["case"], name)][r["build"]].append(v)
print(f"{'case':<18} {'figure':<40} {'old':>10} {'new':>10} {'new/old':>8}")
for (case, name), by in sorted(table.items()):
    old, new = statistics.median(by["old"]), statistics.median(by["new"])
    print(f"{case:<18} {name:<40} {old:>10.4f} {new:>10.4f} {new / old:>8.3f}")
rep = defaultdict(list)
for l in open(f"{out}/reports.jsonl"):
    if l.strip():
        r = json.loads(l)
        rep[r["case"]].append(r["ms_per_step"])
if rep:
    a, b = statistics.median(rep["rain"]), statistics.median(rep["rain-reported"])
    print(f"rain 10M step: {a:.4f} ms; with its splashes reported: {b:.4f} ms ({b / a:.3f}x)")
