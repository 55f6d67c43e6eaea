#!/usr/bin/env bash
# bevy_plume against bevy_hanabi 0.20 drawing mesh particles (crates/bevy_plume/examples/
# versus_hanabi.rs --mesh 1: the fountain, every particle the same Bevy UV sphere of 200
# triangles, unlit in both), one headless Bevy app per run at 1280x720, MSAA off, the two
# plugins alternated: 10,000 and 100,000 live particles, two rounds, screenshots in the first.
# Build and pack the example as benchmarks/bevy-versus-hanabi.sh says; run there:
#   bash benchmarks/bevy-mesh-versus.sh .bin/versus_hanabi.xz OUT
# Then: python3 benchmarks/bevy-versus-summary.py OUT/mesh-versus.jsonl
set -u
packed=$1; out=$2; mkdir -p "$out"
bin=/tmp/versus_hanabi
python3 -c "import lzma,sys; open(sys.argv[2],'wb').write(lzma.open(sys.argv[1]).read())" "$packed" "$bin"
chmod +x "$bin"
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$out/device.txt"
for round in 1 2; do
  for live in 10000 100000; do
    for p in hanabi plume; do
      shot=""; [ $round = 1 ] && shot="--out $out/mesh-$p-$live.png"
      line=$(timeout 170 "$bin" --plugin $p --live $live --mesh 1 --frames 120 $shot \
        2>"$out/last-stderr.txt" | tail -1)
      if [ -z "$line" ]; then
        line="{\"plugin\":\"$p\",\"case\":\"mesh $live\",\"error\":\"no result (exit or timeout)\"}"
        tail -5 "$out/last-stderr.txt" >&2
      fi
      echo "$line" | tee -a "$out/mesh-versus.jsonl"
    done
  done
done
