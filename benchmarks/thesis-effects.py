#!/usr/bin/env python3
"""Writes the effects of the thesis's matrix (docs/performance.md, "Baked fields"):
N position-dependent forces (two attractors for every vortex, spread over a 40 m box) over a
burst of particles filling it, evaluated per particle or baked into an n^3 grid, once or every
step. Usage: thesis-effects.py OUT_DIR"""
import os
import sys

out = sys.argv[1]
os.makedirs(out, exist_ok=True)


def forces(n):
    fs = []
    for i in range(n):
        # A fixed, even spread: golden-ratio steps on each axis.
        x = -18 + 36 * ((i * 0.618034) % 1)
        y = 2 + 16 * ((i * 0.754878) % 1)
        z = -18 + 36 * ((i * 0.569840) % 1)
        if i % 3 == 2:
            fs.append(f"Vortex(center: ({x:.3f}, 0.0, {z:.3f}), axis: (0.0, 1.0, 0.0), range: 4.0, "
                      f"height: 20.0, spin: 3.0, pull: 1.0, down: 0.5, curve: 0.5)")
        else:
            fs.append(f"Attractor(center: ({x:.3f}, {y:.3f}, {z:.3f}), range: 6.0, strength: 2.0)")
    return ",\n        ".join(fs)


for n in (15, 300):
    for field in ("evaluated", "once-16", "once-64", "once-128", "every-16", "every-64", "every-128"):
        if field == "evaluated":
            f = ""
        else:
            refresh, res = field.split("-")
            refresh = "Once" if refresh == "once" else "EveryStep"
            f = (f"field: Baked(resolution: ({res}, {res}, {res}), min: (-20.0, 0.0, -20.0), "
                 f"max: (20.0, 20.0, 20.0), filter: Trilinear, refresh: {refresh}),")
        with open(f"{out}/f{n}-{field}.ron", "w") as fh:
            fh.write(f"""Effect(
    name: "thesis f{n} {field}",
    capacity: 1000,
    emitters: [Emitter(burst: 1000, shape: Box(min: (-19.0, 1.0, -19.0), max: (19.0, 19.0, 19.0)),
                       velocity: Radial(speed: (0.0, 1.0)))],
    forces: [
        {forces(n)},
        Drag(k: 0.1),
    ],
    integrator: SemiImplicitEuler,
    {f}
)
""")
