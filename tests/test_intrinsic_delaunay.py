"""Delaunay edges, the flip algorithm and the harmonic index (Sec 7.2, 7.3): API behaviour and special
gluings.  The statements (Prop 7.9, 7.10, Lemma 7.14–7.18, Cor 7.19, Thm 7.21, Example 7.2, 7.3) are
`ddgjax verify` checks (`sec7_delaunay`)."""

import subprocess
import sys

import numpy as np
import pytest

import ddgjax as dg
from ddgjax.intrinsic import triangulation as T
from ddgjax.mesh.builtin import icosphere, stretched_sphere, torus


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


def test_flip_to_delaunay_takes_a_triangulation_or_faces_and_lengths():
    """`flip_to_delaunay(tri)` and `flip_to_delaunay(F, lengths)` give the same result; the history
    holds h(T) before and after every flip and its steps."""
    V, F = stretched_sphere(2, bumps=0.1)
    result = dg.intrinsic.flip_to_delaunay(F, dg.mesh.edge_lengths(V, F))
    other = dg.intrinsic.flip_to_delaunay(T.from_mesh(V, F))
    assert result.n_flips == other.n_flips > 10
    np.testing.assert_array_equal(result.F, other.F)
    np.testing.assert_allclose(result.lengths, other.lengths, rtol=1e-14)
    assert result.harmonic_index.shape == (result.n_flips + 1,)
    np.testing.assert_allclose(result.harmonic_index_steps, np.diff(result.harmonic_index), rtol=0,
                               atol=1e-12 * result.harmonic_index[0])


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
    """The cotangents of the result (derived: the autodiff Hessian of the Dirichlet energy)
    agree with the law of cosines on the final lengths to rounding, and so does h(T)."""
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


def test_start_keys_are_the_derived_cotangents_to_rounding():
    """The loop's keys of the start (law of cosines, `corner_cotangents`) agree with the derived
    cotangents (autodiff) to rounding, and the angle test fails on the same edges with either."""
    from ddgjax.intrinsic.delaunay import DELAUNAY_TOL, _face_geometry
    from ddgjax.intrinsic.flip_algorithm import start_keys

    V, F = icosphere(3)
    tri = T.from_mesh(V * np.array([12.0, 1.0, 0.5]), F)
    cot, s = _face_geometry(tri)
    derived = np.append(cot + DELAUNAY_TOL * np.repeat(s, 3), np.inf)
    key, _, h = start_keys(tri.edge, tri.lengths, DELAUNAY_TOL)
    assert np.max(np.abs(key[:-1] - derived[:-1]) / np.repeat(s, 3)) < 1e-14
    he = tri.halfedges
    fails = key[he[:, 0]] + key[he[:, 1]] < 0
    assert 100 < fails.sum() and np.array_equal(fails, derived[he[:, 0]] + derived[he[:, 1]] < 0)
    np.testing.assert_allclose(h, dg.intrinsic.harmonic_index(tri), rtol=1e-14)


def test_a_recorded_run_flips_as_an_unrecorded_one():
    """A recorded run keeps the history in a buffer and resumes the loop from its state when the
    buffer is full (`flip_algorithm.sweep`): with several refills it makes the same flips as a
    run without history, and its history ends at the same h(T)."""
    V, F = icosphere(4)
    tri = T.from_mesh(V * np.array([15.0, 1.0, 0.3]), F)
    recorded = dg.intrinsic.flip_to_delaunay(tri)
    unrecorded = dg.intrinsic.flip_to_delaunay(tri, record_history=False)
    assert recorded.n_flips == unrecorded.n_flips > 4 * 1024
    assert recorded.n_rounds == unrecorded.n_rounds
    for a, b in zip((recorded.F, recorded.triangulation.edge, recorded.triangulation.halfedges, recorded.lengths),
                    (unrecorded.F, unrecorded.triangulation.edge, unrecorded.triangulation.halfedges,
                     unrecorded.lengths)):
        np.testing.assert_array_equal(a, b)
    assert recorded.harmonic_index_steps.shape == (recorded.n_flips,)
    assert np.all(recorded.harmonic_index_steps < 0)
    assert recorded.harmonic_index[0] == unrecorded.harmonic_index[0]
    np.testing.assert_allclose(recorded.harmonic_index[-1], unrecorded.harmonic_index[-1], rtol=1e-11)
    np.testing.assert_array_equal(recorded.halfedge_cotangents, unrecorded.halfedge_cotangents)


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
