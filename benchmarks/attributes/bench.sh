#!/usr/bin/env bash
# Figures of docs/performance.md, "Attributes", from one device call. Usage: bench.sh PLUME OUT
#   attributes.jsonl  effects/fountain.ron, fountain-custom.ron (a custom force and draw
#                     expressions reading random numbers) and fountain-attributes.ron (the same
#                     with four attributes set at spawn and changed each step) at 1M and 10M,
#                     alternated twice: the step and the draw at 1280x720
#   hanabi.jsonl      every effects/hanabi port at 1M particles: the step, and the draw
set -euo pipefail
plume=$1
out=$2
here=$(dirname "$0")
mkdir -p "$out"
for round in 1 2; do
    for n in 1000000 10000000; do
        for f in effects/fountain.ron "$here/fountain-custom.ron" "$here/fountain-attributes.ron"; do
            "$plume" bench "$f" --particles "$n" --steps 50 --render 1280x720 --json
        done
    done
done >"$out/attributes.jsonl"
for f in effects/hanabi/*.ron; do
    "$plume" bench "$f" --particles 1000000 --steps 50 --render 1280x720 --json
done >"$out/hanabi.jsonl"
