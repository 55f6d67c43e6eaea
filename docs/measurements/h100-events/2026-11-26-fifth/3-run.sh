#!/usr/bin/env bash
# A (c4569a4) vs C (buckets: slot in the bucket with one id a bucket, placed by the scan;
# look-back scan on NVIDIA) vs C with PLUME_EVENT_SCAN=portable (reduce then scan).
out=$OUT
for r in 1 2; do
  for v in A C Cp; do
    case $v in A) b=.bench/plume.A; p=;; C) b=.bench/plume.C; p=;; Cp) b=.bench/plume.C; p=portable;; esac
    for e in fireworks rain; do
      echo "{\"round\":$r,\"variant\":\"$v\",\"effect\":\"$e\",\"r\":$(PLUME_EVENT_SCAN=$p $b bench effects/$e.ron --particles 10000000 --steps 100 --json 2>/dev/null | tr -d '\n')}"
    done
  done
done > $out/ab.jsonl
for n in 204800 2048000; do
  for v in A C Cp; do
    case $v in A) b=.bench/plume.A; p=;; C) b=.bench/plume.C; p=;; Cp) b=.bench/plume.C; p=portable;; esac
    echo "{\"round\":0,\"variant\":\"$v\",\"effect\":\"every-slot-fires-$n\",\"r\":$(PLUME_EVENT_SCAN=$p $b bench .bench/every-slot-fires.ron --particles $n --steps 50 --json 2>/dev/null | tr -d '\n')}"
  done
done > $out/every-slot-fires.jsonl
.bench/plume.C bench effects/fireworks.ron --particles 10000000 --profile > $out/profile-C-fireworks.txt 2>&1
.bench/plume.C bench effects/rain.ron --particles 10000000 --profile > $out/profile-C-rain.txt 2>&1
(./.bench/events-test --test-threads 1 > $out/events-test-lookback.txt 2>&1; echo "exit $?" >> $out/events-test-lookback.txt)
(PLUME_EVENT_SCAN=portable ./.bench/events-test --test-threads 1 > $out/events-test-portable.txt 2>&1; echo "exit $?" >> $out/events-test-portable.txt)
python3 - <<'PY' $out
import json,sys
for f in ['ab.jsonl','every-slot-fires.jsonl']:
  for l in open(sys.argv[1]+'/'+f):
    d=json.loads(l); r=d['r']
    print(d['round'],d['variant'],d['effect'],'step',round(r['ms_per_step'],4),'plain',round(r['plain_ms_per_step'],4),'ratio',round(r['ms_per_step']/r['plain_ms_per_step'],3),'order',[round(x,4) for x in r['order_ms']], 'firings', r.get('firings_per_step'))
PY
tail -n 4 $out/events-test-lookback.txt $out/events-test-portable.txt
