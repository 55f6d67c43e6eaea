#!/usr/bin/env bash
# The compute renderer against the raster pipeline (docs/performance.md, "The compute renderer"):
# `plume bench --render 1280x720` times both draws of the same frame, the splat with its stages
# (project, scan, emit, sort, ranges, raster), in one run per effect. Discs (fountain) and
# quads (snow: textured and rotating; smoke: a sorted, textured flipbook; boids: textured,
# velocity-aligned), and the effects the splat does not draw yet (sparks: glow; orbit: trails)
# for their raster figures. Usage: splat-bench.sh PLUME OUT_DIR
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
run() { "$plume" bench "effects/$1.ron" --particles "$2" --steps 5 --render 1280x720 --json; }
{
    run fountain 10000000
    run snow 10000000
    run sparks 10000000
    run smoke 1000000
    run orbit 1000000
    run boids 1000000
    run fountain 1000000
} >"$out/splat.jsonl"
