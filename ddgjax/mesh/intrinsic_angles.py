"""Angles and angle defects from edge lengths alone (Sec 5.3, Thm 5.5).

A triangulation with an edge-length function satisfying every triangle inequality defines a
polyhedral metric (Def 5.5, 5.6); its corner angles come from the law of cosines, and the angle
defects depend on the lengths only: the polyhedral Theorema Egregium (Thm 5.5).  Edge-indexed
arrays are ordered like `connectivity.edges(F)`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._checks import is_concrete
from ..errors import ShapeError, TriangleInequalityError
from .connectivity import from_faces
from .curvature import boundary_vertex_mask, defect_from_angles

__all__ = ["edge_lengths", "face_side_lengths", "corner_angles_from_lengths", "angle_defect_from_lengths"]


def edge_lengths(V, F):
    """l(e) = |v_j − v_i| for each edge (i, j) of `edges(F)`, (ne,)."""
    E = from_faces(np.asarray(F), n_vertices=jnp.shape(V)[0]).edges
    return _lengths(jnp.asarray(V), E)


@jax.jit
def _lengths(V, E):
    return jnp.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=-1)


def _triangles(F) -> np.ndarray:
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3:
        raise ShapeError(f"intrinsic angles need triangles, F of shape (nf, 3); got {F.shape}")
    return F


def face_side_lengths(F, lengths):
    """(nf, 3): entry [f, i] is the length of the side of face f opposite its corner i, i.e. of
    the edge (F[f, i+1], F[f, i+2]).
    """
    F = _triangles(F)
    h = from_faces(F)
    lengths = jnp.asarray(lengths)
    if lengths.shape != (h.n_edges,):
        raise ShapeError(f"lengths must have shape ({h.n_edges},) (one per edge of F), got {lengths.shape}")
    opposite = np.roll(h.edge.reshape(-1, 3), -1, axis=1)
    return lengths[opposite]


def _check_triangle_inequalities(L) -> None:
    if not is_concrete(L):
        return
    L = np.asarray(L)
    slack = L.sum(axis=1, keepdims=True) - 2 * L
    bad = np.argwhere(slack < 0)
    if bad.size:
        f = int(bad[0, 0])
        raise TriangleInequalityError(
            f"face {f} has side lengths {tuple(float(x) for x in L[f])}: the side opposite corner "
            f"{int(bad[0, 1])} is longer than the other two together"
        )


def _semiperimeter_differences(L):
    """(2s, 2(s − l_i)) per face with Kahan's ordering: sides sorted x ≥ y ≥ z and
    2(s − x) = z − (x − y), 2(s − y) = z + (x − y), 2(s − z) = x + (y − z), each exact up to one
    rounding (no cancellation of rounded sums).
    """
    order = jnp.argsort(-L, axis=1)
    x, y, z = (jnp.take_along_axis(L, order[:, i : i + 1], axis=1)[:, 0] for i in range(3))
    d_sorted = jnp.stack([z - (x - y), z + (x - y), x + (y - z)], axis=1)
    return x + (y + z), jnp.take_along_axis(d_sorted, jnp.argsort(order, axis=1), axis=1)


def corner_angles_from_lengths(F, lengths):
    """Corner angles (nf, 3) from edge lengths, by the half-angle form of the law of cosines:

        tan(α/2) = √((s − b)(s − c) / (s (s − a))),   s = (a + b + c)/2,

    a the side opposite the corner, the differences s − l evaluated in Kahan's stable order
    (`_semiperimeter_differences`).  Unlike arccos((b² + c² − a²)/2bc) it keeps full relative
    accuracy for angles near 0 and π (needle-like triangles).

    **Raises:** `ShapeError` for non-triangles or lengths of the wrong shape,
    `TriangleInequalityError` naming the first face whose lengths violate a triangle inequality.
    """
    L = face_side_lengths(F, lengths)
    _check_triangle_inequalities(L)
    return _half_angle_formula(L)


@jax.jit
def _half_angle_formula(L):
    two_s, D = _semiperimeter_differences(L)
    Db, Dc = jnp.roll(D, -1, axis=1), jnp.roll(D, 1, axis=1)
    return 2 * jnp.arctan2(jnp.sqrt(Db * Dc), jnp.sqrt(two_s[:, None] * D))


def angle_defect_from_lengths(F, lengths):
    """K(p) = 2π − Σ α (interior) and φ(p) = π − Σ α (boundary) with α from the lengths
    (Def 5.2, Remark 5.4, Thm 5.5), (nv,) with nv = max(F) + 1.
    """
    F = _triangles(F)
    angles = corner_angles_from_lengths(F, lengths).reshape(-1)
    return defect_from_angles(angles, F.reshape(-1), boundary_vertex_mask(from_faces(F)))
