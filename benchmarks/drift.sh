#!/usr/bin/env bash
# Long-run drift of the stateful and stateless kernels (docs/accuracy.md): exports drift.ron
# after 600,000 and 6,000,000 steps (10^4 s and 10^5 s at 60 steps/s) from both.
# Usage: drift.sh PLUME OUT_DIR
set -euo pipefail
plume=$1
out=$2
for steps in 600000 6000000; do
    for state in Stateful Stateless; do
        "$plume" run benchmarks/drift.ron --steps "$steps" --state "$state" \
            --export "$out/drift-$state-$steps.csv" --json
    done
done
