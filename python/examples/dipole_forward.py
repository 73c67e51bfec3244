#!/usr/bin/env python3
"""A forward solution from Python: a rotating dipole's potentials on a model's heart surface, carried
to the body surface by thorax's finite-element solver.

usage: dipole_forward.py MODEL OUT [--frames N] [--grid MM]

  MODEL   a thorax model directory (thorax surfaces, thorax import); meshed here if it has no volume
  OUT     the body-surface potentials written as a series (.raw, .txt or .mat by extension)

For example, with the Dalhousie torso from map3d:

  thorax import -o dal --up -y --front -z daltorso.pts --name torso --role outer \\
                dalepi.pts --name epicardium --role heart
  python3 dipole_forward.py dal torso.mat

The heart's potentials: a unit current dipole at the heart's centroid turning once about the
model's z axis over the frames, phi = p.(x - c) / (4 pi sigma |x - c|^3) with sigma 0.2 S/m (mV for
p in mA m, x in mm; the same formula as `thorax beat`), evaluated at the heart's nodes.
Prints the model, the mesh, and each frame's heart and torso ranges.
"""
import argparse
import sys

import numpy as np

import thorax


def dipole_potentials(nodes, centre, p, sigma=0.2):
    """mV at nodes (mm) of a current dipole p (mA m) at centre (mm) in an unbounded medium of
    conductivity sigma (S/m): with r in m, p in mA m gives mV."""
    d = (nodes - centre) * 1e-3  # m
    return d @ p / (4 * np.pi * sigma * np.linalg.norm(d, axis=1) ** 3)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model")
    ap.add_argument("out")
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--grid", type=float, default=0.0, help="mesh grid spacing in mm (0: thorax mesh's default)")
    a = ap.parse_args()

    m = thorax.Model.read(a.model)
    for s in m.surfaces:
        print(f"surface {s.name:12s} {s.role:7s} {len(s.nodes):6d} nodes {len(s.triangles):6d} triangles")
    if m.volume is None:
        nodes, tets = m.mesh(grid=a.grid)
        print(f"meshed: {nodes} nodes, {tets} tetrahedra")
    for name, sigma in m.regions:
        print(f"region {name:12s} sigma {np.diag(sigma)} S/m")

    heart = m.surface(role="heart")
    centre = heart.nodes.mean(axis=0)
    angles = np.linspace(0, 2 * np.pi, a.frames, endpoint=False)
    phi = np.stack([dipole_potentials(heart.nodes, centre, 0.1 * np.array([np.cos(t), np.sin(t), 0.0]))
                    for t in angles], axis=1)
    heart_series = thorax.Series(phi, time=np.arange(a.frames) * 10.0, unit="mV")

    torso = m.forward(heart_series)
    for f in range(a.frames):
        print(f"frame {f:3d} ({heart_series.time[f]:5.0f} ms): heart {phi[:, f].min():8.3f} .. {phi[:, f].max():7.3f} mV,"
              f" torso {torso.values[:, f].min():7.3f} .. {torso.values[:, f].max():6.3f} mV")
    torso.write(a.out)
    print(f"wrote {a.out} ({torso.values.shape[0]} rows x {torso.values.shape[1]} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
