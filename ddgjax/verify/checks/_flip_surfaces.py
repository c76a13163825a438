"""Triangulated surfaces with skinny triangles, and the angle sums of their edges, shared by the
Sec 7 checks (`sec7_delaunay`, `sec7_empty_circle`)."""

from __future__ import annotations

import functools

import numpy as np

import ddgjax as dg
from ddgjax import intrinsic
from ddgjax.intrinsic import triangulation as T


def opposite_angle_sums(tri) -> np.ndarray:
    """(ne,) α + β: the angles opposite each edge, from `corner_angles` (side i of a face is
    opposite its corner i + 2), independent of the cotangent test of the flip algorithm."""
    return np.bincount(tri.edge, np.roll(T.corner_angles(tri), -2, axis=1).reshape(-1), minlength=tri.n_edges)


@functools.cache
def surfaces(level: int, n_inner: int, torus: tuple[int, int]):
    """name → (start, Delaunay by flips): the stretched icosphere (symmetric: exact ties; and with
    bumps), a skinny torus (m × n long thin quads, radii scaled by 1 + 0.05 N(0, 1)) and a flat disk
    with skinny random triangles (`tall_dome` at height 0)."""
    m, n = torus
    Vt, Ft = dg.mesh.torus(m, n, 1.0, 0.4)
    Vt = Vt * (1 + 0.05 * np.random.default_rng(0).standard_normal((len(Vt), 1)))
    meshes = {"stretched icosphere": dg.mesh.builtin.stretched_sphere(level),
              "bumpy stretched icosphere": dg.mesh.builtin.stretched_sphere(level, bumps=0.1),
              "skinny torus": (Vt, Ft), "flat disk": dg.mesh.builtin.tall_dome(0, n_inner=n_inner, height=0.0)[:2]}
    out = {}
    for name, (V, F) in meshes.items():
        tri = T.from_mesh(V, F)
        out[name] = tri, intrinsic.flip_to_delaunay(tri).triangulation
    return out


# quick sizes: 320 triangles each, the shape the compiled kernels of `sec7_delaunay` already ran on
SURFACES = dict(quick=dict(level=2, n_inner=145, torus=(5, 32)), full=dict(level=4, n_inner=400, torus=(12, 64)))
