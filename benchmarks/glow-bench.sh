#!/usr/bin/env bash
# The looks issue's glow figures (docs/performance.md, "Glow"), from one device call, run from
# the repository root. Usage: glow-bench.sh PLUME OUT_DIR
#   glow.jsonl  `plume bench --render 1920x1080` of sparks.ron (additive streaks, glow
#               threshold 0.4, strength 3, radius 0.015 of the height) at 1M and 10M
#               particles: under `draw`, `ms` is the RGBA8 draw, `glow_draw_ms` the same draw
#               into the HDR image and `glow_blur_ms` the bloom's two blur passes.
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
for n in 1000000 10000000; do
    "$plume" bench effects/sparks.ron --particles "$n" --steps 5 --render 1920x1080 --json
done >"$out/glow.jsonl"
