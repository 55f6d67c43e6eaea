#!/usr/bin/env python3
"""Writes the example effects' sprite textures (effects/textures/*.png), procedurally.

Standard library only, deterministic: `python3 effects/textures/generate.py` rewrites the same
bytes. Texels are white with the shape in alpha (the effect's colour stops tint them), except
where a shape wants shading of its own.

- bird.png: 4 frames (4 x 1) of a bird seen from above, head at the top (the direction of
  flight with `orient: Velocity`), through one wing beat.
- smoke.png: 16 frames (4 x 4) of a puff of smoke that swells, churns and thins out.
- smoke_normals.png: smoke.png's normal map (a lit look's `normals: Map`): each puff's surface
  a half sphere roughened by the noise that shapes it, (r, g, b) = (n + 1) / 2 with x right,
  y up and z toward the viewer; opaque.
- smoke_rtb.png, smoke_lbf.png: smoke.png's six-way lightmaps (`normals: SixWay`), baked
  from that normal and the puff's density: light from the right, top and back in the first
  one's red, green and blue, from the left, bottom and front in the second one's. A side
  lets through 0.15 + 0.85 max(n . d, 0) of a light from direction d; the back, where light
  comes through the puff, 0.15 + 0.6 (1 - alpha). Opaque.
- snowflake.png: one six-armed flake with side branches.
- cloud.png: a soft, lumpy cloud as a greyscale mask: its density in red, green and blue,
  opaque (for `sample: OpacityFromRed`, where the red channel is the sprite's shape).
- blobs.png: 64 frames (8 x 8) of a noisy blob whose lumps shift from frame to frame, its
  density in red, green and blue, opaque (a shape for `sample: OpacityFromRed`).
- ramp.png: a colour ramp across the image, blobs.png's size, opaque: blobs.png's second image
  (`second: Some(SecondTexture(file: "ramp.png", sample: ModulateRgb))`), so each column of
  frames takes its own colours.
"""

import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def write_png(path, width, height, pixel):
    """`pixel(x, y)` -> (r, g, b, a) in [0, 1]; rows top to bottom."""
    rows = bytearray()
    for y in range(height):
        rows.append(0)  # filter: none
        for x in range(width):
            rows.extend(max(0, min(255, round(c * 255))) for c in pixel(x, y))
    chunk = lambda kind, data: (
        struct.pack(">I", len(data)) + kind + data
        + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                + chunk(b"IDAT", zlib.compress(bytes(rows), 9)) + chunk(b"IEND", b""))


def supersampled(inside, x, y, size, n=4):
    """Fraction of an n x n grid of samples in texel (x, y) for which `inside(u, v)` holds,
    u, v in [-1, 1] across the frame, v up."""
    hits = 0
    for j in range(n):
        for i in range(n):
            u = ((x + (i + 0.5) / n) / size) * 2.0 - 1.0
            v = 1.0 - ((y + (j + 0.5) / n) / size) * 2.0
            hits += inside(u, v)
    return hits / (n * n)


def bird(phase):
    """A bird from above at `phase` of its wing beat (0: wings spread level)."""
    lift = math.sin(2.0 * math.pi * phase)  # > 0: wings raised, seen shorter from above
    span = 0.92 * (1.0 - 0.45 * abs(lift))
    sweep = 0.22 * lift  # tips swept back on the up stroke, forward on the down stroke

    def inside(u, v):
        # Body: a slim ellipse along v; head: a small disc in front; tail: a wedge behind.
        if (u / 0.11) ** 2 + ((v - 0.05) / 0.5) ** 2 <= 1.0:
            return True
        if u * u + (v - 0.55) ** 2 <= 0.1 ** 2:
            return True
        if -0.75 <= v <= -0.35 and abs(u) <= 0.08 + 0.35 * (-0.35 - v):
            return True
        # Wings: from the shoulders (v = 0.15) out to +-span, thinning towards the tips.
        a = abs(u)
        if a <= span:
            t = a / span
            lead = 0.2 - sweep * t * t - 0.05 * t  # leading edge
            chord = 0.32 * (1.0 - t) + 0.05  # wing depth
            return lead - chord <= v <= lead
        return False

    return inside


def snowflake(u, v):
    r = math.hypot(u, v)
    if r > 0.98:
        return False
    angle = math.atan2(v, u)
    # Fold onto one arm along angle 0 (six-fold symmetry, mirrored).
    sector = math.pi / 3.0
    a = (angle + sector / 2.0) % sector - sector / 2.0
    x, y = r * math.cos(a), abs(r * math.sin(a))
    if r < 0.16:
        return True  # the hexagonal core, roughly
    if y <= 0.045 and x <= 0.95:
        return True  # the arm
    # Side branches at 60 degrees from the arm, at three distances out.
    for base, length in ((0.35, 0.28), (0.6, 0.22), (0.8, 0.12)):
        along = (x - base) * 0.5 + y * (math.sqrt(3.0) / 2.0)
        across = abs(-(x - base) * (math.sqrt(3.0) / 2.0) + y * 0.5)
        if 0.0 <= along <= length and across <= 0.035:
            return True
    return False


def lattice(ix, iy, seed):
    """A value in [0, 1) per integer lattice point (an integer hash, PCG's output step)."""
    h = (ix * 374761393 + iy * 668265263 + seed * 2246822519) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    h = ((h >> ((h >> 28) + 4)) ^ h) * 277803737 & 0xFFFFFFFF
    return ((h >> 22) ^ h) / 4294967296.0


def value_noise(x, y, seed):
    ix, iy = math.floor(x), math.floor(y)
    fx, fy = x - ix, y - iy
    sx, sy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
    a, b = lattice(ix, iy, seed), lattice(ix + 1, iy, seed)
    c, d = lattice(ix, iy + 1, seed), lattice(ix + 1, iy + 1, seed)
    return (a + (b - a) * sx) + ((c + (d - c) * sx) - (a + (b - a) * sx)) * sy


def fbm(x, y, seed):
    total, amplitude, norm = 0.0, 1.0, 0.0
    for octave in range(4):
        total += amplitude * value_noise(x, y, seed + octave)
        norm += amplitude
        x, y, amplitude = x * 2.03, y * 2.03, amplitude * 0.5
    return total / norm


def smoke(frame, frames):
    """Frame `frame` of a puff: it swells from 55% to 100% of the frame, churns (the noise
    drifts and turns) and thins out."""
    t = frame / (frames - 1)
    radius = 0.55 + 0.4 * t
    density = 1.0 - 0.55 * t
    turn = 0.6 * t

    def texel(u, v):
        r = math.hypot(u, v) / radius
        if r >= 1.0:
            return (1.0, 1.0, 1.0, 0.0)
        cu = u * math.cos(turn) - v * math.sin(turn)
        cv = u * math.sin(turn) + v * math.cos(turn)
        n = fbm(cu * 1.7 + 10.0, cv * 1.7 - 0.8 * t + 10.0, 17)
        falloff = 1.0 - r * r
        a = max(0.0, min(1.0, (n - 0.15) * 2.5)) * falloff * density
        shade = 0.8 + 0.2 * n  # lighter where thicker
        return (shade, shade, shade, a)

    return texel


def smoke_normal(frame, frames):
    """Frame `frame` of smoke.png's normal map: the gradient of a height that is a half
    sphere of the puff's radius, bumped by the puff's own noise."""
    t = frame / (frames - 1)
    radius = 0.55 + 0.4 * t
    turn = 0.6 * t

    def height(u, v):
        r2 = (u * u + v * v) / (radius * radius)
        cu = u * math.cos(turn) - v * math.sin(turn)
        cv = u * math.sin(turn) + v * math.cos(turn)
        n = fbm(cu * 1.7 + 10.0, cv * 1.7 - 0.8 * t + 10.0, 17)
        return radius * math.sqrt(max(0.0, 1.0 - r2)) * (0.7 + 0.6 * n)

    def texel(u, v):
        e = 1.0 / 64.0
        dx = (height(u + e, v) - height(u - e, v)) / (2 * e)
        dy = (height(u, v + e) - height(u, v - e)) / (2 * e)
        n = (-dx, -dy, 1.0)
        length = math.sqrt(sum(c * c for c in n))
        return tuple(0.5 * c / length + 0.5 for c in n) + (1.0,)

    return texel


def main():
    size = 64
    # bird.png: 4 frames side by side.
    beats = [bird(k / 4.0) for k in range(4)]
    write_png(os.path.join(HERE, "bird.png"), 4 * size, size,
              lambda x, y: (1.0, 1.0, 1.0,
                            supersampled(beats[x // size], x % size, y, size)))
    # smoke.png: 4 x 4 frames, left to right, top to bottom.
    puffs = [smoke(k, 16) for k in range(16)]

    def frame_of(x, y):
        """Texel (x, y) of a 4 x 4 atlas of size-texel frames: its frame k and its (u, v) in
        [-1, 1] across the frame, v up."""
        k = (y // size) * 4 + x // size
        u = ((x % size + 0.5) / size) * 2.0 - 1.0
        v = 1.0 - ((y % size + 0.5) / size) * 2.0
        return k, u, v

    def smoke_texel(x, y):
        k, u, v = frame_of(x, y)
        return puffs[k](u, v)

    write_png(os.path.join(HERE, "smoke.png"), 4 * size, 4 * size, smoke_texel)
    normals = [smoke_normal(k, 16) for k in range(16)]

    def normal_texel(x, y):
        k, u, v = frame_of(x, y)
        return normals[k](u, v)

    write_png(os.path.join(HERE, "smoke_normals.png"), 4 * size, 4 * size, normal_texel)

    def six_way(first):
        def texel(x, y):
            n = [c * 2.0 - 1.0 for c in normal_texel(x, y)[:3]]
            alpha = smoke_texel(x, y)[3]
            side = lambda d: 0.15 + 0.85 * max(0.0, sum(a * b for a, b in zip(n, d)))
            if first:
                return (side((1, 0, 0)), side((0, 1, 0)), 0.15 + 0.6 * (1.0 - alpha), 1.0)
            return (side((-1, 0, 0)), side((0, -1, 0)), side((0, 0, 1)), 1.0)
        return texel

    write_png(os.path.join(HERE, "smoke_rtb.png"), 4 * size, 4 * size, six_way(True))
    write_png(os.path.join(HERE, "smoke_lbf.png"), 4 * size, 4 * size, six_way(False))
    write_png(os.path.join(HERE, "snowflake.png"), size, size,
              lambda x, y: (1.0, 1.0, 1.0, supersampled(snowflake, x, y, size)))

    def cloud(x, y):
        u = ((x + 0.5) / size) * 2.0 - 1.0
        v = ((y + 0.5) / size) * 2.0 - 1.0
        r = math.sqrt(u * u + v * v)
        lumps = fbm(u * 2.5 + 7.0, v * 2.5 + 3.0, 41)
        density = max(0.0, min(1.0, (1.0 - r * (0.8 + 0.6 * lumps)) * 1.8))
        return (density, density, density, 1.0)

    write_png(os.path.join(HERE, "cloud.png"), size, size, cloud)

    blob, grid = 64, 8

    def blobs(x, y):
        k = (y // blob) * grid + x // blob
        u = ((x % blob + 0.5) / blob) * 2.0 - 1.0
        v = ((y % blob + 0.5) / blob) * 2.0 - 1.0
        # The lumps drift through time: noise of the frame's slice, blended between the two
        # lattice slices it lies between.
        z = k * 0.15
        z0, f = math.floor(z), z - math.floor(z)
        f = f * f * (3.0 - 2.0 * f)
        n = (1.0 - f) * fbm(u * 3.0 + 5.0, v * 3.0 + 5.0, 100 + 7 * z0) + f * fbm(
            u * 3.0 + 5.0, v * 3.0 + 5.0, 107 + 7 * z0)
        falloff = max(0.0, 1.0 - math.hypot(u, v) / 0.9)
        density = max(0.0, min(1.0, n * 1.6 * falloff))
        return (density, density, density, 1.0)

    write_png(os.path.join(HERE, "blobs.png"), grid * blob, grid * blob, blobs)

    def ramp(x, y):
        h = 0.75 * (x + 0.5) / (grid * blob)
        w = 0.6 + 0.4 * (y + 0.5) / (grid * blob)
        # A hue from red through yellow and green to blue, lighter down the image.
        r = max(0.0, min(1.0, abs(h * 6.0 - 3.0) - 1.0))
        g = max(0.0, min(1.0, 2.0 - abs(h * 6.0 - 2.0)))
        b = max(0.0, min(1.0, 2.0 - abs(h * 6.0 - 4.0)))
        return (r * w + (1.0 - w) * 0.5, g * w + (1.0 - w) * 0.5, b * w + (1.0 - w) * 0.5, 1.0)

    write_png(os.path.join(HERE, "ramp.png"), grid * blob, grid * blob, ramp)


if __name__ == "__main__":
    main()
