#!/usr/bin/env python3
"""Writes ball.obj next to this script: a unit sphere of 24 rings and 48 segments (2,208
triangles), the mesh the Mesh-collider measurements collide with."""
import math
import os

rings, segments = 24, 48
lines = ["o ball", "v 0 1 0"]
for r in range(1, rings + 1):
    theta = math.pi * r / (rings + 1)
    for k in range(segments):
        phi = 2 * math.pi * k / segments
        lines.append("v %.7f %.7f %.7f" % (math.sin(theta) * math.cos(phi), math.cos(theta),
                                           math.sin(theta) * math.sin(phi)))
lines.append("v 0 -1 0")
at = lambda r, k: 2 + (r - 1) * segments + k % segments
bottom = 2 + rings * segments
for k in range(segments):
    lines.append("f 1 %d %d" % (at(1, k + 1), at(1, k)))
    for r in range(1, rings):
        lines.append("f %d %d %d %d" % (at(r, k), at(r, k + 1), at(r + 1, k + 1), at(r + 1, k)))
    lines.append("f %d %d %d" % (bottom, at(rings, k), at(rings, k + 1)))
with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "ball.obj"), "w") as f:
    f.write("\n".join(lines) + "\n")
