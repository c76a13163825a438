"""The empty-circle oracle of `ddgjax.verify.checks.sec7_empty_circle` (Def 7.4, Lemma 7.3)."""

from __future__ import annotations

import numpy as np

import ddgjax as dg
from ddgjax.verify.checks import sec7_empty_circle as ec


def test_power_of_a_point_on_the_unit_circle():
    """pow(x) = |x|² − 1 for the circle through three points of the unit circle."""
    t = np.array([0.3, 2.0, 4.1])
    A, B, C = np.column_stack([np.cos(t), np.sin(t)])
    X = np.array([[0.0, 0.0], [np.cos(5.0), np.sin(5.0)], [2.0, 0.0], [0.1, -0.2]])
    assert np.allclose(ec._power(A, B, C, X), np.sum(X * X, 1) - 1.0, atol=1e-14, rtol=0)
    assert np.isclose(ec._circumradius2(A, B, C), 1.0, atol=1e-14, rtol=0)


def test_lemma_7_3_margin_is_minus_sin_of_the_angle_sum():
    """On a skinny flat disk: m_d = −sin(α + β)/sin α and m_c = −sin(α + β)/sin β, with α the
    angle at c (opposite the edge in the face of its first halfedge) and β at d, from the
    positions; both signs occur."""
    V, F, _ = dg.mesh.builtin.tall_dome(0, n_inner=20, height=0.0)
    tri = dg.intrinsic.from_mesh(V, F)
    e, m_d, m_c = ec.unfolded_margins(tri)
    P = V[tri.F]  # (nf, 3, 3) corners
    u, w = np.roll(P, -1, axis=1) - P, np.roll(P, 1, axis=1) - P
    corner = np.arctan2(np.linalg.norm(np.cross(u, w), axis=-1), np.sum(u * w, -1)).reshape(-1)
    h = tri.halfedges[e]
    alpha, beta = corner[3 * (h // 3) + (h + 2) % 3].T  # side i of a face is opposite its corner i + 2
    assert np.allclose(m_d, -np.sin(alpha + beta) / np.sin(alpha), atol=1e-13, rtol=0)
    assert np.allclose(m_c, -np.sin(alpha + beta) / np.sin(beta), atol=1e-13, rtol=0)
    assert np.any(m_d > 1e-3) and np.any(m_d < -1e-3)
