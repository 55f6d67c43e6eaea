#!/usr/bin/env bash
# Figures of docs/performance.md, "Mesh particles", from one device call. Usage: bench.sh PLUME OUT
#   meshes.jsonl  effects/hanabi/puffs.ron (1280-triangle spheres, lit) and the same drawn as lit
#                 sprites (puffs-sprites.ron, written here): the step and the draw at
#                 1280x720, at 10k and 100k particles alternated twice, then at 1M once (each
#                 bench given at most 240 s); effects/hanabi/circle.ron (two textures a sprite)
#                 at 1M first
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
sprites="$out/puffs-sprites.ron"
grep -v 'mesh: Some' effects/hanabi/puffs.ron | sed 's/name: "puffs"/name: "puffs-sprites"/' >"$sprites"
# The sprites' file names no mesh; its texture-free look needs no base directory.
bench() {
    timeout 240 "$plume" bench "$1" --particles "$2" --steps 50 --render 1280x720 --json || true
}
{
    bench effects/hanabi/circle.ron 1000000
    for round in 1 2; do
        for n in 10000 100000; do
            for f in effects/hanabi/puffs.ron "$sprites"; do
                bench "$f" "$n"
            done
        done
    done
    bench "$sprites" 1000000
    bench effects/hanabi/puffs.ron 1000000
} >"$out/meshes.jsonl"
