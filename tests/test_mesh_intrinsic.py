"""Intrinsic angles from edge lengths (Sec 5.3): Thm 5.5, Example 5.3, triangle inequalities."""

import jax.numpy as jnp
import numpy as np
import pytest

from ddgjax import mesh
from ddgjax.errors import ShapeError, TriangleInequalityError

CLOSED_AND_BOUNDED = ["icosphere", "projective_plane", "klein_bottle", "double_torus", "annulus", "mobius_strip"]


@pytest.mark.parametrize("name", CLOSED_AND_BOUNDED)
def test_thm_5_5_angles_and_defects_from_lengths(name):
    """Corner angles and defects from lengths alone equal the embedded ones to 1e-12."""
    V, F = getattr(mesh, name)()
    lengths = mesh.edge_lengths(V, F)
    assert np.max(np.abs(mesh.corner_angles_from_lengths(F, lengths) - mesh.corner_angles(V, F))) < 1e-12
    assert np.max(np.abs(mesh.angle_defect_from_lengths(F, lengths) - mesh.angle_defect(V, F))) < 1e-12


def test_needle_triangle_is_accurate():
    """An isosceles needle with legs 1 and base a = 2 sin(ε/2): the apex angle ε comes out to
    relative 1e-14, where arccos((b² + c² − a²)/2bc) is off by about 1e-8 relative.
    """
    eps = 1e-9
    a = 2 * np.sin(eps / 2)
    F = np.array([[0, 1, 2]])
    lengths = np.array([1.0, 1.0, a])  # edges (0, 1), (0, 2), (1, 2)
    alpha = float(mesh.corner_angles_from_lengths(F, lengths)[0, 0])
    assert abs(alpha - eps) < 1e-14 * eps
    assert abs(np.arccos((2 - a * a) / 2) - eps) > 1e-8 * eps


def test_example_5_3_pushing_a_vertex_in():
    """Reflect an icosahedron vertex in the plane of its five (coplanar) neighbours: every edge
    length and every angle defect is unchanged, while the mean curvature of its five edges
    changes sign (they become concave): the metric does not determine the embedding.
    """
    V, F = mesh.icosahedron()
    star = np.unique(F[np.any(F == 0, axis=1)])
    nbrs = star[star != 0]
    centre = V[nbrs].mean(axis=0)
    normal = np.linalg.svd(V[nbrs] - centre)[2][-1]
    assert np.max(np.abs((V[nbrs] - centre) @ normal)) < 1e-15 * 10
    W = V.copy()
    W[0] = V[0] - 2 * ((V[0] - centre) @ normal) * normal
    assert np.max(np.abs(mesh.edge_lengths(W, F) - mesh.edge_lengths(V, F))) < 1e-15 * 10
    assert np.max(np.abs(mesh.angle_defect(W, F) - mesh.angle_defect(V, F))) < 1e-12
    E = mesh.edges(F)
    spokes = np.any(E == 0, axis=1)
    H, HW = np.asarray(mesh.edge_mean_curvature(V, F)), np.asarray(mesh.edge_mean_curvature(W, F))
    assert np.all(H[spokes] > 0) and np.all(HW[spokes] < 0)


def test_triangle_inequality_violation_names_the_face():
    V, F = mesh.octahedron()
    lengths = np.asarray(mesh.edge_lengths(V, F)).copy()
    E = mesh.edges(F)
    e = int(np.flatnonzero((E[:, 0] == 0) & (E[:, 1] == 2))[0])
    lengths[e] = 3.0  # edge (0, 2) longer than the other two sides of face 0 = (0, 2, 4)
    with pytest.raises(TriangleInequalityError, match="face 0 has side lengths"):
        mesh.corner_angles_from_lengths(F, lengths)
    with pytest.raises(ShapeError, match="one per edge"):
        mesh.corner_angles_from_lengths(F, lengths[:-1])
    with pytest.raises(ShapeError, match="triangles"):
        mesh.angle_defect_from_lengths(mesh.cube()[1], jnp.ones(12))


def test_degenerate_triangle_gives_a_straight_angle():
    """Equality in the triangle inequality is allowed: the angle is π, the others 0."""
    F = np.array([[0, 1, 2]])
    lengths = np.array([1.0, 2.0, 1.0])  # edges (0,1), (0,2), (1,2): vertex 1 lies between 0 and 2
    alpha = np.asarray(mesh.corner_angles_from_lengths(F, lengths))[0]
    assert np.allclose(alpha, [0, np.pi, 0], atol=1e-15, rtol=0)
