#!/usr/bin/env bash
# Stateless against stateful (docs/performance.md, "Stateless effects"): `plume bench` times the
# stateful update and, in the same run, the stateless `evaluate` of the same N particles, for
# sparks.ron and two variants. Usage: stateless-bench.sh PLUME OUT.jsonl
set -euo pipefail
plume=$1
out=$2
dir=$(mktemp -d)
cp effects/sparks.ron "$dir/sparks.ron"
# Drag toward a moving fluid (wind): one more vector term in the closed form.
sed -e 's/name: "sparks"/name: "sparks-wind"/' -e 's/Drag(k: 1.5)/Drag(k: 1.5, fluid: (2.0, 0.0, 1.0))/' \
    effects/sparks.ron >"$dir/sparks-wind.ron"
# Gravity only, from a box at rest: the cheapest spawn draw and no exp.
sed -e 's/name: "sparks"/name: "drop"/' -e 's/Drag(k: 1.5),//' \
    -e 's/shape: Point((0.0, 1.0, 0.0))/shape: Box(min: (-1.0, 0.0, -1.0), max: (1.0, 2.0, 1.0))/' \
    -e 's/velocity: Radial(speed: (4.0, 12.0))/velocity: Constant((0.0, 3.0, 0.0))/' \
    effects/sparks.ron >"$dir/drop.ron"
for f in "$dir"/*.ron; do
    for n in 1000 10000 100000 1000000 10000000; do
        "$plume" bench "$f" --particles "$n" --steps 100 --json
    done
done >"$out"
