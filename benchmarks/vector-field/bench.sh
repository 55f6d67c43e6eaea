#!/usr/bin/env bash
# The vector field's cost per step against the same effect without it (docs/performance.md,
# "Imported vector fields"). From the project root, after `cargo build --release`:
#   python3 benchmarks/vector-field/make.py && benchmarks/vector-field/bench.sh
set -euo pipefail
dir=benchmarks/vector-field
for n in 1000000 10000000; do
  for e in without_field with_field; do
    ./target/release/plume bench $dir/$e.ron --particles $n --steps 100 --json
  done
done
