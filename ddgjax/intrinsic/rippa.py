"""Rippa's lemma and the circularity criterion for convex quadrilaterals (Lemma 7.14, 7.15,
Cor 7.16).

A convex non-degenerate quadrilateral Q(r₁, r₂, r₃, r₄, θ) (Fig 7.16) has its diagonals meeting
at the origin at the angle θ; vertex k lies at distance r_k, counter-clockwise.  Flipping the
diagonal (13) to (24) changes the Dirichlet energy of the piecewise linear interpolation of
values u₁..u₄ by eq (7.2), whose sign is that of r₁r₃ − r₂r₄.
"""

from __future__ import annotations

import numpy as np

from .._checks import check_positive
from ..mesh.lengths import normalised

__all__ = ["circularity", "diagonal_values", "dirichlet_energy_difference", "is_circular", "quadrilateral"]


def quadrilateral(r, theta) -> np.ndarray:
    """(4, 2) vertices of Q(r₁, r₂, r₃, r₄, θ): vertex k at distance r_k from the intersection of
    the diagonals, at the angles 0, θ, π, π + θ (counter-clockwise for θ in (0, π))."""
    r = np.asarray(r, dtype=np.float64)
    angles = np.array([0.0, theta, np.pi, np.pi + theta])
    return r[:, None] * np.stack([np.cos(angles), np.sin(angles)], axis=1)


def diagonal_values(u, r):
    """(u₀, u₀*): the values at the diagonals' intersection of the interpolation linear along (13)
    and along (24): u₀ = (r₃u₁ + r₁u₃)/(r₁ + r₃), u₀* = (r₄u₂ + r₂u₄)/(r₂ + r₄)."""
    u1, u2, u3, u4 = u
    r1, r2, r3, r4 = r
    return (r3 * u1 + r1 * u3) / (r1 + r3), (r4 * u2 + r2 * u4) / (r2 + r4)


def dirichlet_energy_difference(u, r, theta):
    """E(u₁₃) − E(u₂₄) by Rippa's formula (Lemma 7.14, eq 7.2):

        ¼ (u₀ − u₀*)² / sin θ · (r₁ + r₃)(r₂ + r₄) / (r₁r₂r₃r₄) · (r₁r₃ − r₂r₄),

    u₁₃ affine on the triangles (123), (134) and u₂₄ on (234), (241).
    """
    r1, r2, r3, r4 = r
    u0, u0s = diagonal_values(u, r)
    return 0.25 * (u0 - u0s) ** 2 / np.sin(theta) * (r1 + r3) * (r2 + r4) / (r1 * r2 * r3 * r4) * circularity(r)


def circularity(r):
    """r₁r₃ − r₂r₄: zero iff Q is circular (Lemma 7.15); > 0 iff the diagonal (24) is Delaunay,
    < 0 iff (13) is."""
    r1, r2, r3, r4 = r
    return r1 * r3 - r2 * r4


def is_circular(r, rtol: float = 1e-12) -> bool:
    """Lemma 7.15: the vertices of Q lie on a circle iff r₁r₃ = r₂r₄ (the intersecting chords
    theorem), tested to the relative tolerance `rtol`, on r divided by a power of two
    (`ddgjax.mesh.lengths.normalised`; the test is scale-invariant).

    **Raises:** `InvalidInputError` unless `rtol` is finite and positive."""
    check_positive(rtol, "rtol")
    r1, r2, r3, r4 = normalised(np.asarray(r, dtype=np.float64))[0]
    return bool(abs(circularity(r)) <= rtol * max(r1 * r3, r2 * r4))
