"""Piecewise flat surfaces as glued triangles, unfolding and the intrinsic flip (Sec 5.3, Lemma 5.8).
Lemma 5.8 on flat quadrilaterals is a `ddgjax verify` check (`sec7_delaunay`)."""

import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import (
    FlipBudgetError,
    GluingError,
    MeshError,
    NonFiniteError,
    NonManifoldError,
    OrientationError,
    TriangleInequalityError,
)
from ddgjax.intrinsic import triangulation as T
from ddgjax.mesh.builtin import icosphere, tetrahedron, torus


def test_flip_length_on_a_curved_surface_matches_law_of_cosines():
    """|cd|² = |ac|² + |ad|² − 2|ac||ad| cos(∠cab + ∠bad) in the unfolding (Fig 5.11)."""
    V, F = icosphere(1)
    V = V * np.array([1.0, 0.7, 1.3])
    tri = T.from_mesh(V, F)
    for e in (0, 7, 19):
        h, t = tri.halfedges[e]
        a, b, c, d = V[F.reshape(-1)[h]], V[F.reshape(-1)[T.next_halfedge(h)]], V[F.reshape(-1)[T.next_halfedge(T.next_halfedge(h))]], V[F.reshape(-1)[T.next_halfedge(T.next_halfedge(t))]]
        ang = lambda p, q, r: np.arccos(np.dot(q - p, r - p) / np.linalg.norm(q - p) / np.linalg.norm(r - p))
        alpha = ang(a, c, b) + ang(a, b, d)
        lac, lad = np.linalg.norm(c - a), np.linalg.norm(d - a)
        expected = np.sqrt(lac**2 + lad**2 - 2 * lac * lad * np.cos(alpha))
        np.testing.assert_allclose(dg.intrinsic.flip(tri, e).lengths[e], expected, rtol=1e-12)


def test_thm_5_5_cone_angles_unchanged_by_flips_and_gauss_bonnet():
    V, F = torus(10, 6)
    tri = T.from_mesh(V, F)
    K0 = T.angle_defects(tri)
    np.testing.assert_allclose(K0, dg.mesh.angle_defect(V, F), atol=1e-12)
    flipped = tri
    for e in range(0, tri.n_edges, 7):
        if dg.intrinsic.is_flippable(flipped, e):
            flipped = dg.intrinsic.flip(flipped, e)
    assert np.any(flipped.lengths != tri.lengths)
    np.testing.assert_allclose(T.angle_defects(flipped), K0, atol=1e-12)
    assert abs(T.angle_defects(flipped).sum()) < 1e-10  # Gauss–Bonnet, χ(torus) = 0


def test_triangle_glued_to_itself_cone_with_loop_and_valence_one_vertex():
    """Side 0 (corner 0 → 1) glued to side 1 (corner 1 → 2): a cone; corner 1 becomes a vertex of
    valence one, side 2 a boundary loop."""
    tri = T.from_gluing([1, 0, -1], [[1.0, 1.0, 0.6]])
    assert tri.n_vertices == 2 and tri.n_edges == 2
    ends = tri.edges
    loop = ends[:, 0] == ends[:, 1]
    assert loop.sum() == 1
    apex_vertex = tri.F[0, 1]
    assert np.bincount(ends.reshape(-1), minlength=2)[apex_vertex] == 1
    theta = T.cone_angles(tri)
    np.testing.assert_allclose(theta[apex_vertex], 2 * np.arcsin(0.3), rtol=1e-14)
    # Gauss–Bonnet for a disk (χ = 1): Σ K = 2π
    np.testing.assert_allclose(T.angle_defects(tri).sum(), 2 * np.pi, rtol=1e-14)
    # an edge lying twice on one triangle cannot be flipped (Remark 5.9) and is Delaunay
    assert not dg.intrinsic.is_flippable(tri, int(tri.edge[0]))
    assert dg.intrinsic.is_delaunay(tri)


def test_example_5_5_tetrahedron_flip_gives_double_edge():
    V, F = tetrahedron()
    tri = T.from_mesh(V, F)
    flipped = dg.intrinsic.flip(tri, 0)
    s = np.sqrt(8.0)
    np.testing.assert_allclose(flipped.lengths[0], s * np.sqrt(3.0), rtol=1e-14)
    ends = np.sort(flipped.edges, axis=1)
    assert len(np.unique(ends, axis=0)) == 5  # two edges between the same pair of vertices
    np.testing.assert_allclose(T.cone_angles(flipped), np.pi, rtol=1e-14)
    twin = flipped.twin
    assert np.all(twin[twin] == np.arange(twin.size))


def test_gluing_roundtrip_matches_faces():
    V, F = icosphere(1)
    tri = T.from_mesh(V, F)
    L = T.side_lengths(tri)
    glued = T.from_gluing(tri.twin, L)
    assert glued.n_vertices == tri.n_vertices and glued.n_edges == tri.n_edges
    np.testing.assert_allclose(np.sort(T.cone_angles(glued)), np.sort(T.cone_angles(tri)), rtol=1e-14)


@pytest.mark.parametrize(
    "twin, lengths, error, words",
    [
        ([0, -1, -1], [[1, 1, 1]], GluingError, "halfedge 0"),
        ([1, 2, 0], [[1, 1, 1]], GluingError, "halfedge 0"),
        ([5, -1, -1], [[1, 1, 1]], GluingError, "halfedge 0"),
        ([1, 0, -1], [[1, 2, 1.5]], GluingError, "halfedge 0"),
        ([-1, -1, -1], [[1, 1, 3]], TriangleInequalityError, "face 0"),
        ([-1, -1, -1], [[1, np.nan, 1]], NonFiniteError, "edge 1"),
    ],
)
def test_bad_gluing_and_lengths_name_the_culprit(twin, lengths, error, words):
    with pytest.raises(error, match=words):
        T.from_gluing(twin, lengths)


def test_bad_faces_and_lengths_name_the_culprit():
    V, F = icosphere(1)
    E = dg.mesh.edges(F)
    l = np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1)
    bad = l.copy()
    bad[E.tolist().index(sorted(F[3, :2].tolist()))] = 10.0
    with pytest.raises(TriangleInequalityError, match="face"):
        dg.intrinsic.flip_to_delaunay(F, bad)
    bad = l.copy()
    bad[5] = np.nan
    with pytest.raises(NonFiniteError, match="edge 5"):
        dg.intrinsic.flip_to_delaunay(F, bad)
    with pytest.raises(OrientationError, match="edge"):
        dg.intrinsic.from_mesh(V, np.vstack([F[:1, ::-1], F[1:]]))
    with pytest.raises(NonManifoldError, match="edge"):
        dg.intrinsic.from_mesh(V, np.vstack([F, [[F[0, 1], F[0, 0], 41]]]))
    with pytest.raises(MeshError, match="face 2"):
        dg.intrinsic.from_mesh(V, np.vstack([F[:2], [[0, 0, 1]]]))
    Vn = V.copy()
    Vn[7, 1] = np.nan
    with pytest.raises(NonFiniteError, match="vertex 7"):
        dg.intrinsic.laplace_beltrami(Vn, F)
    cone = T.from_gluing([1, 0, -1], [[1.0, 1.0, 0.6]])
    for e in range(cone.n_edges):  # one edge lies twice on the triangle, the other is a boundary loop
        with pytest.raises(MeshError, match=f"edge {e}"):
            dg.intrinsic.flip(cone, e)


def test_flip_budget_raises_instead_of_hanging():
    V, F = icosphere(2)
    with pytest.raises(FlipBudgetError, match="edge"):
        dg.intrinsic.flip_to_delaunay(dg.intrinsic.from_mesh(V * [8.0, 1, 1], F), max_flips=3)


@pytest.mark.parametrize("mesh", [lambda: icosphere(2), lambda: torus(30, 10)])
def test_inputs_not_mutated(mesh):
    """Also through `laplace_beltrami`'s in-place flips (on its own copies), with and without
    the internal renumbering (the icosphere's labels are renumbered, the torus grid's not)."""
    V, F = mesh()
    V = V * [5.0, 1, 1]
    V0, F0 = V.copy(), F.copy()
    tri = T.from_mesh(V, F)
    arrays = [a.copy() for a in (tri.F, tri.edge, tri.halfedges, tri.lengths)]
    result = dg.intrinsic.flip_to_delaunay(tri)
    assert result.n_flips > 0
    dg.intrinsic.laplace_beltrami(V, F)
    np.testing.assert_array_equal(V, V0)
    np.testing.assert_array_equal(F, F0)
    for a, b in zip(arrays, (tri.F, tri.edge, tri.halfedges, tri.lengths)):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("top", [1, 70_000, 2**40])
def test_radix_argsort_is_the_stable_argsort(top):
    from ddgjax.intrinsic.ordering import radix_argsort

    keys = np.random.default_rng(top % 97).integers(0, top, 50_000)
    np.testing.assert_array_equal(radix_argsort(keys), np.argsort(keys, kind="stable"))
    assert radix_argsort(keys[:0]).size == 0
