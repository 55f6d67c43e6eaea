#!/usr/bin/env bash
# bevy_plume against bevy_hanabi 0.20 on the same fountain (crates/bevy_plume/examples/versus_hanabi.rs),
# one headless Bevy app per run, the two plugins alternated case by case, in one device call:
# MSAA off and 4x, fountains of 1M and 10M particles, 1,000 effects of 1,000 (two rounds), the
# 1M fountain in a Camera2d view, and the empty app beside each; then a thousand bare entities
# beside the thousand effects. Every line has frame, CPU and
# GPU times (median and p90 over 120 frames) and the last frame's lit pixels.
# Build here:
#   cd crates/bevy_plume && CARGO_PROFILE_RELEASE_STRIP=true cargo +nightly build --release \
#       --ignore-rust-version --features hanabi --example versus_hanabi
#   xz -T2 -6 -c target/release/examples/versus_hanabi > ../../.bin/versus_hanabi.xz
# Run there (with .gl unpacked as ../shared/tools/gpu-prep.sh says, Vulkan on the NVIDIA driver):
#   bash benchmarks/bevy-versus-hanabi.sh .bin/versus_hanabi.xz OUT
# Then: python3 benchmarks/bevy-versus-summary.py OUT/versus.jsonl
set -u
packed=$1; out=$2; mkdir -p "$out"
bin=/tmp/versus_hanabi
python3 -c "import lzma,sys; open(sys.argv[2],'wb').write(lzma.open(sys.argv[1]).read())" "$packed" "$bin"
chmod +x "$bin"
run() { # plugin, then the case's arguments
  local line
  line=$(timeout 170 "$bin" --plugin "$@" --frames 120 2>"$out/last-stderr.txt" | tail -1)
  if [ -z "$line" ]; then
    line="{\"plugin\":\"$1\",\"case\":\"${*:2}\",\"error\":\"no result (exit or timeout); see stderr\"}"
    tail -5 "$out/last-stderr.txt" >&2
  fi
  echo "$line" | tee -a "$out/versus.jsonl"
}
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$out/device.txt"
for msaa in 1 4; do
  run empty --live 1 --msaa $msaa
  for live in 1000000 10000000; do
    for p in "hanabi" "plume --draw auto"; do
      shot=""; [ $msaa = 1 ] && shot="--out $out/${p%% *}-$live.png"
      run $p --live $live --msaa $msaa $shot
    done
  done
  for round in 1 2; do
    for p in "hanabi" "plume --draw auto"; do
      run $p --live 1000 --effects 1000 --msaa $msaa
    done
  done
  run empty --live 1 --msaa $msaa --view 2d
  for p in "hanabi" "plume --draw auto"; do
    shot=""; [ $msaa = 1 ] && shot="--out $out/${p%% *}-2d.png"
    run $p --live 1000000 --view 2d --msaa $msaa $shot
  done
done
# Where the CPU time of a thousand effects goes: the same app with a thousand bare entities
# (what a PlumeEffect requires, no plugin) beside each plugin's, four rounds (floor.jsonl).
for round in 1 2 3 4; do
  for p in empty bare plume hanabi; do
    timeout 100 "$bin" --plugin $p --live 1000 --effects 1000 --frames 120 2>/dev/null | tail -1 \
      | tee -a "$out/floor.jsonl"
  done
done
ls -la "$out"
