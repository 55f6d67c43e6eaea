#!/usr/bin/env python3
"""Prints the issue goals' figures from one device call's output folder (docs/performance.md):
OUT/splat/splat.jsonl (splat-bench.sh), OUT/speed/{sort.jsonl,torch.txt,flock.jsonl}
(speed-bench.sh ... sort,flock) and OUT/events/*.json (events-bench.sh).
Usage: python3 benchmarks/goals-summary.py OUT"""
import json
import pathlib
import sys

out = pathlib.Path(sys.argv[1])


def rounded(stages):
    return {k: round(v, 4) for k, v in sorted((stages or {}).items())}


for line in (out / "splat/splat.jsonl").open():
    d = json.loads(line)
    draw = d["draw"]
    print(
        pathlib.Path(d["effect"]).name, d["particles"], "raster", round(draw["ms"], 2),
        "compute", round(draw.get("compute_ms", draw.get("splat_ms")) or 0, 3), "prep", draw["prepare_ms"] and round(draw["prepare_ms"], 3),
        rounded(draw.get("compute_stages_ms", draw.get("splat_stages_ms"))),
    )
for line in (out / "speed/sort.jsonl").open():
    d = json.loads(line)
    alone = [(s["ranking"], s["key_bits"], round(s["ms"], 4)) for s in d.get("sort_alone") or []]
    print("sort", d["particles"], "depth", round(d["sort_radix_ms"], 4), rounded(d["sort_stages_ms"]), alone)
torch = out / "speed/torch.txt"
if torch.exists():
    print(torch.read_text().strip())
for line in (out / "speed/flock.jsonl").open():
    d = json.loads(line)
    print("flock", d["particles"], round(d["ms_per_step"], 4), rounded(d["flock_stages_ms"]))
for path in sorted((out / "events").glob("*.json")):
    d = json.loads(path.read_text())
    print(
        path.name, "step", round(d["ms_per_step"], 4), "plain", round(d["plain_ms_per_step"], 4),
        "ratio", round(d["ms_per_step"] / d["plain_ms_per_step"], 3),
        "order", [round(x, 4) for x in d["order_ms"]],
    )
