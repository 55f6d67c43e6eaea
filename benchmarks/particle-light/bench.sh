#!/usr/bin/env bash
# Figures of docs/performance.md, "Light from particles", from one device call.
# Usage: bench.sh PLUME OUT
#   light.jsonl  effects/embers.ron at 1M and 10M particles, twice, alternated: the step, the
#                draw at 1280x720, and the two kernels that pick the 8 lights (light_ms).
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
for round in 1 2; do
    for n in 1000000 10000000; do
        "$plume" bench effects/embers.ron --particles "$n" --steps 50 --render 1280x720 --json
    done
done >"$out/light.jsonl"
