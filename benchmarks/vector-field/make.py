#!/usr/bin/env python3
"""Writes the vector-field benchmark's inputs next to this script: swirl.fga (a 33 x 17 x 33
swirl with a ripple, 18,513 nodes) and two effects that differ only in that force:
with_field.ron and without_field.ron. Run: python3 make.py, then bench.sh."""
import os

here = os.path.dirname(os.path.abspath(__file__))
nx, ny, nz = 33, 17, 33
lines = [f"{nx},{ny},{nz},", "-8,0,-8,", "8,8,8,"]
for k in range(nz):
    for j in range(ny):
        for i in range(nx):
            x, y, z = -8 + 0.5 * i, 0.5 * j, -8 + 0.5 * k
            ripple = 0.3 * ((i * 7 + j * 3 + k * 5) % 4)
            lines.append(f"{-z + ripple:.4f},{0.5 + 0.1 * y:.4f},{x:.4f},")
open(os.path.join(here, "swirl.fga"), "w").write("\n".join(lines) + "\n")

effect = """Effect(name: "swirl", capacity: 1000000, seed: 8, dt: 0.016666666666666666,
    emitters: [Emitter(rate: 400000.0, shape: Disc(center: (0.0, 0.2, 0.0), normal: (0.0, 1.0, 0.0), radius: 7.0),
        velocity: Constant((0.0, 0.5, 0.0)), lifetime: Some((2.0, 3.0)))],
    forces: [{field}Drag(k: 0.4)],
    integrator: SemiImplicitEuler)
"""
open(os.path.join(here, "with_field.ron"), "w").write(
    effect.format(field='VectorField(file: "swirl.fga", strength: 2.0), '))
open(os.path.join(here, "without_field.ron"), "w").write(effect.format(field=""))
