#!/usr/bin/env bash
# The update of several builds alternated in one device call (docs/performance.md, "The update
# at large sizes": "What slowed it"). Usage: bench.sh OUT BUILD...
#   update.jsonl  fountain.ron at 100M and 10M, rock_fountain.ron at 10M and 1M,
#                 magnetic_bottle.ron at 10M: each build in turn, two rounds
#   events.jsonl  rain.ron and fireworks.ron at 10M slots, with events and without
# Each line is {"build": BUILD, "round": R, "result": <plume bench --json>}.
set -u
out=$1
shift
mkdir -p "$out"
run() { # build file particles steps
    printf '{"build":"%s","round":%s,"result":' "$1" "$round"
    local r
    r=$(timeout 120 "$1" bench "$2" --particles "$3" --steps "$4" --json 2>/dev/null | tr -d '\n')
    printf '%s' "${r:-null}"
    printf '}\n'
}
for round in 1 2; do
    for e in effects/fountain.ron:100000000 effects/fountain.ron:10000000 effects/rock_fountain.ron:10000000 \
        effects/magnetic_bottle.ron:10000000 effects/rock_fountain.ron:1000000; do
        for b in "$@"; do
            run "$b" "${e%%:*}" "${e##*:}" 50
        done
    done
done >"$out/update.jsonl"
for round in 1 2; do
    for e in rain fireworks; do
        for b in "$@"; do
            run "$b" "effects/$e.ron" 10000000 100
        done
    done
done >"$out/events.jsonl"
