#!/usr/bin/env bash
# bevy_plume against bevy_hanabi 0.20 on the same fountain (crates/bevy_plume/examples/versus_hanabi.rs),
# one headless Bevy app per run, both plugins alternated case by case, in one device call.
# Build here:
#   cd crates/bevy_plume && CARGO_PROFILE_RELEASE_STRIP=true cargo +nightly build --release \
#       --ignore-rust-version --features hanabi --example versus_hanabi
#   xz -T2 -6 -c target/release/examples/versus_hanabi > ../../.bench/versus_hanabi.xz
# Run there (with .gl unpacked as ../shared/tools/gpu-prep.sh says, Vulkan on the NVIDIA driver):
#   bash benchmarks/bevy-versus-hanabi.sh .bench/versus_hanabi.xz OUT
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
run empty --live 1
# Plume with each renderer (auto takes compute for 65,536 particles or more on a GPU); the
# compute renderer's fixed cost per effect is also measured on small effects.
for c in "--live 100000" "--live 1000000" "--live 10000000" "--live 1000 --effects 1"; do
  for p in "hanabi" "plume --draw raster" "plume --draw compute"; do
    run $p $c
  done
done
# Many small effects: the CPU's case, three rounds alternated (the two plugins' CPU times
# move by up to 15% from run to run), each round with the empty frame beside it.
for round in 1 2 3; do
  for c in "--live 1000 --effects 100" "--live 1000 --effects 1000"; do
    for p in "hanabi" "plume --draw auto"; do
      run $p $c
    done
  done
  run empty --live 1
done
run plume --draw compute --live 1000 --effects 100
# The side-by-side frames, 1M particles each.
timeout 150 "$bin" --plugin hanabi --live 1000000 --frames 5 --out "$out/hanabi-1M.png" >/dev/null 2>&1
for d in raster compute; do
  timeout 150 "$bin" --plugin plume --draw $d --live 1000000 --frames 5 --out "$out/plume-$d-1M.png" >/dev/null 2>&1
done
ls -la "$out"
