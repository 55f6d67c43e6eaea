#!/usr/bin/env python3
"""Table of benchmarks/meshes/indexed-bench.sh's output: each build's raster draw of the lit and
unlit 200-triangle spheres, per round, and new over old.
python3 benchmarks/meshes/indexed-summary.py OUT/indexed.jsonl"""
import json
import sys

rows = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
print(rows[0].get("adapter", "?"))
print(f"{'effect':18} {'round':>5} {'old ms':>9} {'new ms':>9} {'new/old':>8}")
for effect in sorted({r["effect"] for r in rows}):
    for rnd in sorted({r["round"] for r in rows}):
        ms = {r["build"]: r["draw"]["ms"] for r in rows if r["effect"] == effect and r["round"] == rnd}
        name = effect.rsplit("/", 1)[-1]
        print(f"{name:18} {rnd:>5} {ms['old']:9.3f} {ms['new']:9.3f} {ms['new'] / ms['old']:8.3f}")
