#!/usr/bin/env python3
"""Table of benchmarks/meshes/compute-bench.sh's output: each effect's raster draw and compute
renderer, per round, the compute renderer's stages, and compute over raster.
python3 benchmarks/meshes/compute-summary.py OUT/compute.jsonl"""
import json
import sys

rows = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
print(rows[0].get("adapter", "?"))
print(f"{'effect':18} {'round':>5} {'raster ms':>10} {'compute ms':>11} {'compute/raster':>15}  stages (ms)")
for r in rows:
    d = r["draw"]
    name = r["effect"].rsplit("/", 1)[-1]
    stages = ", ".join(f"{k} {v:.3f}" for k, v in (d.get("compute_stages_ms") or {}).items())
    compute = d.get("compute_ms")
    if compute is None:
        print(f"{name:18} {r['round']:>5} {d['ms']:10.3f} {'-':>11} {'-':>15}")
        continue
    print(f"{name:18} {r['round']:>5} {d['ms']:10.3f} {compute:11.3f} {compute / d['ms']:15.3f}  {stages}")
