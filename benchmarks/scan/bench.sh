#!/usr/bin/env bash
# The shared workgroup scan against the four copies it replaced, and what a reported event
# costs, in one device call: two builds alternated (OLD, NEW), two rounds, each timing the
# work that scans (the radix sort of 16.7M pairs and fountain's depth sort, events' ordering
# and spawns in rain and fireworks at 10M slots, the compute renderer's frame of fountain 10M
# and smoke 1M, a 1M-boid flock's step), then NEW alone on rain.ron with its splash event
# reported (rain-reported.ron) against rain.ron.
# Usage: bash benchmarks/scan/bench.sh OLD NEW OUT
set -euo pipefail
old=${1:?old plume}
new=${2:?new plume}
out=${3:?output directory}
mkdir -p "$out"
cases() {
    local plume=$1 tag=$2
    "$plume" bench effects/fountain.ron --particles 16777216 --steps 20 --sort-keys 16777216 --json | sed "s/^{/{\"build\":\"$tag\",\"case\":\"sort\",/"
    for e in rain fireworks; do
        "$plume" bench "effects/$e.ron" --particles 10000000 --steps 100 --json | sed "s/^{/{\"build\":\"$tag\",\"case\":\"events-$e\",/"
    done
    "$plume" bench effects/fountain.ron --particles 10000000 --steps 5 --render 1280x720 --json | sed "s/^{/{\"build\":\"$tag\",\"case\":\"splat-fountain\",/"
    "$plume" bench effects/smoke.ron --particles 1000000 --steps 5 --render 1280x720 --json | sed "s/^{/{\"build\":\"$tag\",\"case\":\"splat-smoke\",/"
    "$plume" bench effects/boids.ron --particles 1048576 --steps 50 --json | sed "s/^{/{\"build\":\"$tag\",\"case\":\"flock\",/"
}
for round in 1 2; do
    cases "$old" old >>"$out/scan-ab.jsonl"
    cases "$new" new >>"$out/scan-ab.jsonl"
done
for round in 1 2 3; do
    for e in effects/rain.ron benchmarks/scan/rain-reported.ron; do
        "$new" bench "$e" --particles 10000000 --steps 100 --json | sed "s/^{/{\"case\":\"$(basename "$e" .ron)\",/"
    done
done >"$out/reports.jsonl"
