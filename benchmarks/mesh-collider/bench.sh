#!/usr/bin/env bash
# The Mesh collider's cost per step against the analytic Sphere it approximates and against the
# ground alone, and the SceneDepth collider's against the same ball seen in a 1280 x 720 depth
# image (docs/performance.md, "Mesh colliders" and "Scene depth"): 10M particles falling onto a
# ball over the ground, 100 steps. From the project root, after `cargo build --release`:
#   python3 benchmarks/mesh-collider/make.py && benchmarks/mesh-collider/bench.sh
set -euo pipefail
dir=benchmarks/mesh-collider
plume=${PLUME:-./target/release/plume}
for n in 1000000 10000000; do
  for e in ground_only analytic mesh32 mesh96 mesh128 depth depth_nothing; do
    $plume bench $dir/$e.ron --particles $n --steps 100 --json
  done
done
