#!/usr/bin/env bash
# Mesh particles drawn by the raster pipeline and by the compute renderer, in one run of one
# build: docs/performance.md, "Mesh particles". 100,000 spheres of 200 triangles
# (puffs-200.ron, lit; the same unlit, written here) and of 1280 (effects/hanabi/puffs.ron),
# 1280x720, each bench twice (at most 240 s each).
# Usage: compute-bench.sh PLUME OUT; then python3 benchmarks/meshes/compute-summary.py OUT/compute.jsonl
set -euo pipefail
plume=$1
out=$2
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
# The unlit copy sits beside the mesh it names.
unlit="$here/puffs-200-unlit.ron"
grep -v 'lit: Some' "$here/puffs-200.ron" | sed 's/name: "puffs-200"/name: "puffs-200-unlit"/' >"$unlit"
trap 'rm -f "$unlit"' EXIT
for round in 1 2; do
    for f in "$here/puffs-200.ron" "$unlit" "$here/../../effects/hanabi/puffs.ron"; do
        timeout 240 "$plume" bench "$f" --particles 100000 --steps 50 --render 1280x720 --json |
            python3 -c "import json,sys; d=json.loads(sys.stdin.read().splitlines()[-1]); d['round']=$round; print(json.dumps(d))"
    done
done >"$out/compute.jsonl"
