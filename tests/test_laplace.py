"""Cotan and graph Laplacians (Sec 6.2, 6.3): libigl, invariants, bad input, plots.  Thm 6.6 (the
Hessian by autodiff) and the smooth limits (Def 6.2, Cor 6.4) are `ddgjax verify` checks
(`sec6_laplace`)."""

import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import (
    DegenerateFaceError,
    InvalidInputError,
    MeshError,
    NonFiniteError,
    NonManifoldError,
)
from energies import dirichlet


def random_disk(seed, rings=3, m=9, lift=0.3):
    """A disk mesh with interior and boundary edges, vertices jittered in 3D."""
    V, F = dg.mesh.disk(rings, m)
    rng = np.random.default_rng(seed)
    V = V + 0.04 * rng.normal(size=V.shape)
    V[:, 2] += lift * rng.normal(size=len(V)) * 0.3
    return V, F


def test_triangle_dirichlet_energy_is_the_cotan_formula():
    """Sec 6.3: ½ A |∇f|² = ¼ Σ cot α_i (f_{i+1} − f_{i−1})² on one triangle."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        P, f = rng.normal(size=(3, 3)), rng.normal(size=3)
        alpha = np.asarray(dg.mesh.corner_angles(P, np.array([[0, 1, 2]])))[0]
        cot_form = 0.25 * sum((f[(i + 1) % 3] - f[(i - 1) % 3]) ** 2 / np.tan(alpha[i]) for i in range(3))
        assert abs(float(dg.laplace.triangle_dirichlet_energy(f, P)) - cot_form) < 1e-12 * (1 + abs(cot_form))


def test_cotan_laplacian_matches_libigl():
    igl = pytest.importorskip("igl")
    for V, F in [random_disk(4), dg.mesh.icosphere(2), dg.mesh.torus(12, 7)]:
        L = dg.laplace.cotan_laplacian(V, F)
        assert abs(L + igl.cotmatrix(V, F)).max() < 1e-12 * abs(L).max()


def test_laplacian_invariants():
    """L 1 = 0, L symmetric, weights scale invariant, E(f) = ½ fᵀ L f, edge weights in edges(F) order."""
    V, F = random_disk(5)
    L = dg.laplace.cotan_laplacian(V, F)
    assert np.max(np.abs(L @ np.ones(len(V)))) < 1e-13
    assert abs(L - L.T).max() == 0
    L.data[:] = 0.0
    L.eliminate_zeros()  # changing a returned matrix in place leaves the cached structure alone
    L = dg.laplace.cotan_laplacian(V, F)
    assert abs(L - L.T).max() == 0 and L.nnz == len(V) + 2 * len(dg.mesh.edges(F))
    assert abs(dg.laplace.cotan_laplacian(3.7 * V, F) - L).max() < 1e-12
    E, w = dg.laplace.edge_cotan_weights(V, F)
    assert np.array_equal(E, dg.mesh.edges(F))
    f = np.random.default_rng(0).normal(size=len(V))
    assert abs(0.5 * f @ (L @ f) - 0.5 * np.sum(w * (f[E[:, 0]] - f[E[:, 1]]) ** 2)) < 1e-12
    W = dg.laplace.cotan_weights(V, F)
    assert np.max(np.abs(np.asarray(W.sum(axis=1)).ravel() - L.diagonal())) < 1e-13
    assert abs(dg.laplace.graph_laplacian(E, w, len(V)) - L).max() < 1e-13


def test_edge_weights_keep_zero_weight_edges():
    """On the square grid the diagonals have ν = ½ (cot 90° + cot 90°) = 0 (to round-off)."""
    V, F, _ = square_grid(4)
    E, w = dg.laplace.edge_cotan_weights(V, F)
    assert np.array_equal(E, dg.mesh.edges(F))
    diagonal = np.abs(V[E[:, 0], 0] - V[E[:, 1], 0]) * np.abs(V[E[:, 0], 1] - V[E[:, 1], 1]) > 0
    assert np.max(np.abs(w[diagonal])) < 1e-15
    assert np.array_equal(np.unique(np.round(w[~diagonal], 12)), [0.5, 1.0])  # boundary ½ cot 45°, interior 1


def test_graph_laplacian_example_6_1():
    """Example 6.1 on a path (G = Z): (Δf)(n) = 2 f(n) − f(n+1) − f(n−1)."""
    n = 6
    edges = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
    L = dg.laplace.graph_laplacian(edges, np.ones(n - 1)).toarray()
    f = np.arange(n) ** 2.0
    assert np.allclose((L @ f)[1:-1], -2.0, atol=1e-14)


# Smooth limits on regular planar triangulations of the unit square.


def square_grid(n):
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    F = dg.mesh.triangulate(dg.mesh.builtin.grid_quads(n + 1, n + 1, False, False))
    boundary = np.flatnonzero((x.ravel() % 1 == 0) | (y.ravel() % 1 == 0))
    return V, F, boundary


# Bad input


def test_bad_meshes_name_the_offender():
    V, F = random_disk(6)
    W = V.copy()
    W[7, 1] = np.nan
    with pytest.raises(NonFiniteError, match="vertex 7"):
        dg.laplace.cotan_laplacian(W, F)
    W = V.copy()
    W[F[4, 2]] = 0.5 * (W[F[4, 0]] + W[F[4, 1]])  # collinear corners
    with pytest.raises(DegenerateFaceError, match="face 4"):
        dg.laplace.cotan_laplacian(W, F)
    G = F.copy()
    G[3, 1] = len(V) + 2
    with pytest.raises(MeshError, match="face 3"):
        dg.laplace.cotan_laplacian(V, G)
    with pytest.raises(NonManifoldError):
        bowtie = np.array([[0, 1, 2], [0, 3, 4]])
        dirichlet.cotan(np.random.default_rng(0).normal(size=(5, 3)), bowtie, [1, 2, 3, 4], np.zeros(4))
    with pytest.raises(InvalidInputError, match="edge 1"):
        dg.laplace.graph_laplacian([[0, 1], [2, 2]], [1.0, 1.0])
    assert not np.isnan(V).any()  # the caller's array is untouched


def assert_harmonic_plot_shows(fig, V, F, f):
    """`plot_laplace.harmonic_function`'s figure of a planar mesh: one 2-D axes with f shaded over
    the triangles and its contour lines, the mesh's edges drawn once each, and a colour bar of f's
    range labelled "f"; the view covers the mesh."""
    ax, bar = fig.axes
    assert ax.name == "rectilinear" and bar.get_label() == "<colorbar>"
    shading, contours = ax.collections
    assert type(shading).__name__ == "TriMesh" and type(contours).__name__ == "TriContourSet"
    np.testing.assert_allclose(shading.get_array(), f, rtol=1e-12, atol=0)
    assert shading.get_clim() == (f.min(), f.max()) and shading.colorbar.ax is bar
    assert bar.get_ylabel() == "f" and bar.get_ylim() == (f.min(), f.max())
    levels = contours.levels
    assert len(levels) >= 10 and levels[0] <= f.min() and levels[-1] >= f.max()
    edges, _ = ax.lines  # triplot: the edges (NaN-separated), then the (unmarked) vertices
    assert len(edges.get_xdata()) == 3 * len(dg.mesh.edges(F))
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= V[:, 0].min() and x1 >= V[:, 0].max() and y0 <= V[:, 1].min() and y1 >= V[:, 1].max()


def test_harmonic_function_plot_shows_the_solution(tmp_path):
    import matplotlib.pyplot as plt

    from ddgjax.plot import laplace as plot_laplace

    V, F, b = square_grid(8)
    u = np.exp(V[:, 0]) * np.sin(V[:, 1])
    f = dirichlet.cotan_sparse(V, F, b, u[b])
    fig = plot_laplace.harmonic_function(V, F, f, title="dDBVP")
    assert_harmonic_plot_shows(fig, V, F, f)
    assert fig.axes[0].get_title() == "dDBVP"
    with pytest.raises(AssertionError):  # negative control: the smooth u differs from f inside
        assert_harmonic_plot_shows(fig, V, F, u)
    plt.close(fig)
    # a curved surface is drawn in 3-D, one polygon per triangle
    W = V.copy()
    W[:, 2] = 0.3 * f
    fig = plot_laplace.harmonic_function(W, F, f)
    ax, bar = fig.axes
    assert ax.name == "3d" and bar.get_label() == "<colorbar>"
    assert bar.get_ylim() == pytest.approx((-f[F].mean(axis=1).max(), f[F].mean(axis=1).max()), rel=1e-12)
    fig.canvas.draw()
    assert len(ax.collections[0].get_paths()) == len(F)
    plt.close(fig)
    path = plot_laplace.harmonic_function(V, F, f, tmp_path / "harmonic.png")
    assert path == tmp_path / "harmonic.png"
    assert plt.imread(path).shape == (495, 550, 4)  # 5 × 4.5 in at 110 dpi


def test_edge_weight_laplacian_is_the_summed_entries_in_canonical_csr():
    """`laplacian_of_edge_weights` (compiled row-by-row assembly, `ddgjax.csr_assembly`) equals
    scipy's COO → CSR sum of the entries L_ij = −w, L_ii = Σ w over edges that are not loops, on
    random multigraphs with loops and repeated edges; its rows are sorted without duplicates, and
    L·1 = 0.  Negative control: counting the loops on the diagonal changes the matrix."""
    import scipy.sparse as sp

    rng = np.random.default_rng(0)
    for n, m in [(1, 1), (5, 0), (5, 12), (3, 50), (200, 2000)]:
        i, j, w = rng.integers(0, n, m), rng.integers(0, n, m), rng.normal(size=m)
        L = dg.laplace.laplacian_of_edge_weights(i, j, w, n)
        keep = i != j
        rows = np.concatenate([i[keep], j[keep], i[keep], j[keep]])
        cols = np.concatenate([j[keep], i[keep], i[keep], j[keep]])
        vals = np.concatenate([-w[keep], -w[keep], w[keep], w[keep]])
        reference = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
        assert abs(L - reference).max() <= 1e-12 * (1 + abs(w).sum()) if m else L.nnz == n
        assert np.all(np.diff(L.indptr) >= 1)  # the diagonal is stored in every row
        for r in range(n):
            cols_r = L.indices[L.indptr[r]:L.indptr[r + 1]]
            assert np.all(np.diff(cols_r) > 0)  # sorted, no duplicates
        assert np.max(np.abs(L @ np.ones(n))) <= 1e-12 * (1 + abs(w).sum())
        if np.any(~keep):  # a check that can fail: a loop counted on the diagonal changes L
            loops = sp.coo_matrix((w[~keep], (i[~keep], i[~keep])), shape=(n, n))
            assert abs(L - (reference + loops)).max() > 1e-3
