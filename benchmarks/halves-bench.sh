#!/usr/bin/env bash
# What motion in 16-bit floats saves (docs/performance.md, "Motion in 16-bit floats"): a
# damped spring stepped by Verlet x1, its motion in halves (the accuracy budget's choice: 28
# bytes a mortal particle, 24 an immortal one) against 32-bit floats (the same scheme named in
# the file: 32 bytes), at 1M and 10M particles, each pair timed back to back, twice, in one run.
# Usage: bash benchmarks/halves-bench.sh PLUME OUT
set -euo pipefail
plume=${1:?path to the plume binary}
out=${2:?output directory}
dir=benchmarks/h100-halves
mkdir -p "$out"
for round in 1 2; do
    for n in 1000000 10000000; do
        for life in mortal immortal; do
            for store in f32 halves; do
                "$plume" bench "$dir/spring-$life-$store.ron" --particles "$n" --steps 100 --json \
                    >"$out/spring-$life-$store-$n-$round.json"
            done
        done
    done
done
