#!/usr/bin/env bash
# The cost of building an effect (`Effect::new`: buffers and kernels) the first time in a
# process, again with the device's cache of modules and pipelines, and again with an empty
# cache: `plume bench`'s build_ms, build_again_ms and build_again_uncached_ms, for each example
# at 1,000 particles (so buffers cost little) and at 1M.
# Run: bash benchmarks/build-bench.sh PLUME OUT.jsonl
set -u
plume=$1; out=$2
for n in 1000 1000000; do
  for e in fountain snow sparks orbit smoke lit_smoke rock_fountain magnetic_bottle tornado boids; do
    line=$("$plume" bench "effects/$e.ron" --particles "$n" --steps 5 --json 2>/dev/null | tail -1)
    [ -z "$line" ] && line="{\"effect\":\"effects/$e.ron\",\"particles\":$n,\"error\":\"no result\"}"
    echo "$line" | python3 -c "import json,sys; d=json.loads(sys.stdin.read()); print(json.dumps({k: d.get(k) for k in ['effect','adapter','capacity','build_ms','build_again_ms','build_again_uncached_ms','error']}))" | tee -a "$out"
  done
done
