#!/usr/bin/env bash
# What events cost (docs/performance.md, "Events"): fireworks.ron and rain.ron scaled to 1M
# and 10M slots, each step with its events against the same groups and live particles with
# none, and each event's ordering alone, all timed in one run of `plume bench` per effect and size.
# Usage: bash benchmarks/events-bench.sh PLUME OUT
set -euo pipefail
plume=${1:?path to the plume binary}
out=${2:?output directory}
mkdir -p "$out"
for n in 1000000 10000000; do
    for e in fireworks rain; do
        "$plume" bench "effects/$e.ron" --particles "$n" --steps 100 --json >"$out/$e-$n.json"
    done
done
