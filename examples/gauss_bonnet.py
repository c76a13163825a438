"""Gauss–Bonnet (Thm 5.6) on the built-in meshes: the angle defects sum to 2πχ whatever the
geometry, and the classification (Thm 4.1) names the surface.

    python examples/gauss_bonnet.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax import mesh

MESHES = ("tetrahedron", "cube", "icosphere", "torus", "double_torus", "disk", "annulus", "mobius_strip",
          "projective_plane", "klein_bottle")


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    for name in MESHES[:4] if tiny else MESHES:
        V, F = getattr(mesh, name)()
        total = float(np.sum(np.asarray(mesh.angle_defect(V, F))))
        print(f"{name:17s} χ = {mesh.euler_characteristic(F):2d}   Σ K / 2π = {total / (2 * np.pi):+.12f}   {mesh.classify(F)}")
    drawn = ("torus",) if tiny else ("torus", "double_torus")
    return [dg.plot.surface.surface(*getattr(mesh, name)(), path=out / f"gauss_bonnet_{name}.png", title=f"angle defect, {name}")
            for name in drawn]


if __name__ == "__main__":
    run(main, __doc__)
