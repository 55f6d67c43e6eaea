#!/usr/bin/env bash
# Figures of docs/performance.md, "Expressions at spawn and in the draw", from one device
# call. Usage: bench.sh PLUME OUT_DIR
#   by.jsonl      effects/fountain.ron and fountain-by.ron (the same fountain, its spawn
#                 velocity, colour, opacity and size written as expressions) at 1M and 10M,
#                 alternated: the step and the draw at 1280x720
set -euo pipefail
plume=$1
out=$2
here=$(dirname "$0")
mkdir -p "$out"
for round in 1 2; do
    for n in 1000000 10000000; do
        for f in effects/fountain.ron "$here/fountain-by.ron"; do
            "$plume" bench "$f" --particles "$n" --steps 50 --render 1280x720 --json
        done
    done
done >"$out/by.jsonl"
