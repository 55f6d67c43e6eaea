#!/usr/bin/env bash
# CPU time of 1,000 fountains of 1,000 particles (crates/bevy_plume/examples/versus_hanabi.rs)
# in two builds of the example, alternated in one device call beside bevy_hanabi, the empty app
# and a thousand bare entities (what a PlumeEffect requires, no plugin): a change to the
# plugin's per-entity CPU cost measured against the build before it on the same host.
# Build each as bevy-versus-hanabi.sh says, packed with xz. Run there:
#   bash benchmarks/bevy-thousand-builds.sh BEFORE.xz AFTER.xz OUT [ROUNDS] [MSAA] [LIVE]
# (LIVE, particles alive per effect, 1,000 unless given: 10 keeps lavapipe's GPU time small.)
# Then: python3 benchmarks/bevy-thousand-summary.py OUT/thousand.jsonl
set -u
before=$1; after=$2; out=$3; rounds=${4:-4}; msaa=${5:-1}; live=${6:-1000}
mkdir -p "$out"
unpack() { python3 -c "import lzma,sys; open(sys.argv[2],'wb').write(lzma.open(sys.argv[1]).read())" "$1" "$2"; chmod +x "$2"; }
unpack "$before" /tmp/versus-before
unpack "$after" /tmp/versus-after
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$out/device.txt"
for round in $(seq "$rounds"); do
  for run in "after empty" "after bare" "before plume" "after plume" "after hanabi"; do
    build=${run%% *}; plugin=${run##* }
    line=$(timeout 100 "/tmp/versus-$build" --plugin "$plugin" --live "$live" --effects 1000 \
      --msaa "$msaa" --frames 120 2>/dev/null | tail -1)
    [ -z "$line" ] && line="{\"plugin\":\"$plugin\",\"error\":\"no result\"}"
    echo "{\"round\":$round,\"build\":\"$build\",\"run\":$line}" | tee -a "$out/thousand.jsonl"
  done
done
