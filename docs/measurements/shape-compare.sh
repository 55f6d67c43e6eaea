#!/usr/bin/env bash
# Old (aa3578b, before issue 42's move) against new (after), alternating, two rounds, one call.
# Usage, on the H100 with .gl unpacked as ../shared/tools/gpu-prep.sh says: both builds stripped
# into .bench/ as plume-old and plume-new, then  bash docs/measurements/shape-compare.sh OUT
out=$1; mkdir -p "$out"
cases=(
 "effects/fountain.ron --particles 1000000 --steps 50"
 "effects/fountain.ron --particles 10000000 --steps 50"
 "effects/rain.ron --particles 10000000 --steps 50"
 "effects/fireworks.ron --particles 10000000 --steps 50"
 "effects/boids.ron --particles 16384 --steps 50"
 "effects/boids.ron --particles 1048576 --steps 50"
 "effects/fountain.ron --particles 1000000 --steps 20 --render 1280x720"
 "effects/fountain.ron --particles 1048576 --steps 20 --sort-keys 16777216"
)
for round in 1 2; do
  for c in "${cases[@]}"; do
    for v in old new; do
      echo "{\"round\":$round,\"build\":\"$v\",\"case\":\"$c\",\"result\":$(./.bench/plume-$v bench $c --json 2>/dev/null | tail -1)}" >> "$out/compare.jsonl"
    done
  done
done
