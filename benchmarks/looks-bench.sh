#!/usr/bin/env bash
# The looks issue's draw figures (docs/performance.md, "Oriented sprites"), from one device
# call. Usage: looks-bench.sh PLUME OUT_DIR
#   orient.jsonl  `plume bench --render 1920x1080` of sparks.ron (stateless, drawn from the
#                 closed form) and rain.ron (stateful) at 1M and 10M particles, each with
#                 render.orient Camera, Velocity (as the file has it) and Fixed((0, 1, 0)): one
#                 JSON line per (effect, orient, particles), tagged `file` and `orient`; the draw figures are under `draw`
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
tmp=$(mktemp -d)
for effect in sparks rain; do
    for orient in Camera Velocity Fixed; do
        case $orient in
            Camera) replace='orient: Camera,' ;;
            Velocity) replace='&' ;;
            Fixed) replace='orient: Fixed((0.0, 1.0, 0.0)),' ;;
        esac
        sed "s/orient: Velocity([^)]*),/$replace/" "effects/$effect.ron" >"$tmp/$effect-$orient.ron"
        for n in 1000000 10000000; do
            "$plume" bench "$tmp/$effect-$orient.ron" --particles "$n" --steps 5 \
                --render 1920x1080 --json |
                python3 -c "import json,sys; d=json.load(sys.stdin); d['file']='$effect'; d['orient']='$orient'; print(json.dumps(d))"
        done
    done
done >"$out/orient.jsonl"
