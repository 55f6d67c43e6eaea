#!/usr/bin/env bash
# H (51a9959) vs I (the children's spawn prepared by the ordering's first kernel: no event_prepare dispatch).
out=$OUT
for r in 1 2 3; do
  for v in H I; do
    case $v in base) b=.bench/plume;; E) b=.bench/plume.E;; F) b=.bench/plume.F;; G) b=.bench/plume.G;; H) b=.bench/plume.H;; I) b=.bench/plume.I;; esac
    for e in fireworks rain; do
      for n in 1000000 10000000; do
      echo "{\"round\":$r,\"variant\":\"$v\",\"effect\":\"$e-$n\",\"r\":$($b bench effects/$e.ron --particles $n --steps 100 --json 2>/dev/null | tr -d '\n')}"
      done
    done
  done
done > $out/ab.jsonl
for n in 204800 2048000; do
  for v in H I; do
    case $v in base) b=.bench/plume;; F) b=.bench/plume.F;; G) b=.bench/plume.G;; H) b=.bench/plume.H;; I) b=.bench/plume.I;; esac
    echo "{\"round\":0,\"variant\":\"$v\",\"effect\":\"every-slot-fires-$n\",\"r\":$($b bench .bench/every-slot-fires.ron --particles $n --steps 50 --json 2>/dev/null | tr -d '\n')}"
  done
done >> $out/ab.jsonl

.bench/plume.I bench effects/fireworks.ron --particles 10000000 --profile > $out/profile-I-fireworks.txt 2>&1
.bench/plume.I bench effects/rain.ron --particles 10000000 --profile > $out/profile-I-rain.txt 2>&1
python3 - <<'PY' $out
import json,sys
for l in open(sys.argv[1]+'/ab.jsonl'):
    d=json.loads(l); r=d['r']
    print(d['round'],d['variant'],d['effect'],'step',round(r['ms_per_step'],4),'plain',round(r['plain_ms_per_step'],4),'ratio',round(r['ms_per_step']/r['plain_ms_per_step'],3),'order',[round(x,4) for x in r['order_ms']])
PY
grep -A16 "dispatches with" $out/profile-I-*.txt
(./.bench/events-test --test-threads 1 > $out/events-test.txt 2>&1; echo "exit $?" >> $out/events-test.txt)
tail -n 3 $out/events-test.txt
