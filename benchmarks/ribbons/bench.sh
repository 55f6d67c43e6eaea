#!/usr/bin/env bash
# Figures of docs/performance.md, "Ribbons", from one device call. Usage: bench.sh PLUME OUT
#   bolts.jsonl  bolts.ron (1M particles joined into 25,000 ribbons of 40) and
#                bolts-sprites.ron (the same particles as sprites), alternated three times:
#                the step and the raster draw at 1280x720
set -euo pipefail
plume=$1
out=$2
here=$(dirname "$0")
mkdir -p "$out"
for round in 1 2 3; do
    for f in "$here/bolts.ron" "$here/bolts-sprites.ron"; do
        "$plume" bench "$f" --particles 1000000 --steps 50 --render 1280x720 --json
    done
done >"$out/bolts.jsonl"
# hanabi-graphs.jsonl (h100/) came from the same build in one call before it:
#   for f in worms firework; do PLUME bench effects/hanabi/$f.ron --particles 1000000 --steps 50 --json; done
