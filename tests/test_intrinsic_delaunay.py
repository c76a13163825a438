"""Delaunay edges, the flip algorithm and the harmonic index (Sec 7.2, 7.3), Rippa's lemma."""

import subprocess
import sys

import numpy as np
import pytest

import ddgjax as dg
from ddgjax.intrinsic import rippa
from ddgjax.intrinsic import triangulation as T
from ddgjax.mesh.builtin import cube, icosphere, tetrahedron, torus
from ddgjax.mesh.lengths import corner_cotangents, face_harmonic_index, triangle_area


def _bumpy_sphere(level=2, seed=0, stretch=(3.0, 1.0, 0.6)):
    V, F = icosphere(level)
    rng = np.random.default_rng(seed)
    return V * np.asarray(stretch) * (1 + 0.1 * rng.standard_normal((len(V), 1))), F


def _opposite_angle_sums(tri):
    """(ne,) α + β opposite each interior edge, from `corner_angles` (independent of the cot
    test used by the algorithm)."""
    ang = T.corner_angles(tri)
    # side i is opposite corner i + 2
    per_side = np.roll(ang, -2, axis=1).reshape(-1)
    return np.bincount(tri.edge, per_side, minlength=tri.n_edges)


def test_prop_7_9_flip_algorithm_reaches_angle_criterion_with_decreasing_harmonic_index():
    V, F = _bumpy_sphere()
    tri = T.from_mesh(V, F)
    before = _opposite_angle_sums(tri)
    assert before.max() > np.pi + 0.1
    result = dg.intrinsic.flip_to_delaunay(F, dg.mesh.edge_lengths(V, F))
    assert result.n_flips > 10
    assert dg.intrinsic.is_delaunay(result)
    assert _opposite_angle_sums(result.triangulation).max() <= np.pi + 1e-12
    h = result.harmonic_index
    assert h.shape == (result.n_flips + 1,)
    assert np.all(np.diff(h) < 0) and np.all(result.harmonic_index_steps < 0)  # Cor 7.19
    np.testing.assert_allclose(h[0], dg.intrinsic.harmonic_index(tri), rtol=1e-14)
    np.testing.assert_allclose(h[-1], dg.intrinsic.harmonic_index(result), rtol=1e-12)
    # the metric is unchanged: cone angles agree (Thm 5.5)
    np.testing.assert_allclose(T.cone_angles(result.triangulation), T.cone_angles(tri), atol=1e-11)


def test_prop_7_10_weights_nonnegative_iff_delaunay():
    V, F = _bumpy_sphere(seed=1)
    tri = T.from_mesh(V, F)
    assert dg.intrinsic.cotan_weights(tri).min() < -0.05
    assert not dg.intrinsic.is_delaunay(tri)
    flipped = dg.intrinsic.flip_to_delaunay(tri).triangulation
    assert dg.intrinsic.cotan_weights(flipped).min() >= -1e-12


def test_lemma_7_17_and_7_18_harmonic_index(rng):
    a, b = rng.uniform(0.5, 2, 100), rng.uniform(0.5, 2, 100)
    c = rng.uniform(np.abs(a - b) + 0.01, a + b - 0.01)
    A = triangle_area(a, b, c)
    cots = sum(corner_cotangents(a * a, b * b, c * c, A))
    np.testing.assert_allclose(face_harmonic_index(a, b, c, A), 4 * cots, rtol=1e-12)
    # h(T) = 8 Σ_i E(φ_i), E(φ_i) = ½ L_ii
    V, F = _bumpy_sphere(seed=2)
    tri = T.from_mesh(V, F)
    L = dg.intrinsic.cotan_laplacian(tri)
    np.testing.assert_allclose(dg.intrinsic.harmonic_index(tri), 8 * 0.5 * L.diagonal().sum(), rtol=1e-12)


def _force_flips(tri, n, rng, longest=True):
    """n flips of flippable edges chosen to make edges long (Example 7.3), ignoring Delaunay."""
    for _ in range(n):
        candidates = [e for e in rng.permutation(tri.n_edges)[:40] if dg.intrinsic.is_flippable(tri, e)]
        options = [dg.intrinsic.flip(tri, e) for e in candidates]
        tri = max(options, key=lambda t: t.lengths.max()) if longest else options[0]
    return tri


def test_example_7_3_cube_with_long_edges_terminates_at_the_unique_tessellation():
    V, F = cube(triangulated=True)
    tri = T.from_mesh(V, F)
    rng = np.random.default_rng(3)
    long = _force_flips(tri, 25, rng)
    assert long.lengths.max() > 3.0  # longer than the cube's diameter √3
    result = dg.intrinsic.flip_to_delaunay(long)
    assert dg.intrinsic.is_delaunay(result)
    assert np.all(np.diff(result.harmonic_index) < 0)
    # the Delaunay tessellation is unique (Thm 7.5): the same Laplace–Beltrami operator
    L0 = dg.intrinsic.laplace_beltrami(V, F).toarray()
    L1 = dg.intrinsic.cotan_laplacian(result.triangulation).toarray()
    np.testing.assert_allclose(L1, L0, atol=1e-12)
    tess = dg.intrinsic.delaunay_tessellation(result.triangulation)
    assert tess.n_cells == 6 and np.all(tess.cell_size == 2)  # six squares


def test_example_7_2_tetrahedron_from_a_bad_triangulation():
    V, F = tetrahedron()
    tri = T.from_mesh(V, F)
    bad = _force_flips(tri, 6, np.random.default_rng(4))
    assert not dg.intrinsic.is_delaunay(bad)
    result = dg.intrinsic.flip_to_delaunay(bad)
    assert dg.intrinsic.is_delaunay(result) and np.all(np.diff(result.harmonic_index) < 0)
    np.testing.assert_allclose(dg.intrinsic.cotan_laplacian(result.triangulation).toarray(),
                               dg.intrinsic.laplace_beltrami(V, F).toarray(), atol=1e-12)


def test_example_7_2_flat_tetrahedron_delaunay_is_not_regular():
    """A flattened tetrahedron: its Delaunay triangulation has two edges between one pair of
    vertices."""
    V = np.array([[-1, 0, 0], [1, 0, 0], [0, 0.2, 0], [0, 0.1, 0.01]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    result = dg.intrinsic.flip_to_delaunay(T.from_mesh(V, F))
    assert result.n_flips == 1 and dg.intrinsic.is_delaunay(result)
    ends = np.sort(result.triangulation.edges, axis=1)
    assert len(np.unique(ends, axis=0)) < len(ends)


def test_doubled_obtuse_triangle_delaunay_has_loop_and_valence_one_vertices():
    """Two copies of an obtuse triangle glued along all sides (a flat tetrahedron with three
    vertices): the long edge is not Delaunay; flipping it gives a loop at the obtuse vertex and
    two vertices of valence one."""
    s = [2.0, 1.1, 1.1]  # side 0 is the long one, opposite the obtuse corner 2
    twin = [3 + 0, 3 + 2, 3 + 1, 0, 2, 1]  # face 1 = (b, a, c) reversed copy
    tri = T.from_gluing(twin, [s, [s[0], s[2], s[1]]])
    assert tri.n_vertices == 3
    result = dg.intrinsic.flip_to_delaunay(tri)
    assert result.n_flips == 1 and dg.intrinsic.is_delaunay(result)
    ends = result.triangulation.edges
    assert np.sum(ends[:, 0] == ends[:, 1]) == 1
    valence = np.bincount(ends.reshape(-1), minlength=3)
    assert sorted(valence.tolist()) == [1, 1, 4]


def _dirichlet_energy_planar(P, triangles, u):
    """Σ ½ |∇u|² A over planar triangles, ∇u from solving the affine interpolation directly."""
    total = 0.0
    for t in map(list, triangles):
        X = np.column_stack([P[t], np.ones(3)])
        grad = np.linalg.solve(X, u[t])[:2]
        area = 0.5 * abs(np.linalg.det(np.column_stack([P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]])))
        total += 0.5 * grad @ grad * area
    return total


def test_lemma_7_14_rippa_formula_matches_direct_energies(rng):
    for _ in range(50):
        r = rng.uniform(0.2, 2.0, 4)
        theta = rng.uniform(0.2, np.pi - 0.2)
        u = rng.standard_normal(4)
        P = rippa.quadrilateral(r, theta)
        E13 = _dirichlet_energy_planar(P, [(0, 1, 2), (0, 2, 3)], u)
        E24 = _dirichlet_energy_planar(P, [(1, 2, 3), (1, 3, 0)], u)
        np.testing.assert_allclose(rippa.dirichlet_energy_difference(u, r, theta), E13 - E24,
                                   rtol=1e-10, atol=1e-13)


def test_lemma_7_15_circularity_and_delaunay_diagonal(rng):
    for _ in range(50):
        # four points on a circle, counter-clockwise: r₁r₃ = r₂r₄ (intersecting chords)
        phi = np.sort(rng.uniform(0, 2 * np.pi, 4))
        P = np.stack([np.cos(phi), np.sin(phi)], axis=1)
        M = np.column_stack([P[2] - P[0], P[1] - P[3]])
        s, _ = np.linalg.solve(M, P[1] - P[0])
        O = P[0] + s * (P[2] - P[0])
        r = np.linalg.norm(P - O, axis=1)
        assert rippa.is_circular(r, rtol=1e-9)
        # generic quadrilateral: the sign of r₁r₃ − r₂r₄ says which diagonal is Delaunay
        r = rng.uniform(0.2, 2.0, 4)
        Q = rippa.quadrilateral(r, rng.uniform(0.2, np.pi - 0.2))
        ang = lambda p, q, x: np.arccos(np.dot(q - p, x - p) / np.linalg.norm(q - p) / np.linalg.norm(x - p))
        diag24_delaunay = ang(Q[0], Q[1], Q[3]) + ang(Q[2], Q[3], Q[1]) <= np.pi
        assert (rippa.circularity(r) > 0) == diag24_delaunay


def test_thm_7_21_no_single_flip_lowers_dirichlet_energy_at_delaunay(rng):
    V, F = _bumpy_sphere(level=1, seed=5)
    tri = dg.intrinsic.flip_to_delaunay(T.from_mesh(V, F)).triangulation
    f = rng.standard_normal((tri.n_vertices, 5))
    energy = lambda t: 0.5 * np.einsum("ik,ik->k", f, dg.intrinsic.cotan_laplacian(t) @ f)
    E0 = energy(tri)
    flipped = 0
    for e in range(tri.n_edges):
        if dg.intrinsic.is_flippable(tri, e):
            assert np.all(energy(dg.intrinsic.flip(tri, e)) >= E0 - 1e-12)
            flipped += 1
    assert flipped > 0.8 * tri.n_edges  # the check is not vacuous


@pytest.mark.parametrize("mesh", [lambda: torus(12, 6), lambda: icosphere(2)])
def test_delaunay_input_needs_no_flips(mesh):
    V, F = mesh()
    result = dg.intrinsic.flip_to_delaunay(T.from_mesh(V, F))
    assert dg.intrinsic.is_delaunay(T.from_mesh(V, F)) == (result.n_flips == 0)
    assert result.harmonic_index.shape == (result.n_flips + 1,)


def test_gluing_stays_consistent_through_many_batched_flips():
    """After thousands of batched flips: the twin map is an involution without fixed points,
    glued halfedges run between the same vertices in opposite directions, every edge's
    halfedges point back to it, and the metric (cone angles) is unchanged."""
    V, F = icosphere(3)
    tri = T.from_mesh(V * np.array([15.0, 1.0, 0.3]), F)
    result = dg.intrinsic.flip_to_delaunay(tri)
    assert result.n_flips > 1000 and dg.intrinsic.is_delaunay(result)
    out = result.triangulation
    twin = out.twin
    h = np.arange(twin.size)
    assert np.all(twin[twin] == h) and np.all(twin != h)
    tail = out.F.reshape(-1)
    head = tail[T.next_halfedge(h)]
    np.testing.assert_array_equal(tail[twin], head)
    np.testing.assert_array_equal(out.edge[out.halfedges[:, 0]], np.arange(out.n_edges))
    np.testing.assert_array_equal(out.edge[out.halfedges[:, 1]], np.arange(out.n_edges))
    np.testing.assert_allclose(T.cone_angles(out), T.cone_angles(tri), atol=1e-10)


def test_cached_cotangents_of_the_result_equal_a_fresh_computation():
    """The flip loop keeps only the keys cot + tol · s and recovers the cotangents of the result
    from them (the cotangents of a face sum to s, Lemma 7.17): they agree with the law of
    cosines on the final lengths to rounding, and so does h(T)."""
    V, F = icosphere(3)
    tri = T.from_mesh(V * np.array([12.0, 1.0, 0.5]), F)
    result = dg.intrinsic.flip_to_delaunay(tri)
    assert result.n_flips > 500
    fresh = T.corner_cotangents(result.triangulation)  # corner k is opposite side k + 1
    per_side = np.roll(fresh, 1, axis=1).reshape(-1)
    scale = np.abs(fresh).sum(axis=1).repeat(3)
    assert np.max(np.abs(result.halfedge_cotangents - per_side) / scale) < 1e-13
    unrecorded = dg.intrinsic.flip_to_delaunay(tri, record_history=False)
    np.testing.assert_allclose(unrecorded.harmonic_index[-1], dg.intrinsic.harmonic_index(result), rtol=1e-13)


def test_flipping_in_place_equals_flipping_a_copy():
    """`flip_owned(copy=False)` (used by `laplace_beltrami` on triangulations it built itself)
    gives the same triangulation as the copying `flip_to_delaunay`."""
    from ddgjax.intrinsic.delaunay import flip_owned

    V, F = torus(40, 12)
    V = V @ np.array([[1.0, 0.0, 1.5], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]]).T
    copied = dg.intrinsic.flip_to_delaunay(T.from_mesh(V, F))
    in_place = flip_owned(T.from_mesh(V, F), copy=False)
    assert copied.n_flips == in_place.n_flips > 100
    for a, b in zip((copied.F, copied.triangulation.edge, copied.triangulation.halfedges, copied.lengths),
                    (in_place.F, in_place.triangulation.edge, in_place.triangulation.halfedges, in_place.lengths)):
        np.testing.assert_array_equal(a, b)


def test_compiled_flip_writes_what_lemma_5_8_flip_writes():
    """The compiled loop's flip (`flip_algorithm`) and `flips.flip` give the same gluing and the
    same length of the new diagonal, on a triangulation needing exactly one flip."""
    V = np.array([[-1, 0, 0], [1, 0, 0], [0, 0.2, 0], [0, 0.1, 0.01]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    tri = T.from_mesh(V, F)
    (e,) = np.flatnonzero(~dg.intrinsic.delaunay_edges(tri))
    result = dg.intrinsic.flip_to_delaunay(tri)
    single = dg.intrinsic.flip(tri, int(e))
    assert result.n_flips == 1
    for a, b in ((result.F, single.F), (result.triangulation.edge, single.edge),
                 (result.triangulation.halfedges, single.halfedges)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(result.lengths, single.lengths, rtol=4e-16)


def test_import_ddgjax_does_not_load_numba():
    """numba (the compiled flip loop) is loaded by the first flip, not by `import ddgjax`."""
    code = "import sys, ddgjax, ddgjax.intrinsic; assert 'numba' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)
