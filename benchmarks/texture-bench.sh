#!/usr/bin/env bash
# The looks issue's texture figures (docs/performance.md, "Textured sprites"), from one device
# call, run from the repository root. Usage: texture-bench.sh PLUME OUT_DIR
#   texture.jsonl  `plume bench --render 1920x1080` at 1M and 10M particles of
#                  snow.ron (stateful, unsorted) drawn as round dots (texture and rotation
#                  removed), with its 64x64 snowflake texture, and with texture and rotation
#                  (as the file has it); and smoke.ron (stateful, depth-sorted) as round dots and
#                  with its 16-frame 256x256 flipbook (as the file has it). One JSON line per
#                  (effect, variant, particles), tagged `file` and `variant`; the draw figures
#                  are under `draw`.
set -euo pipefail
plume=$1
out=$2
mkdir -p "$out"
tmp=$(mktemp -d)
# The copies live in $tmp: point their textures at the repository's.
textures="$PWD/effects/textures"
variant() { # effect name sed-program
    sed -e "s|file: \"textures/|file: \"$textures/|" -e "$3" "effects/$1.ron" >"$tmp/$1-$2.ron"
}
variant snow dots '/texture: Some/d; /rotation: Some/d'
variant snow texture '/rotation: Some/d'
variant snow texture+rotation ''
variant smoke dots '/texture: Some/d'
variant smoke flipbook ''
for run in snow:dots snow:texture snow:texture+rotation smoke:dots smoke:flipbook; do
    effect=${run%%:*}
    v=${run##*:}
    for n in 1000000 10000000; do
        "$plume" bench "$tmp/$effect-$v.ron" --particles "$n" --steps 5 --render 1920x1080 --json |
            python3 -c "import json,sys; d=json.load(sys.stdin); d['file']='$effect'; d['variant']='$v'; print(json.dumps(d))"
    done
done >"$out/texture.jsonl"
