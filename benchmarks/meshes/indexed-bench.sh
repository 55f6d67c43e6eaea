#!/usr/bin/env bash
# The draw of 100,000 mesh particles of 200 triangles (puffs-200.ron, lit; and the same file
# unlit, written here), 1280x720, by two builds alternated twice: docs/performance.md, "Mesh
# particles" (an unlit mesh drawn indexed against every corner of every triangle shaded).
# Usage: indexed-bench.sh OLD_PLUME NEW_PLUME OUT; then python3 benchmarks/meshes/indexed-summary.py OUT/indexed.jsonl
set -euo pipefail
old=$1
new=$2
out=$3
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
# The unlit copy sits beside the mesh it names.
unlit="$here/puffs-200-unlit.ron"
grep -v 'lit: Some' "$here/puffs-200.ron" | sed 's/name: "puffs-200"/name: "puffs-200-unlit"/' >"$unlit"
trap 'rm -f "$unlit"' EXIT
for round in 1 2; do
    for build in old new; do
        plume=$old
        [ "$build" = new ] && plume=$new
        for f in "$here/puffs-200.ron" "$unlit"; do
            timeout 240 "$plume" bench "$f" --particles 100000 --steps 50 --render 1280x720 --json |
                python3 -c "import json,sys; d=json.loads(sys.stdin.read().splitlines()[-1]); d['build']='$build'; d['round']=$round; print(json.dumps(d))"
        done
    done
done >"$out/indexed.jsonl"
