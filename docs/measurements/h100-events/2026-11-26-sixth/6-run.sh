#!/usr/bin/env bash
# I (b38ecbc) vs K (the preparation's loads at the kernel's start, its stores at its end).
out=$OUT
for r in 1 2 3; do
  for v in I K; do
    case $v in base) b=.bench/plume;; E) b=.bench/plume.E;; F) b=.bench/plume.F;; G) b=.bench/plume.G;; H) b=.bench/plume.H;; I) b=.bench/plume;; K) b=.bench/plume.K;; esac
    for e in fireworks rain; do
      for n in 1000000 10000000; do
      echo "{\"round\":$r,\"variant\":\"$v\",\"effect\":\"$e-$n\",\"r\":$($b bench effects/$e.ron --particles $n --steps 100 --json 2>/dev/null | tr -d '\n')}"
      done
    done
  done
done > $out/ab.jsonl
for n in 204800 2048000; do
  for v in I K; do
    case $v in base) b=.bench/plume;; F) b=.bench/plume.F;; G) b=.bench/plume.G;; H) b=.bench/plume.H;; I) b=.bench/plume;; K) b=.bench/plume.K;; esac
    echo "{\"round\":0,\"variant\":\"$v\",\"effect\":\"every-slot-fires-$n\",\"r\":$($b bench .bench/every-slot-fires.ron --particles $n --steps 50 --json 2>/dev/null | tr -d '\n')}"
  done
done >> $out/ab.jsonl

.bench/plume.K bench effects/fireworks.ron --particles 10000000 --profile > $out/profile-K-fireworks.txt 2>&1
.bench/plume.K bench effects/rain.ron --particles 10000000 --profile > $out/profile-K-rain.txt 2>&1
python3 - <<'PY' $out
import json,sys
for l in open(sys.argv[1]+'/ab.jsonl'):
    d=json.loads(l); r=d['r']
    print(d['round'],d['variant'],d['effect'],'step',round(r['ms_per_step'],4),'plain',round(r['plain_ms_per_step'],4),'ratio',round(r['ms_per_step']/r['plain_ms_per_step'],3),'order',[round(x,4) for x in r['order_ms']])
PY
grep -A16 "dispatches with" $out/profile-K-*.txt
