"""Simplicial area and minimal surfaces (Sec 6.4): `energies.area`'s entry points, their methods,
errors and plots.  Thm 6.7, the catenoid of Fig 6.5 (criticality, order of the neck, the Newton
polish) and Fig 6.6 are `ddgjax verify` checks (`sec6_laplace`)."""

import jax
import numpy as np
import pytest
from scipy.optimize import brentq

import ddgjax as dg
from ddgjax.errors import (
    ConvergenceError,
    DegenerateFaceError,
    InvalidInputError,
    NonFiniteError,
    NonManifoldError,
)
from ddgjax.verify import references
from energies import area


def jittered(V, seed, scale=0.05):
    return V + scale * np.random.default_rng(seed).normal(size=V.shape)


# The catenoid between the coaxial circles of radius R at z = ±H.


def cylinder(n, R=1.0, H=0.5):
    """The start: n + 1 rings of 3n vertices on the cylinder of radius R, |z| ≤ H (h = 2H/n)."""
    V, F = dg.mesh.annulus(3 * n, n + 1, 1.0, 2.0)
    t, s = np.arctan2(V[:, 1], V[:, 0]), np.linalg.norm(V[:, :2], axis=1) - 1.0
    return np.stack([R * np.cos(t), R * np.sin(t), H * (2 * s - 1)], 1), F


def test_planar_boundary_gives_a_planar_surface():
    V, F = dg.mesh.disk(4, 12)
    V = jittered(V, 2, 0.02)
    b = dg.mesh.boundary_vertices(F, len(V))
    V[b, 2] = 0.0
    before = V.copy()
    Vm, _, info = area.minimal_surface(V, F, tol=1e-12)
    assert np.array_equal(V, before)  # the input is not changed
    assert np.max(np.abs(Vm[:, 2])) < 1e-14
    assert info["converged"] and info["iterations"] <= 3


def fig_6_6_star(h, r=0.3, s=1.0):
    """A vertex at (0, 0, h) over a hexagon alternating between radius 1 at z = 0 and radius r at z = s."""
    theta = np.arange(6) * np.pi / 3
    far = np.arange(6) % 2 == 0
    ring = np.stack([np.where(far, 1.0, r) * np.cos(theta), np.where(far, 1.0, r) * np.sin(theta), np.where(far, 0.0, s)], 1)
    F = np.array([[0, 1 + j, 1 + (j + 1) % 6] for j in range(6)])
    return np.vstack([[0.0, 0.0, h], ring]), F


def test_newton_finds_the_fig_6_6_star_from_a_perturbed_start():
    """Newton on the area functional (`minimal_surface(method="newton")`, through `solve`) finds the
    Fig 6.6 star, a critical point with negative weights outside the convex hull of its
    neighbours, from a perturbed start (the statements are `ddgjax verify` checks)."""
    z_gradient = lambda h: (dg.laplace.cotan_laplacian(*fig_6_6_star(h)) @ fig_6_6_star(h)[0])[0, 2]
    h = brentq(z_gradient, 1.02, 1.1, xtol=1e-15)
    V, F = fig_6_6_star(h)
    start = V.copy()
    start[0] += [0.02, -0.01, 0.03]
    V_newton, _, info = area.minimal_surface(start, F, method="newton", tol=1e-12)
    assert info["converged"] and np.max(np.abs(V_newton - V)) < 1e-12


def test_bad_input():
    V, F = cylinder(4)
    with pytest.raises(InvalidInputError, match="method"):
        area.minimal_surface(V, F, method="conformal")
    with pytest.raises(InvalidInputError, match="boundary vertex 999"):
        area.simplicial(V, F, [0, 999])
    W = V.copy()
    W[9] = np.nan
    with pytest.raises(NonFiniteError, match="vertex 9"):
        area.minimal_surface(W, F)
    W = V.copy()
    W[F[5, 0]] = W[F[5, 1]]  # face 5 (and others at that vertex) collapse
    with pytest.raises(DegenerateFaceError, match="face"):
        area.simplicial(W, F)
    with pytest.raises(NonManifoldError):
        area.simplicial(np.random.default_rng(0).normal(size=(5, 3)), np.array([[0, 1, 2], [0, 3, 4]]))


def test_delaunay_method_is_fig_7_23_accelerated_by_newton():
    """`method="delaunay"` with `newton=False` is `harmonic_iteration(flip=True)`; by default its
    result is a fixed point of Fig 7.23 to 1e-12 (one more step finds T Delaunay, no flip, and
    the residual within tol) reached with Newton steps, within 1e-4 of the plain iteration's at
    1e-6."""
    V, F = cylinder(4)
    V1, F1, info = area.minimal_surface(V, F, method="delaunay", tol=1e-6, newton=False)
    V2, F2, _ = area.harmonic_iteration(V, F, None, flip=True, tol=1e-6)
    assert info["converged"] and np.array_equal(V1, V2) and np.array_equal(F1, F2)
    W, FW, info = area.minimal_surface(V, F, method="delaunay", tol=1e-12)
    assert info["converged"] and info["newton_iterations"] > 0
    _, _, again = area.harmonic_iteration(W, FW, None, flip=True, tol=1e-12, max_iter=0)
    assert again["converged"] and again["flips"].sum() == 0 and again["residual"] <= 1e-12
    assert np.max(np.abs(W - V1)) < 1e-4


def test_narrow_sense_minimal_surface_with_a_non_planar_boundary():
    """Fig 7.23 (Def 7.9) on Enneper's surface over |w| ≤ 0.8, a non-planar boundary, 4-ring
    polar disk: with Newton it converges to residual ≤ 1e-10 on a triangulation that is
    intrinsically Delaunay for the result (so L_T is its Laplace–Beltrami operator and the
    surface is a fixed point of the iteration, Remark 7.10), within 1e-2 of the exact surface.
    Negative control: the plain iteration is still above 1e-6 after 1,000 steps."""
    from ddgjax import intrinsic

    V, F, b, w = enneper_disk(4)
    W, FW, info = area.minimal_surface(V, F, b, method="delaunay")
    assert info["converged"] and info["residual"] <= 1e-10 and info["flips"].sum() > 0
    assert intrinsic.is_delaunay(intrinsic.from_mesh(W, FW)) and np.array_equal(W[b], V[b])
    assert references.enneper_distance(W, w).max() < 1e-2
    _, _, plain = area.minimal_surface(V, F, b, method="delaunay", newton=False, throw=False)
    assert not plain["converged"] and plain["residual"] > 1e-6


def _rows(colours) -> list:
    """RGBA rows as a sorted list of rounded tuples."""
    return sorted(map(tuple, np.round(np.asarray(colours), 12)))


def assert_minimal_surface_plot_shows(fig, V, F, history):
    """`plot_laplace.minimal_surface`'s figure: the surface in 3-D, one polygon per triangle,
    coloured by the angle defect K at the interior vertices (0 on the boundary) on a colour bar
    symmetric about 0; beside it the residual history against the iteration on a log scale."""
    import matplotlib

    surface, bar, history_ax = fig.axes
    assert [ax.name for ax in fig.axes] == ["3d", "rectilinear", "rectilinear"] and bar.get_label() == "<colorbar>"
    K = np.array(dg.mesh.angle_defect(V, F))
    K[np.concatenate(dg.mesh.boundary_loops(F))] = 0.0
    values = K[F].mean(axis=1)
    scale = np.max(np.abs(values))
    assert bar.get_ylim() == pytest.approx((-scale, scale), rel=1e-12) and bar.get_ylabel() == "angle defect K"
    (faces,) = surface.collections
    expected = matplotlib.colormaps["coolwarm"]((values + scale) / (2 * scale))
    assert _rows(faces.get_facecolor()) == _rows(expected)  # whatever order the faces are painted in
    limits = np.array([surface.get_xlim(), surface.get_ylim(), surface.get_zlim()])
    assert np.all(limits[:, 0] <= V.min(axis=0)) and np.all(limits[:, 1] >= V.max(axis=0))
    (line,) = history_ax.lines
    np.testing.assert_array_equal(line.get_xdata(), np.arange(len(history)))
    np.testing.assert_array_equal(line.get_ydata(), history)
    assert history_ax.get_yscale() == "log" and history_ax.get_xlabel() == "iteration"
    assert history_ax.get_title() == "convergence"
    fig.canvas.draw()  # the polygons are projected when drawn
    assert len(faces.get_paths()) == len(F)


def test_plot_minimal_surface(tmp_path):
    import matplotlib.pyplot as plt

    from ddgjax.plot import laplace as plot_laplace

    V, F = cylinder(4)
    Vm, _, info = area.minimal_surface(V, F, tol=1e-5)
    history = np.asarray(info["history"])
    fig = plot_laplace.minimal_surface(Vm, F, history=history, title="catenoid")
    assert_minimal_surface_plot_shows(fig, Vm, F, history)
    assert fig.axes[0].get_title() == "catenoid"
    with pytest.raises(AssertionError):  # negative control: the start cylinder is not the minimal surface
        assert_minimal_surface_plot_shows(fig, V, F, history)
    plt.close(fig)
    fig = plot_laplace.minimal_surface(Vm, F)  # without a history: the surface and its colour bar only
    assert [ax.name for ax in fig.axes] == ["3d", "rectilinear"]
    plt.close(fig)
    path = plot_laplace.minimal_surface(Vm, F, tmp_path / "catenoid.png", history=history)
    assert path == tmp_path / "catenoid.png"
    assert plt.imread(path).shape == (495, 1100, 4)  # 10 × 4.5 in at 110 dpi


def test_default_minimal_surface_is_a_minimum_of_the_area():
    """The default method (Fig 6.5 to a loose tolerance, then Newton with inertia correction)
    converges to tol and returns a local minimum: no negative eigenvalue of the area Hessian on
    the free vertices (Sylvester: counted by the LDLᵀ pivots and, here, by the dense spectrum)."""
    V, F = cylinder(6)
    W, F, info = area.minimal_surface(V, F)
    assert info["converged"] and info["residual"] <= 1e-10 and info["minimum"]
    problem = area.simplicial(W, F)
    free = ~np.asarray(problem.fixed).ravel()
    H = np.asarray(jax.jit(jax.hessian(lambda x: problem.energy(x.reshape(-1, 3), None)))(W.ravel()))[np.ix_(free, free)]
    eigenvalues = np.linalg.eigvalsh(H)
    assert eigenvalues[0] > 0
    assert abs(references.neck_radius(W) - references.catenoid_neck()) < 0.02


def test_minimal_surface_between_circles_too_far_apart_pinches():
    """Two coaxial unit circles at distance 1.4 bound no catenoid (c cosh(H/c) = 1 has no root for
    H = 0.7 > 0.6627): a clear error that the surface pinched, never a converged surface."""
    V, F = cylinder(8, H=0.7)
    with pytest.raises(ConvergenceError, match="pinched") as error:
        area.minimal_surface(V, F)
    assert "input mesh is not at fault" in str(error.value)
    # negative control: at distance 1 the same call converges
    assert area.minimal_surface(*cylinder(8))[2]["converged"]


def enneper_disk(rings):
    """Enneper's surface over |w| ≤ 0.8 meshed as the polar disk `dg.mesh.disk(rings, 4 rings)`:
    the boundary on the surface, the interior started flat (`sec7_narrow.enneper_polar_disk`),
    and the parameter w of each vertex."""
    from ddgjax.verify.checks.sec7_narrow import enneper_polar_disk

    V, F, b = enneper_polar_disk(rings)
    D, _ = dg.mesh.disk(rings, 4 * rings)
    return V, F, b, 0.8 * (D[:, 0] + 1j * D[:, 1])


def test_default_minimal_surface_converges_to_a_minimum_on_enneper():
    """Enneper's surface over |w| ≤ 0.8 on polar disks of 4 and 8 rings: the default method converges
    (residual ≤ 1e-10) to a local minimum of the area (inertia of the Hessian on the free vertices,
    `info["minimum"]`; at 4 rings also the dense spectrum), and the vertices' distance to the exact
    surface falls at order ≈ 2 (Sec 6.4; here 1.8–1.9 at these resolutions).  Negative control:
    the start fails the distance bound."""
    distances = []
    for rings in (4, 8):
        V, F, b, w = enneper_disk(rings)
        W, F2, info = area.minimal_surface(V, F, b)
        assert info["converged"] and info["residual"] <= 1e-10 and info["minimum"]
        assert np.array_equal(W[b], V[b])
        distances.append(references.enneper_distance(W, w).max())
        if rings == 4:
            problem = area.simplicial(W, F2, b)
            free = ~np.asarray(problem.fixed).ravel()
            H = jax.jit(jax.hessian(lambda x: problem.energy(x.reshape(-1, 3), None)))(W.ravel())
            assert np.linalg.eigvalsh(np.asarray(H)[np.ix_(free, free)])[0] > 0
    assert distances[1] < 4e-3 and np.log2(distances[0] / distances[1]) > 1.7
    assert references.enneper_distance(V, w).max() > 50 * distances[1]  # the flat start fails the bound


@pytest.mark.slow
def test_default_minimal_surface_neck_order_two():
    """The 24×8 … 96×32 cylinders between unit circles at distance 1: the default method converges
    (residual ≤ 1e-10) and the neck radius tends to c (c cosh(1/(2c)) = 1) at order 2."""
    errors = []
    for n in (8, 16, 32):
        W, _, info = area.minimal_surface(*cylinder(n))
        assert info["converged"] and info["residual"] <= 1e-10
        errors.append(abs(references.neck_radius(W) - references.catenoid_neck()))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.1)


@pytest.mark.slow
def test_default_minimal_surface_on_a_wavy_tall_dome_fails_with_a_convergence_error():
    """A non-planar boundary (`tall_dome(wave=0.3)`) on which the minimisation lets a face become
    flat in space after a Delaunay re-flip: `ConvergenceError` saying a triangle degenerated (the
    documented failure), never the `NonFiniteError` of the inner solve blaming its start."""
    V, F, b = dg.mesh.builtin.tall_dome(0, wave=0.3)
    with pytest.raises(ConvergenceError, match="degenerated"):
        area.minimal_surface(V, F, b)


@pytest.mark.parametrize("args, message", [((0,), "n >= 1"), ((4, -0.5), "height"), ((4, float("nan")), "height")])
def test_between_circles_rejects_bad_input(args, message):
    """`area.between_circles(n, height)`: a cylinder without rings or a height that is not finite
    and positive raises `InvalidInputError` naming the argument."""
    with pytest.raises(dg.errors.InvalidInputError, match=message):
        area.between_circles(*args)
