#!/usr/bin/env python3
"""The head-to-head's table (docs/bevy.md) from the lines of benchmarks/bevy-versus-hanabi.sh.

Usage: python3 benchmarks/bevy-versus-summary.py versus.jsonl

One row per case and round: each plugin's median frame, CPU and GPU milliseconds (p90 in
brackets), Plume's over hanabi's for CPU and GPU, and each plugin's lit pixels.
"""
import json
import sys


def case_of(r):
    return (r.get("view", "3d"), r.get("msaa", 1), r["live_per_effect"], r["effects"],
            r.get("mesh", False))


def name(case):
    view, msaa, live, effects, mesh = case
    size = f"{live // 1_000_000}M" if live >= 1_000_000 else f"{live:,}"
    what = f"{effects:,} effects of {size}" if effects > 1 else f"1 effect, {size}"
    meshes = ", 200-triangle meshes" if mesh else ""
    return f"{view.upper()}, MSAA {'off' if msaa == 1 else f'{msaa}x'}, {what}{meshes}"


def cell(r, key):
    if r.get(key) is None:
        return "-"
    return f"{r[key]:.2f} ({r[key + '_p90']:.2f})"


def ratio(p, h, key):
    if p.get(key) is None or not h.get(key):
        return "-"
    return f"{p[key] / h[key]:.2f}"


def pixels(r):
    n = r.get("lit_pixels")
    return "-" if n is None else f"{n:,}"


def main(path):
    rows = [json.loads(l) for l in open(path) if l.strip()]
    errors = [r for r in rows if "error" in r]
    rows = [r for r in rows if "error" not in r]
    pending = {}
    print("| case | plugin | frame ms | cpu ms | gpu ms | lit pixels |")
    print("|---|---|---|---|---|---|")
    pairs = []
    for r in rows:
        if r["plugin"] == "empty":
            print(f"| {name(case_of(r))} | empty app | {cell(r, 'frame_ms')} | "
                  f"{cell(r, 'cpu_ms')} | {cell(r, 'gpu_ms')} | {pixels(r)} |")
            continue
        print(f"| {name(case_of(r))} | {r['plugin']} ({r['draw'].lower()}) | "
              f"{cell(r, 'frame_ms')} | {cell(r, 'cpu_ms')} | {cell(r, 'gpu_ms')} | "
              f"{pixels(r)} |")
        c = case_of(r)
        if r["plugin"] == "hanabi":
            pending[c] = r
        elif c in pending:
            pairs.append((c, pending.pop(c), r))
    print()
    print("| case | Plume / hanabi, frame | cpu | gpu | lit pixels, hanabi / Plume |")
    print("|---|---|---|---|---|")
    for c, h, p in pairs:
        print(f"| {name(c)} | {ratio(p, h, 'frame_ms')} | {ratio(p, h, 'cpu_ms')} | "
              f"{ratio(p, h, 'gpu_ms')} | {pixels(h)} / {pixels(p)} |")
    for e in errors:
        print(f"\nno result: {e}")


if __name__ == "__main__":
    main(sys.argv[1])
