#!/usr/bin/env bash
# One device call's A/B of the events (docs/performance.md, "Events ordered in three
# dispatches"): fireworks.ron and rain.ron at 1M and 10M slots, in three rounds alternating the
# builds, then every-slot-fires.ron (beside this file) at 204,800 and 2,048,000 slots,
# `--profile` of the last build on both effects at 10M, and the events tests when given.
# Usage: OUT=DIR bash ab.sh NAME=PLUME [NAME=PLUME ...] [--events-test BINARY]
set -euo pipefail
out=${OUT:?output directory}
here=$(dirname "$0")
variants=()
events_test=
while (($#)); do
    case $1 in
        --events-test) events_test=$2; shift 2;;
        *) variants+=("$1"); shift;;
    esac
done
run() { # name binary effect slots steps round
    echo "{\"round\":$6,\"variant\":\"$1\",\"effect\":\"$(basename "$3" .ron)-$4\",\"r\":$("$2" bench "$3" --particles "$4" --steps "$5" --json 2>/dev/null | tr -d '\n')}"
}
for r in 1 2 3; do
    for v in "${variants[@]}"; do
        for e in fireworks rain; do
            for n in 1000000 10000000; do run "${v%%=*}" "${v#*=}" "effects/$e.ron" "$n" 100 "$r"; done
        done
    done
done >"$out/ab.jsonl"
for n in 204800 2048000; do
    for v in "${variants[@]}"; do
        run "${v%%=*}" "${v#*=}" "$here/every-slot-fires.ron" "$n" 50 0
    done
done >>"$out/ab.jsonl"
last=${variants[-1]}
for e in fireworks rain; do
    "${last#*=}" bench "effects/$e.ron" --particles 10000000 --profile >"$out/profile-$e.txt" 2>&1
done
if [[ -n $events_test ]]; then
    ("$events_test" --test-threads 1 >"$out/events-test.txt" 2>&1; echo "exit $?" >>"$out/events-test.txt")
fi
python3 - "$out" <<'PY'
import json, sys
for line in open(sys.argv[1] + '/ab.jsonl'):
    d = json.loads(line); r = d['r']
    print(d['round'], d['variant'], d['effect'], 'step', round(r['ms_per_step'], 4),
          'plain', round(r['plain_ms_per_step'], 4),
          'ratio', round(r['ms_per_step'] / r['plain_ms_per_step'], 3),
          'order', [round(x, 4) for x in r['order_ms']])
PY
