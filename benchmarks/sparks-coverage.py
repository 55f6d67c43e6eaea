#!/usr/bin/env python3
"""How much drawing the sparks 10M frame of the goals holds (docs/performance.md, "What bounds
sparks"): a Monte Carlo model of effects/sparks.ron after `plume bench --steps 5` (dt 1/60,
every spark of the burst alive), projected as the compute renderer projects it at 1280x720. It counts, a
spark on average: the pixels its streak covers (the fragments any renderer must shade), the
pixels of its box (what a box test visits), and the 16x16 tiles its box touches (the
compute renderer's entries: compare with `compute_entries` of the bench, 53.7M). Pure Python, no numpy:
python3 benchmarks/sparks-coverage.py [SAMPLES]
"""
import math
import random
import sys

samples = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
random.seed(1)
# effects/sparks.ron: a burst from (0, 1, 0), radial speed 4 to 12, lifetime 0.6 to 1.4 s,
# gravity and drag k = 1.5 (closed form), size 0.07 -> 0.03 over life, streaks along the
# velocity's image-plane part: length max(size, min(size + 0.04 speed, 0.45)), width size.
t = 5 / 60
k = 1.5
g = (0.0, -9.81, 0.0)
decay = math.exp(-k * t)


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def mul(a, s):
    return tuple(x * s for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def unit(a):
    return mul(a, 1 / math.sqrt(dot(a, a)))


eye, target = (0.0, 2.0, 8.0), (0.0, 1.0, 0.0)
forward = unit(sub(target, eye))
right = unit(cross(forward, (0.0, 1.0, 0.0)))
up = cross(right, forward)
width, height = 1280, 720
focal = (height / 2) / math.tan(math.radians(50 / 2))


def pixel(p):
    q = sub(p, eye)
    z = dot(q, forward)
    return (width / 2 + dot(q, right) / z * focal, height / 2 - dot(q, up) / z * focal)


covered = boxed = tiles = 0.0
for _ in range(samples):
    direction = unit((random.gauss(0, 1), random.gauss(0, 1), random.gauss(0, 1)))
    v0 = mul(direction, random.uniform(4, 12))
    terminal = mul(g, 1 / k)
    v = add(terminal, mul(sub(v0, terminal), decay))
    x = add(add((0.0, 1.0, 0.0), mul(g, t / k)), mul(sub(v0, terminal), (1 - decay) / k))
    size = 0.07 + (0.03 - 0.07) * t / random.uniform(0.6, 1.4)
    vx, vy = dot(v, right), dot(v, up)
    speed = math.hypot(vx, vy)
    along = (vx / speed, vy / speed)
    length = max(size, min(size + 0.04 * speed, 0.45))
    half_x = mul(add(mul(right, along[1]), mul(up, -along[0])), 0.5 * size)
    half_y = mul(add(mul(right, along[0]), mul(up, along[1])), 0.5 * length)
    corners = [pixel(add(add(x, mul(half_x, a)), mul(half_y, b))) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    covered += 0.5 * abs(sum(corners[i][0] * corners[(i + 1) % 4][1] - corners[(i + 1) % 4][0] * corners[i][1] for i in range(4)))
    first = [max(0, math.ceil(min(c[i] for c in corners) - 0.5)) for i in (0, 1)]
    last = [min((width, height)[i] - 1, math.floor(max(c[i] for c in corners) - 0.5)) for i in (0, 1)]
    if first[0] <= last[0] and first[1] <= last[1]:
        boxed += (last[0] - first[0] + 1) * (last[1] - first[1] + 1)
        tiles += (last[0] // 16 - first[0] // 16 + 1) * (last[1] // 16 - first[1] // 16 + 1)

n = 10_000_000
print(f"a spark: {covered / samples:.1f} pixels covered, {boxed / samples:.1f} in its box, {tiles / samples:.2f} tiles")
print(f"10M sparks: {covered / samples * n / 1e9:.2f} G fragments, {boxed / samples * n / 1e9:.2f} G box pixels, {tiles / samples * n / 1e6:.1f} M entries")
