#!/usr/bin/env bash
# The GPU draw (docs/performance.md, "Drawing"): `plume bench --render` times the draw of all
# live particles straight from the GPU buffers, with GPU timestamps around the render pass, beside
# the simulation step of the same run. Usage: draw-bench.sh PLUME OUT_DIR
#   draw.jsonl      fountain (sorted, alpha) and sparks (stateless, additive) at 1M, 10M, 100M,
#                   1280x720: the draw, without blending, vertices only, the sort before it,
#                   the compacted-list variant (unsorted) and the stateless closed-form draw
#   occupancy.jsonl snow at 10M slots with 1%, 10% and 100% alive: hidden free slots against a
#                   compacted list of the live ones
#   pixels.jsonl    fountain at 10M on 640x360, 1280x720 and 2560x1440: does the draw scale with
#                   pixels (fill) or not (vertices)?
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
for n in 1000000 10000000 100000000; do
    for e in fountain sparks; do
        "$plume" bench "effects/$e.ron" --particles "$n" --steps 20 --render 1280x720 --json
    done
done >"$out/draw.jsonl"
for occ in 0.01 0.1 1; do
    "$plume" bench effects/snow.ron --particles 10000000 --occupancy "$occ" --steps 5 --render 1280x720 --json
done >"$out/occupancy.jsonl"
for size in 640x360 2560x1440; do
    "$plume" bench effects/fountain.ron --particles 10000000 --steps 5 --render "$size" --json
done >"$out/pixels.jsonl"
