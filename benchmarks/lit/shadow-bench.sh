#!/usr/bin/env bash
# Figures of docs/performance.md, "Received shadows", from one device call. Usage:
# shadow-bench.sh PLUME OUT
#   shadow.jsonl  smoke-unlit.ron, smoke-one-light-map.ron (normal-mapped, one directional
#                 light) and smoke-shadow-map.ron (the same light's shadow cast by a wall from
#                 the scene's meshes), smoke-shadow-particle.ron (the same shadow looked up once
#                 a particle), 1M particles, the draw at 1280x720 (raster and compute renderer),
#                 in three rounds, alternated.
#   meshes-200.jsonl  ../meshes/puffs-200.ron (200-triangle spheres, lit) at 100k, twice.
set -euo pipefail
plume=$1
out=$2
here=$(dirname "$0")
mkdir -p "$out"
for round in 1 2 3; do
    for f in "$here/smoke-unlit.ron" "$here/smoke-one-light-map.ron" "$here/smoke-shadow-map.ron" \
        "$here/smoke-shadow-particle.ron"; do
        "$plume" bench "$f" --particles 1000000 --steps 20 --render 1280x720 --json
    done
done >"$out/shadow.jsonl"
for round in 1 2; do
    timeout 240 "$plume" bench "$here/../meshes/puffs-200.ron" --particles 100000 --steps 50 \
        --render 1280x720 --json || true
done >"$out/meshes-200.jsonl"
