#!/usr/bin/env python3
"""Writes the example meshes next to this script: rock.obj (a lumpy boulder: a sphere of 20
rings and 40 segments whose radius follows a few fixed waves), crystal.obj (a hexagonal
prism with pointed ends), steps.obj (a flight of four stone steps on a ground slab) and
floor.obj (a flat 12 m square at y = 0, facing up), wall.obj (a stone wall 4 m high, 5 m
long and 0.3 m thick, standing on y = 0 across x = -2: what casts the shadow in
shadowed_smoke.ron) and ico.obj (a sphere of radius 0.5, an
icosahedron whose faces are split in four three times: 1280 triangles, a mesh particle's
shape). Deterministic: run it again and the files come out the same."""

import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def write(name, vertices, faces, comment):
    with open(os.path.join(HERE, name), "w") as f:
        f.write(f"# {comment}\n# Written by make_meshes.py.\no {name[:-4]}\n")
        for v in vertices:
            f.write("v %.6f %.6f %.6f\n" % v)
        for face in faces:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")


def rock(rings=20, segments=40):
    def radius(theta, phi):
        return (1.0 + 0.12 * math.sin(3 * phi + 1.0) * math.sin(2 * theta)
                + 0.08 * math.cos(5 * phi) * math.sin(theta) ** 2
                + 0.06 * math.sin(4 * theta + 2 * phi))

    vertices = [(0.0, radius(0.0, 0.0) * 0.85, 0.0)]
    for r in range(1, rings + 1):
        theta = math.pi * r / (rings + 1)
        for k in range(segments):
            phi = 2 * math.pi * k / segments
            rad = radius(theta, phi)
            # Flattened a little: a boulder sits, it does not roll.
            vertices.append((rad * math.sin(theta) * math.cos(phi),
                             0.85 * rad * math.cos(theta),
                             rad * math.sin(theta) * math.sin(phi)))
    vertices.append((0.0, -0.85 * radius(math.pi, 0.0), 0.0))
    at = lambda r, k: 1 + (r - 1) * segments + k % segments
    bottom = len(vertices) - 1
    faces = []
    for k in range(segments):
        faces.append((0, at(1, k + 1), at(1, k)))
        for r in range(1, rings):
            faces.append((at(r, k), at(r, k + 1), at(r + 1, k + 1), at(r + 1, k)))
        faces.append((bottom, at(rings, k), at(rings, k + 1)))
    write("rock.obj", vertices, faces, "A lumpy boulder, about 2 m across, centred on its origin.")


def crystal(sides=6, half_length=0.6, radius=0.3, tip=0.35):
    vertices = [(0.0, half_length + tip, 0.0)]
    for y in (half_length, -half_length):
        for k in range(sides):
            phi = 2 * math.pi * k / sides
            vertices.append((radius * math.cos(phi), y, radius * math.sin(phi)))
    vertices.append((0.0, -half_length - tip, 0.0))
    top = lambda k: 1 + k % sides
    low = lambda k: 1 + sides + k % sides
    bottom = len(vertices) - 1
    faces = []
    for k in range(sides):
        faces.append((0, top(k + 1), top(k)))
        faces.append((top(k), top(k + 1), low(k + 1), low(k)))
        faces.append((bottom, low(k), low(k + 1)))
    write("crystal.obj", vertices, faces, "A hexagonal crystal with pointed ends, along y.")


def steps(count=4, rise=0.3, tread=0.5, width=3.0):
    vertices, faces = [], []

    def box(lo, hi):
        box_faces(vertices, faces, lo, hi)

    box((-6.0, -0.1, -6.0), (6.0, 0.0, 6.0))
    for k in range(count):
        # Step k (0 the lowest) is k + 1 rises high, its front edge k treads back from z = 1;
        # every step reaches back to z = -2 (the boxes overlap: this is drawn, not filled).
        box((-width / 2, 0.0, -2.0), (width / 2, rise * (k + 1), 1.0 - tread * k))
    write("steps.obj", vertices, faces, "Four stone steps climbing towards -z on a 12 m ground slab.")


def box_faces(vertices, faces, lo, hi):
    base = len(vertices)
    for k in range(8):
        vertices.append(tuple(hi[a] if k >> a & 1 else lo[a] for a in range(3)))
    # Corner k has x from bit 0, y from bit 1, z from bit 2; faces wind outward.
    for q in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3)):
        faces.append(tuple(base + i for i in q))


def wall():
    vertices, faces = [], []
    box_faces(vertices, faces, (-2.15, 0.0, -2.5), (-1.85, 4.0, 2.5))
    write("wall.obj", vertices, faces, "A stone wall 4 m high and 5 m long across x = -2.")


def floor(half=6.0):
    vertices = [(-half, 0.0, -half), (half, 0.0, -half), (half, 0.0, half), (-half, 0.0, half)]
    # Wound counter-clockwise seen from above: the face points up.
    write("floor.obj", vertices, [(0, 3, 2, 1)], "A flat 12 m square at y = 0, facing up.")


def ico(splits=3, radius=0.5):
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    vertices = [tuple(c / math.sqrt(1 + t * t) for c in v) for v in vertices]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(splits):
        middle = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                m = [(x + y) / 2.0 for x, y in zip(vertices[a], vertices[b])]
                n = math.sqrt(sum(c * c for c in m))
                vertices.append(tuple(c / n for c in m))
                middle[key] = len(vertices) - 1
            return middle[key]

        split = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = split
    vertices = [tuple(c * radius for c in v) for v in vertices]
    write("ico.obj", vertices, faces, f"A sphere of radius {radius}: an icosahedron split {splits} times.")


rock()
crystal()
steps()
floor()
wall()
ico()
