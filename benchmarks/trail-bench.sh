#!/usr/bin/env bash
# The looks issue's trail figures (docs/performance.md, "Trails"), from one device call, run
# from the repository root. Usage: trail-bench.sh PLUME OUT_DIR
#   trail.jsonl  `plume bench --render 1920x1080` at 1M and 10M particles of orbit.ron
#                (stateful Verlet, additive, unsorted) drawn as its plain sprites (trail
#                removed), and with ribbons of 8 and 32 points (a sample every 2 steps, as the
#                file has it). One JSON line per (variant, particles), tagged `file` and
#                `variant`; the draw figures are under `draw`, the step's under `step`.
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
tmp=$(mktemp -d)
variant() { # name python-expression-on-the-file-text
    python3 -c "import sys; s=open('effects/orbit.ron').read(); print($2, end='')" >"$tmp/orbit-$1.ron"
}
# The trail block is the lines from `trail: Some(Trail(` to its closing `)),`.
variant sprites "s[:s.index('        trail: Some(')] + s[s.index('        )),', s.index('trail: Some(')) + len('        )),') + 1:]"
variant trail8 "s.replace('points: 24', 'points: 8')"
variant trail32 "s.replace('points: 24', 'points: 32')"
for v in sprites trail8 trail32; do
    for n in 1000000 10000000; do
        "$plume" bench "$tmp/orbit-$v.ron" --particles "$n" --steps 5 --render 1920x1080 --json |
            python3 -c "import json,sys; d=json.load(sys.stdin); d['file']='orbit'; d['variant']='$v'; print(json.dumps(d))"
    done
done >"$out/trail.jsonl"
