#!/usr/bin/env bash
# base (9b0339a) vs J (the flock snapshot's positions, then its velocities, not interleaved).
out=$OUT
for r in 1 2 3; do
  for v in base J; do
    case $v in base) b=.bench/plume;; J) b=.bench/plume.J;; esac
    for n in 16384 262144 1048576; do
      echo "{\"round\":$r,\"variant\":\"$v\",\"n\":$n,\"r\":$($b bench effects/boids.ron --particles $n --steps 50 --json 2>/dev/null | tr -d '\n')}"
    done
  done
done > $out/ab.jsonl
python3 - <<'PY' $out
import json,sys
for l in open(sys.argv[1]+'/ab.jsonl'):
    d=json.loads(l); r=d['r']
    fl=r.get('flock_stages_ms') or {}
    print(d['round'],d['variant'],d['n'],'step',round(r['ms_per_step'],4), {k:(round(v,4) if isinstance(v,(int,float)) else v) for k,v in (fl.items() if isinstance(fl,dict) else [])})
PY
