"""Euclidean triangles from their side lengths alone (Sec 5.3): area, cotangents, harmonic index,
unfolding of two triangles into the plane.

Every function is vectorised over numpy arrays of side lengths (any common shape) and does no
validation; `triangulation.py` checks the triangle inequalities once at the API boundary.
"""

from __future__ import annotations

import numpy as np

__all__ = ["apex", "cotangent", "face_harmonic_index", "flipped_length", "triangle_area"]


def _sorted3(a, b, c):
    """(x, y, z) with x ≥ y ≥ z elementwise, exactly (min / max only, no arithmetic)."""
    x = np.maximum(np.maximum(a, b), c)
    z = np.minimum(np.minimum(a, b), c)
    y = np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c))
    return x, y, z


def triangle_area(a, b, c):
    """Area of the Euclidean triangle with sides a, b, c by Heron's formula in Kahan's stable
    order, sides sorted x ≥ y ≥ z:

        A = ¼ √((x + (y + z)) (z − (x − y)) (z + (x − y)) (x + (y − z))),

    accurate for needle-like triangles (no cancellation of rounded sums).
    """
    x, y, z = _sorted3(a, b, c)
    return 0.25 * np.sqrt((x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z)))


def cotangent(a, b, c, area):
    """cot α of the angle α opposite the side a: cot α = (b² + c² − a²) / (4 A) (law of cosines
    over twice the area; used in eq 6.2 and Lemma 7.17).
    """
    return (b * b + c * c - a * a) / (4.0 * area)


def face_harmonic_index(a, b, c, area):
    """h(Δ) = (a² + b² + c²) / A(Δ) (Def 7.7), = 4 (cot α + cot β + cot γ) by Lemma 7.17."""
    return (a * a + b * b + c * c) / area


def apex(base, left, right, area, side: float = 1.0):
    """The third vertex of a triangle laid out on the base from (0, 0) to (base, 0): its distance
    to (0, 0) is `left`, to (base, 0) is `right`; above the base for side = +1, below for −1.
    Returns (x, y) = ((base² + left² − right²) / (2 base), side · 2A / base).
    """
    x = (base * base + left * left - right * right) / (2.0 * base)
    return x, side * 2.0 * area / base


def flipped_length(l_ab, l_bc, l_ca, l_ad, l_db, area_abc=None, area_bad=None):
    """Length of the other diagonal cd of the quadrilateral a d b c obtained by unfolding the
    triangles (a, b, c) and (b, a, d) along their common edge ab into the plane (Lemma 5.8,
    Fig 5.11): a = (0, 0), b = (l_ab, 0), c above and d below the x-axis.
    """
    if area_abc is None:
        area_abc = triangle_area(l_ab, l_bc, l_ca)
    if area_bad is None:
        area_bad = triangle_area(l_ab, l_ad, l_db)
    xc, yc = apex(l_ab, l_ca, l_bc, area_abc, +1.0)
    xd, yd = apex(l_ab, l_ad, l_db, area_bad, -1.0)
    return np.hypot(xc - xd, yc - yd)
