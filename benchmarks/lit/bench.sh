#!/usr/bin/env bash
# Figures of docs/performance.md, "Lit sprites", from one device call. Usage: bench.sh PLUME OUT
#   lit.jsonl  effects/lit_smoke.ron (sphere normals, three lights), smoke-one-light.ron (its
#              sun alone), smoke-flat.ron (flat normals, three lights), smoke-normal-map.ron
#              and smoke-one-light-map.ron (normal-mapped, three lights and the sun alone),
#              smoke-six-way.ron (six-way lightmaps, three lights) and smoke-unlit.ron (the
#              same smoke unlit), 1M particles, the draw at 1280x720
#              (raster and compute renderer), in three rounds, alternated.
set -euo pipefail
plume=$1
out=$2
here=$(dirname "$0")
mkdir -p "$out"
for round in 1 2 3; do
    for f in "$here/smoke-unlit.ron" effects/lit_smoke.ron "$here/smoke-one-light.ron" \
        "$here/smoke-flat.ron" "$here/smoke-normal-map.ron" "$here/smoke-one-light-map.ron" \
        "$here/smoke-six-way.ron"; do
        "$plume" bench "$f" --particles 1000000 --steps 20 --render 1280x720 --json
    done
done >"$out/lit.jsonl"
