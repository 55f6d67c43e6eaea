#!/usr/bin/env bash
# The speed issue's figures (docs/performance.md: "Depth sort", "Flocking", "The update at
# large sizes"), all from one device call. Usage: speed-bench.sh PLUME OUT_DIR [PARTS]
# PARTS: a comma-separated choice of sort, flock, update (default: all three)
#   sort.jsonl    the radix sort alone on 1M and 16M random pairs (`--sort-keys`: every ranking
#                 the adapter runs, 32- and 16-bit keys, per-stage times) and with the depth keys
#                 of fountain.ron (`sort: true`)
#   torch.txt     torch.sort (CUB's radix sort) of the same counts of f32 keys and of int16
#                 keys, stable, with indices, on the same GPU (skipped where python3 has no CUDA torch)
#   flock.jsonl   effects/boids.ron at 256 and 4,096 boids (the pipeline's launch floor) and at 16k to 1M
#                 boids: the step, and each stage of the flocking pass
#   update.jsonl  fountain.ron's update, and update-floor.ron's (an update that does almost
#                 nothing), at 1M to 100M against the copy kernel and an in-place copy
#   layouts.txt   examples/update_layouts (when its binary is beside PLUME): the same update on
#                 particle-major and word-major words, staged or not, against the copy, and
#                 whether the copy's speed depends on the data, the buffers or the time
set -euo pipefail
plume=$1
out=$2
parts=",${3:-sort,flock,update},"
mkdir -p "$out"
if [[ $parts == *,sort,* ]]; then
for n in 1048576 16777216; do
    "$plume" bench effects/fountain.ron --particles "$n" --steps 20 --sort-keys "$n" --json
done >"$out/sort.jsonl"
python3 - >"$out/torch.txt" 2>&1 <<'PY' || true
import torch
def median_ms(keys):
    for _ in range(3):
        torch.sort(keys, stable=True)
    torch.cuda.synchronize()
    times = []
    for _ in range(9):
        start, end = torch.cuda.Event(enable_timing=True), torch.cuda.Event(enable_timing=True)
        start.record()
        torch.sort(keys, stable=True)
        end.record()
        torch.cuda.synchronize()
        times.append(start.elapsed_time(end))
    times.sort()
    return times[4]
for n in [1 << 20, 16 << 20]:
    t = median_ms(torch.rand(n, device="cuda", dtype=torch.float32))
    print(f"torch.sort n={n} f32 keys + int64 indices, stable: {t:.3f} ms, {n / t / 1e6:.2f} G keys/s")
    # 16-bit keys, as the depth sort's: CUB sorts only their 16 bits.
    t = median_ms(torch.randint(-32768, 32767, (n,), device="cuda", dtype=torch.int16))
    print(f"torch.sort n={n} int16 keys + int64 indices, stable: {t:.3f} ms, {n / t / 1e6:.2f} G keys/s")
PY
fi
if [[ $parts == *,flock,* ]]; then
for n in 256 4096 16384 65536 131072 262144 1048576; do
    "$plume" bench effects/boids.ron --particles "$n" --steps 50 --json
done >"$out/flock.jsonl"
fi
if [[ $parts == *,update,* ]]; then
for e in benchmarks/update-floor.ron effects/fountain.ron; do
    for n in 1000000 10000000 16777216 100000000; do
        "$plume" bench "$e" --particles "$n" --steps 50 --json
    done
done >"$out/update.jsonl"
layouts=$(dirname "$plume")/examples/update_layouts
if [ -x "$layouts" ]; then
    "$layouts" 1048576,10000000,16777216,60000000 >"$out/layouts.txt" 2>&1
fi
fi
