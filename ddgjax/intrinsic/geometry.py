"""Two Euclidean triangles unfolded into the plane from their side lengths (Lemma 5.8, Fig 5.11):
the apex of a triangle over a base, and the other diagonal of the quadrilateral of two triangles
glued along an edge (the length of a flipped edge).

Vectorised over numpy arrays of side lengths, no validation; the areas are Kahan's
(`ddgjax.mesh.lengths.triangle_area`).
"""

from __future__ import annotations

import numpy as np

from ..mesh.lengths import power_of_two_scale, triangle_area

__all__ = ["apex", "flipped_length"]


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
    Fig 5.11): a = (0, 0), b = (l_ab, 0), c above and d below the x-axis.  Laid out on the
    lengths divided by m = `power_of_two_scale(l_ab)` (areas by m²) and multiplied by m, so
    that the squares in `apex` stay in range.
    """
    m = power_of_two_scale(l_ab)
    l_ab, l_bc, l_ca, l_ad, l_db = (l * (1.0 / m) for l in (l_ab, l_bc, l_ca, l_ad, l_db))
    area_abc = triangle_area(l_ab, l_bc, l_ca) if area_abc is None else area_abc * (1.0 / m) * (1.0 / m)
    area_bad = triangle_area(l_ab, l_ad, l_db) if area_bad is None else area_bad * (1.0 / m) * (1.0 / m)
    xc, yc = apex(l_ab, l_ca, l_bc, area_abc, +1.0)
    xd, yd = apex(l_ab, l_ad, l_db, area_bad, -1.0)
    return np.hypot(xc - xd, yc - yd) * m
