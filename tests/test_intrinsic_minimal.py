"""Minimal surfaces in the narrow sense (Def 7.9, Fig 7.23): the entry points and the before/after
flip plot.  Fig 7.26 and Remark 7.10 are `ddgjax verify` checks (`sec7_delaunay`)."""

import numpy as np
import pytest
from scipy.spatial import Delaunay

import ddgjax as dg
from ddgjax.plot import intrinsic as iplot
from energies import area


def test_fig_6_5_cotan_iteration_here_agrees_with_energies_area():
    """`harmonic_iteration(flip=False)` is Fig 6.5: the same iterates as the cotan Laplacian of
    the surface (`pinkall_polthier_step`)."""
    V, F, boundary = dg.mesh.builtin.tall_dome(0, n_inner=40, m=16, stretch=1.0, height=0.5)
    W1, _, info1 = area.harmonic_iteration(V, F, boundary, flip=False, max_iter=3)
    W2, residuals = V, []
    for _ in range(3):
        W2, r = area.pinkall_polthier_step(W2, F, boundary)
        residuals.append(r)
    residuals.append(area.pinkall_polthier_step(W2, F, boundary)[1])
    np.testing.assert_allclose(W1, W2, atol=1e-12)
    np.testing.assert_allclose(info1["history"], residuals[: len(info1["history"])], rtol=1e-10, atol=1e-14)


def test_minimal_surface_delaunay_returns_its_final_triangulation():
    """`minimal_surface_delaunay` returns the faces of its final (flipped) triangulation, keeps the
    boundary and leaves its input alone; `minimal_surface(method="delaunay")` is the same call."""
    V, F, boundary = dg.mesh.builtin.tall_dome(0)
    V0, F0 = V.copy(), F.copy()
    W, F1, info = area.minimal_surface_delaunay(V, F, boundary, tol=1e-9, max_iter=30)
    assert info["converged"] and info["flips"].sum() > 0
    np.testing.assert_array_equal(F1, info["triangulation"].F)
    np.testing.assert_array_equal(W[boundary], V[boundary])
    np.testing.assert_array_equal(V, V0)
    np.testing.assert_array_equal(F, F0)
    W2, F2, _ = area.minimal_surface(V, F, boundary, method="delaunay", tol=1e-9, max_iter=30)
    np.testing.assert_array_equal(W2, W)
    np.testing.assert_array_equal(F2, F1)


def test_minimal_surface_bad_boundary_index():
    V, F, _ = dg.mesh.builtin.tall_dome(0, n_inner=20, m=8)
    with pytest.raises(dg.errors.InvalidInputError, match="boundary vertex 999"):
        area.minimal_surface_delaunay(V, F, [0, 999])


def _segment_set(segments) -> set:
    """Segments as a set of unordered pairs of points (rounded), to compare drawings with edges."""
    return {tuple(sorted(map(tuple, np.round(np.asarray(s), 12)))) for s in segments}


def assert_panel_shows(ax, tri, V):
    """One panel of `before_after`: the edges of `tri` at the positions V, the Delaunay ones grey
    and thin, the non-Delaunay ones (Prop 7.9) red and thick and counted in the legend, the
    vertices as dots, all inside the view."""
    ok = np.asarray(dg.intrinsic.delaunay_edges(tri))
    chords = V[tri.edges][:, :, :2]
    grey, red = ax.collections
    assert _segment_set(grey.get_segments()) == _segment_set(chords[ok])
    assert _segment_set(red.get_segments()) == _segment_set(chords[~ok])
    assert grey.get_linewidth()[0] < red.get_linewidth()[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [f"non-Delaunay ({int((~ok).sum())})"]
    (dots,) = ax.lines
    np.testing.assert_array_equal(np.column_stack(dots.get_data()), V[:, :2])
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= V[:, 0].min() and x1 >= V[:, 0].max() and y0 <= V[:, 1].min() and y1 >= V[:, 1].max()


def test_plot_before_after_shows_both_triangulations(tmp_path):
    """Two 2-D panels: the start triangulation with its non-Delaunay edges highlighted, and the
    flipped one with none; the saved PNG is the 10 × 5 in figure at 120 dpi."""
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(3)
    P = rng.uniform(0, 1, (60, 2))
    F = Delaunay(P * np.array([1.0, 6.0])).simplices  # not Delaunay for the true metric
    u, w = P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]
    cw = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0] < 0
    F[cw] = F[cw][:, [0, 2, 1]]
    V = np.column_stack([P, np.zeros(60)])
    result, fig = iplot.before_after(V, F)
    assert result.n_flips > 0 and dg.intrinsic.is_delaunay(result)
    start = dg.intrinsic.from_mesh(V, F)
    before, after = fig.axes
    assert [ax.name for ax in fig.axes] == ["rectilinear", "rectilinear"]
    assert [ax.get_title() for ax in fig.axes] == ["start triangulation", f"after {result.n_flips} flips"]
    assert_panel_shows(before, start, V)
    assert_panel_shows(after, result.triangulation, V)
    assert len(after.collections[1].get_segments()) == 0 < len(before.collections[1].get_segments())
    with pytest.raises(AssertionError):  # negative control: the start panel is not the flipped triangulation
        assert_panel_shows(before, result.triangulation, V)
    plt.close(fig)

    path = tmp_path / "flips.png"
    open_figures = len(plt.get_fignums())
    saved = iplot.before_after(V, F, path)  # with a path: the flip result, the figure written and closed
    assert saved.n_flips == result.n_flips and len(plt.get_fignums()) == open_figures
    assert plt.imread(path).shape == (600, 1200, 4)
