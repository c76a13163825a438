"""The discrete Laplace–Beltrami operator (Def 7.8, Prop 7.10, Remark 7.9) and the Delaunay
tessellation; cross-checks against libigl and robust-laplacian (geometry-central).  Independence of
the triangulation on the cube and Example 5.3 are `ddgjax verify` checks (`sec7_delaunay`)."""

import numpy as np
import pytest

import ddgjax as dg
from ddgjax.intrinsic import triangulation as T
from ddgjax.mesh.builtin import (
    annulus,
    grid_quads,
    icosphere,
    torus,
    triangulate,
)


def _skinny_ellipsoid(level=3, a=12.0):
    V, F = icosphere(level)
    return V * np.array([a, 1.0, 0.5]), F


def _sheared_torus():
    V, F = torus(24, 8)
    return V @ np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [3.0, 0.0, 1.0]]).T * np.array([1.0, 0.3, 1.0]), F


def _bumpy_sphere():
    V, F = icosphere(3)
    rng = np.random.default_rng(7)
    return V * (1 + 0.15 * rng.standard_normal((len(V), 1))), F


CLOSED = {"skinny_ellipsoid": _skinny_ellipsoid, "sheared_torus": _sheared_torus, "bumpy_sphere": _bumpy_sphere}


def _rel(A, B) -> float:
    return float(abs(A - B).max() / abs(B).max())


@pytest.mark.parametrize("name", list(CLOSED))
def test_agrees_with_libigl_intrinsic_delaunay_cotmatrix(name):
    igl = pytest.importorskip("igl")
    V, F = CLOSED[name]()
    L = dg.intrinsic.laplace_beltrami(V, F)
    assert dg.intrinsic.flip_to_delaunay(T.from_mesh(V, F)).n_flips > 0 or name == "bumpy_sphere"
    L_igl = igl.intrinsic_delaunay_cotmatrix(V, F)[0]  # libigl: negative semidefinite
    assert _rel(L, -L_igl) < 1e-10


@pytest.mark.parametrize("name", list(CLOSED))
def test_agrees_with_robust_laplacian_without_mollification(name):
    rl = pytest.importorskip("robust_laplacian")
    V, F = CLOSED[name]()
    L_rl, _mass = rl.mesh_laplacian(V, F, mollify_factor=0)  # returns (L, M), L positive semidefinite
    assert _rel(dg.intrinsic.laplace_beltrami(V, F), L_rl) < 1e-10


def test_boundary_edges_kept_as_in_libigl():
    igl = pytest.importorskip("igl")
    V, F = annulus(24, 4)
    V = np.column_stack([V[:, 0] * 6.0, V[:, 1], 0.3 * V[:, 0] ** 2])
    tri = T.from_mesh(V, F)
    result = dg.intrinsic.flip_to_delaunay(tri)
    assert result.n_flips > 0
    boundary = tri.halfedges[:, 1] < 0
    assert np.all(result.triangulation.halfedges[boundary, 1] < 0)
    np.testing.assert_array_equal(np.sort(result.triangulation.edges[boundary], 1), np.sort(tri.edges[boundary], 1))
    np.testing.assert_array_equal(result.lengths[boundary], tri.lengths[boundary])
    assert _rel(dg.intrinsic.laplace_beltrami(V, F), -igl.intrinsic_delaunay_cotmatrix(V, F)[0]) < 1e-10


@pytest.mark.parametrize("name", list(CLOSED))
def test_prop_7_10_nonnegative_weights_symmetric_constants_in_kernel(name):
    V, F = CLOSED[name]()
    L = dg.intrinsic.laplace_beltrami(V, F)
    off = L - np.diag(L.diagonal())
    assert off.max() <= 1e-12  # L_ij = −ν_ij ≤ 0
    assert abs(L - L.T).max() < 1e-14
    assert abs(L @ np.ones(L.shape[0])).max() < 1e-10 * abs(L).max()


def test_independent_of_the_delaunay_triangulation_flat_torus_grid():
    """The flat square torus as glued unit squares split by either diagonal: both are Delaunay
    (cocircular quads); the Laplace–Beltrami operator is the graph Laplacian of the square grid."""
    m = n = 6
    Q = grid_quads(m, n, True, True)
    Ls = []
    for roll in (0, 1):
        F = triangulate(np.roll(Q, roll, axis=1))
        E = dg.mesh.edges(F)
        i, j = E.T // n, E.T % n
        di, dj = np.minimum(abs(i[0] - i[1]), m - abs(i[0] - i[1])), np.minimum(abs(j[0] - j[1]), n - abs(j[0] - j[1]))
        lengths = np.hypot(di, dj)
        assert dg.intrinsic.is_delaunay(F, lengths)
        Ls.append(dg.intrinsic.laplace_beltrami_from_lengths(F, lengths))
        tess = dg.intrinsic.delaunay_tessellation(dg.intrinsic.from_faces(F, lengths))
        assert tess.n_cells == m * n
    assert abs(Ls[0] - Ls[1]).max() < 1e-14
    np.testing.assert_allclose(Ls[0].diagonal(), 4.0, rtol=1e-14)  # the 4-neighbour grid Laplacian


def test_isometric_bending_of_a_strip_does_not_change_the_operator():
    """A planar strip triangulated with skinny non-Delaunay triangles, bent along its vertical
    grid lines onto a polygonal arc: every triangle stays congruent (Example 5.3)."""
    m, n = 30, 5
    rng = np.random.default_rng(8)
    x = np.cumsum(np.r_[0.0, rng.uniform(0.05, 0.3, m - 1)])
    # columns at constant x, rows jagged: skinny, partly non-Delaunay triangles
    X = np.repeat(x[:, None], n, axis=1)
    Y = np.linspace(0, 4, n)[None, :] + rng.uniform(-0.45, 0.45, (m, n))
    F = triangulate(grid_quads(m, n, False, False))
    flat = np.column_stack([X.ravel(), Y.ravel(), np.zeros(m * n)])
    # arc with the same chord lengths: turn by a fixed angle at every column
    steps = np.diff(x)
    heading = np.cumsum(np.r_[0.0, np.full(m - 2, 0.2)])
    arc = np.vstack([[0.0, 0.0], np.cumsum(np.stack([np.cos(heading), np.sin(heading)], 1) * steps[:, None], axis=0)])
    bent = np.column_stack([np.repeat(arc[:, 0], n), Y.ravel(), np.repeat(arc[:, 1], n)])
    np.testing.assert_allclose(dg.mesh.edge_lengths(bent, F), dg.mesh.edge_lengths(flat, F), rtol=1e-12)
    assert dg.intrinsic.flip_to_delaunay(T.from_mesh(flat, F)).n_flips > 0
    L_flat, L_bent = dg.intrinsic.laplace_beltrami(flat, F), dg.intrinsic.laplace_beltrami(bent, F)
    assert abs(L_flat - L_bent).max() < 1e-10 * abs(L_flat).max()
    # on the flat strip, linear functions are harmonic at interior vertices (Delaunay or not)
    interior = np.ones(m * n, bool)
    interior[np.unique(np.r_[np.arange(n), np.arange((m - 1) * n, m * n), np.arange(0, m * n, n), np.arange(n - 1, m * n, n)])] = False
    assert abs((L_flat @ flat[:, :2])[interior]).max() < 1e-10


def test_tessellation_of_a_generic_surface_is_the_triangulation():
    V, F = _bumpy_sphere()
    tri = dg.intrinsic.flip_to_delaunay(T.from_mesh(V, F)).triangulation
    tess = dg.intrinsic.delaunay_tessellation(tri)
    assert tess.n_cells == tri.n_faces and tess.edge_mask.all()
    # Remark 7.9: all weights of the tessellation's edges are positive
    assert dg.intrinsic.cotan_weights(tri)[tess.edge_mask].min() > 0


def test_errors_name_the_callers_indices_after_internal_renumbering():
    """laplace_beltrami renumbers an icosphere internally (ordering.is_local is False); errors
    must still name the caller's vertices and faces."""
    import re

    from ddgjax.intrinsic.ordering import is_local

    V, F = icosphere(3)
    assert not is_local(F, len(V))
    F2 = F.copy()
    F2[100] = F2[100, ::-1]
    with pytest.raises(dg.errors.OrientationError) as info:
        dg.intrinsic.laplace_beltrami(V, F2)
    i, j = (int(x) for x in re.search(r"vertices \((\d+), (\d+)\)", str(info.value)).groups())
    assert {i, j} <= set(F[100].tolist())
    W = V.copy()
    W[F[200, 0]] = W[F[200, 1]]  # an edge of length zero
    e = dg.mesh.edges(F).tolist().index(sorted(F[200, :2].tolist()))  # its index in the caller's order
    with pytest.raises(dg.errors.TriangleInequalityError, match=f"edge {e} "):
        dg.intrinsic.laplace_beltrami(W, F)


def test_renumbering_does_not_change_the_operator():
    V, F = _skinny_ellipsoid(level=3)
    L = dg.intrinsic.laplace_beltrami(V, F)
    L_direct = dg.intrinsic.laplace_beltrami_from_lengths(dg.intrinsic.from_mesh(V, F))
    assert abs(L - L_direct).max() < 1e-13 * abs(L).max()


@pytest.mark.parametrize("mesh", [lambda: torus(16, 8), lambda: icosphere(2)])
def test_equals_the_cotan_laplacian_on_delaunay_meshes(mesh):
    """On a triangulation that is already Delaunay, Def 7.8 is the cotan Laplacian of Def 6.2
    (ddgjax.laplace, same sign convention)."""
    V, F = mesh()
    assert dg.intrinsic.is_delaunay(dg.intrinsic.from_mesh(V, F))
    L, L_cot = dg.intrinsic.laplace_beltrami(V, F), dg.laplace.cotan_laplacian(V, F)
    assert abs(L - L_cot).max() < 1e-12 * abs(L_cot).max()
