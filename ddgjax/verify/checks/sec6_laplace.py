"""Discrete Laplacians and simplicial minimal surfaces (Sec 6: Thm 6.1–6.7, Fig 6.5, 6.6)."""

from __future__ import annotations

import jax
import numpy as np
from scipy.optimize import brentq
from scipy.sparse.linalg import spsolve

import ddgjax as dg
from ddgjax.errors import NonUniqueSolutionError
from ddgjax.plot import laplace as plot_laplace
from ddgjax.verify import check, references
from energies import area, dirichlet

from ._surfaces import random_graph

GRAPHS = 20  # random connected graphs with positive weights per graph check


def _graph_problem(seed: int):
    """`(edges, weights, boundary, values, f)`: a random dDBVP and its solution by sparse LU."""
    edges, weights, rng = random_graph(seed)
    boundary = rng.choice(14, size=int(rng.integers(1, 6)), replace=False)
    values = rng.normal(size=len(boundary))
    return edges, weights, boundary, values, dirichlet.graph_sparse(edges, weights, boundary, values)


def _interior(n: int, boundary) -> np.ndarray:
    return np.setdiff1d(np.arange(n), boundary)


@check("Thm 6.1", "the dDBVP solution is a critical point of the Dirichlet energy on F_(V0,c): ∇E = 0 off V0",
       quantity="max over random graphs of max_(i∉V0) |∂E/∂f_i| (autodiff of the declared energy)",
       at_most=1e-12, quick=dict(graphs=5), full=dict(graphs=GRAPHS))
def ddbvp_is_critical(ctx, graphs):
    worst = 0.0
    for seed in range(graphs):
        edges, weights, boundary, values, f = _graph_problem(seed)
        problem = dirichlet.graph(edges, weights, boundary, values)
        gradient = np.asarray(jax.jit(jax.grad(problem.energy))(f, problem.params))
        worst = max(worst, float(np.max(np.abs(gradient[_interior(14, boundary)]))))
    return worst


@check("Thm 6.5", "positive weights, connected, V0 ≠ ∅: the energy on F_(V0,c) is strictly convex (unique minimum)",
       quantity="min over 20 random graphs of λ_min(L_II) (interior block of L)", at_least=1e-6,
       quick=dict(graphs=GRAPHS))
def dirichlet_minimum_is_unique(ctx, graphs):
    smallest = np.inf
    for seed in range(graphs):
        edges, weights, boundary, _, _ = _graph_problem(seed)
        inner = _interior(14, boundary)
        L = dg.laplace.graph_laplacian(edges, weights).toarray()
        smallest = min(smallest, float(np.linalg.eigvalsh(L[np.ix_(inner, inner)])[0]))
    return smallest


@check("Thm 6.2", "maximum principle: with positive weights a harmonic f takes its max and min on V0",
       quantity="max over 20 random graphs of how far f exceeds [min c, max c] off V0, and of how far f is from "
       "harmonic off V0 (|(L f)_i|) with f = c on V0", at_most=1e-12, quick=dict(graphs=GRAPHS))
def maximum_principle(ctx, graphs):
    worst = 0.0
    for seed in range(graphs):
        edges, weights, boundary, values, f = _graph_problem(seed)
        inner = _interior(14, boundary)
        harmonic = float(np.max(np.abs((dg.laplace.graph_laplacian(edges, weights) @ f)[inner])))
        if not np.array_equal(f[boundary], values):
            return float("inf")
        worst = max(worst, float(f[inner].max() - values.max()), float(values.min() - f[inner].min()), harmonic)
    return worst


@check("Thm 6.2, eq (6.3)", "negative control: with a negative weight the maximum principle fails "
       "(0 joined to V0 = {1, 2} with ν = 2, −1 and c = 0, 1 gives f_0 = −1)",
       quantity="min c − f_0 (−∞ unless f_0 = −1 to 1e-14)", at_least=0.5, quick=dict())
def maximum_principle_fails_with_negative_weight(ctx):
    f = dirichlet.graph_sparse([[0, 1], [0, 2]], [2.0, -1.0], [1, 2], [0.0, 1.0])
    return 0.0 - float(f[0]) if abs(f[0] + 1.0) < 1e-14 else float("-inf")


def _kernel(L: np.ndarray) -> np.ndarray:
    """The unit eigenvectors of L with eigenvalue ≈ 0, as columns."""
    eig, vec = np.linalg.eigh(L)
    return vec[:, np.abs(eig) <= 1e-10 * np.abs(eig).max()]


def _kernel_spread(L: np.ndarray) -> float:
    """max peak-to-peak of the unit eigenvectors of L with eigenvalue ≈ 0 (0 iff ker L = constants)."""
    return float(np.ptp(_kernel(L), axis=0).max())


@check("Cor 6.3", "discrete Liouville: on a connected graph with positive weights every harmonic function is constant",
       quantity="max over 20 graphs of the spread of the unit vectors of ker L", at_most=1e-12,
       quick=dict(graphs=GRAPHS))
def liouville(ctx, graphs):
    return max(_kernel_spread(dg.laplace.graph_laplacian(*random_graph(seed)[:2]).toarray()) for seed in range(graphs))


@check("Cor 6.3", "negative control: the triangle with weights 1, 1, −½ has a non-constant harmonic function "
       "(ker L is two-dimensional)", quantity="spread of the unit vectors of ker L (−∞ unless dim ker L = 2)",
       at_least=0.1, quick=dict())
def liouville_fails_with_negative_weight(ctx):
    L = dg.laplace.graph_laplacian([[0, 1], [1, 2], [2, 0]], [1.0, 1.0, -0.5]).toarray()
    return _kernel_spread(L) if _kernel(L).shape[1] == 2 else float("-inf")


def _jacobi(L, boundary, values, f, sweeps: int) -> np.ndarray:
    """`sweeps` Jacobi sweeps f_i ← Σ_j ν_ij f_j / Σ_j ν_ij at the interior vertices (values kept on V0)."""
    L = L.toarray()
    d = np.diag(L).copy()
    W = np.diag(d) - L
    inner = _interior(len(f), boundary)
    f = f.copy()
    f[boundary] = values
    for _ in range(sweeps):
        f[inner] = (W[inner] @ f) / d[inner]
    return f


@check("Cor 6.4", "the dDBVP solution is unique: Jacobi sweeps from two random starts reach the sparse-LU solution",
       quantity="max over random graphs and 2 starts each of |f_Jacobi − f_LU|", at_most=1e-10, quick=dict(graphs=5),
       full=dict(graphs=GRAPHS))
def ddbvp_is_unique(ctx, graphs):
    worst = 0.0
    for seed in range(graphs):
        edges, weights, boundary, values, f = _graph_problem(seed)
        L = dg.laplace.graph_laplacian(edges, weights)
        for start in np.random.default_rng(seed).normal(scale=10.0, size=(2, 14)):
            worst = max(worst, float(np.max(np.abs(_jacobi(L, boundary, values, start, 4000) - f))))
    return worst


@check("Cor 6.4", "negative control: weights 1, −1 at the only interior vertex make L_II = 0: no unique solution",
       quantity="1 if dirichlet_solve raises NonUniqueSolutionError", at_least=1.0, quick=dict())
def ddbvp_not_unique_with_negative_weight(ctx):
    try:
        dirichlet.graph_sparse([[0, 1], [0, 2]], [1.0, -1.0], [1, 2], [0.0, 1.0])
    except NonUniqueSolutionError:
        return 1.0
    return 0.0


@check("Thm 6.1, 6.5", "Newton on the declared Dirichlet energy (solvers.solve) from two starts equals the sparse path",
       quantity="max |f_solve − f_LU|", at_most=1e-10, quick=dict(), full_only=True)
def ddbvp_solve_equals_sparse(ctx):
    from solvers import solve

    edges, weights, boundary, values, f = _graph_problem(0)
    problem = dirichlet.graph(edges, weights, boundary, values)
    other = np.where(problem.fixed, problem.x0, 10 * np.random.default_rng(1).normal(size=14))
    return max(float(np.max(np.abs(np.asarray(solve(p, tol=1e-12).x) - f))) for p in (problem, problem.with_x0(other)))


def _jittered_disk(rings: int = 3, m: int = 10, seed: int = 0):
    V, F = dg.mesh.disk(rings, m)
    rng = np.random.default_rng(seed)
    return V + 0.05 * rng.normal(size=V.shape) + [0.0, 0.0, 0.1] * rng.normal(size=(len(V), 1)), F


def _cotan_from_angles(V, F):
    """eq (6.2) from the corner angles: ν(ij) = ½ Σ cot of the angles opposite (ij), dense L."""
    cot = 0.5 / np.tan(np.asarray(dg.mesh.corner_angles(V, F)))
    i, j = F[:, [1, 2, 0]].ravel(), F[:, [2, 0, 1]].ravel()  # the edge opposite corner k
    W = np.zeros((len(V), len(V)))
    np.add.at(W, (i, j), cot.ravel())
    W = W + W.T
    return np.diag(W.sum(1)) - W


@check("Thm 6.6", "the Hessian (by autodiff) of the declared Dirichlet energy ½∫|∇f|² is the cotan Laplacian (6.2)",
       quantity="max |∇²E − L(angles)| and |L(ddgjax) − L(angles)| over jittered 3D disks (interior and boundary edges)",
       at_most=1e-12, quick=dict(rings=3, disks=3), full=dict(rings=6, disks=10))
def cotan_hessian(ctx, rings, disks):
    worst, hessian = 0.0, None
    for seed in range(disks):
        V, F = _jittered_disk(rings, seed=seed)
        problem = dirichlet.cotan(V, F, [0], [0.0])
        if hessian is None:  # one compilation: the disks share F, the positions enter through params
            hessian = jax.jit(jax.hessian(problem.energy))
        oracle = _cotan_from_angles(V, F)
        worst = max(worst, float(np.max(np.abs(np.asarray(hessian(np.zeros(len(V)), problem.params)) - oracle))),
                    float(np.max(np.abs(dg.laplace.cotan_laplacian(V, F).toarray() - oracle))))
    return worst


@check("Thm 6.7", "A(S) = Σ_k E(f_k) (Dirichlet energies of the coordinates) and ∇A = L f (autodiff of the area)",
       quantity="max over a jittered disk and a jittered icosphere of |A − Σ E(f_k)| / A (E declared, and ½ fᵀ L f), "
       "|A − surface_area| / A and max |∇A − L f|", at_most=1e-12, quick=dict(rings=3, level=1),
       full=dict(rings=6, level=3))
def area_is_dirichlet_energy(ctx, rings, level):
    V, F = dg.mesh.icosphere(level)
    sphere = V + 0.05 * np.random.default_rng(1).normal(size=V.shape), F
    worst = 0.0
    for V, F in (_jittered_disk(rings, seed=1), sphere):
        problem = area.simplicial(V, F, [0])
        A, gradient = jax.jit(jax.value_and_grad(problem.energy))(V, None)
        A, gradient = float(A), np.asarray(gradient)
        L = dg.laplace.cotan_laplacian(V, F)
        coordinate = dirichlet.cotan(V, F, [0], [0.0])
        declared = float(np.sum(jax.jit(jax.vmap(coordinate.energy, in_axes=(1, None)))(V, coordinate.params)))
        worst = max(worst, abs(A - declared) / A, abs(A - 0.5 * np.einsum("ik,ik->", V, L @ V)) / A,
                    abs(A - float(dg.mesh.surface_area(V, F))) / A, float(np.max(np.abs(gradient - L @ V))))
    return worst


def _catenoid(n: int):
    """Fig 6.5 from the cylinder to an area-gradient residual 0.05 h⁴-ish (0.05/n⁴): the geometry
    settles well below the O(h²) discretisation error."""
    return area.minimal_surface(*dg.mesh.builtin.cylinder(n), tol=0.05 / n**4, max_iter=4000)


CATENOID_H2 = 0.25  # n² max_i |r_i − c cosh(z_i/c)| of the discrete minimum is 0.19–0.20 for n = 4…32


@check("Fig 6.5, Thm 6.7", "the Pinkall–Polthier iteration from the cylinder (stopped at max |L f| ≤ 1e-6) lowers "
       "the area and lands on the smooth catenoid r(z) = c cosh(z/c) (c cosh(H/c) = R) to O(h²), h = 1/n",
       quantity="n² · max over vertices of |r_i − c cosh(z_i/c)| (the discrete minimum: 0.19–0.20 at n = 4…32)",
       at_most=CATENOID_H2, quick=dict(n=16), full=dict(n=32))
def catenoid_is_critical(ctx, n):
    V, F, info = area.minimal_surface(*dg.mesh.builtin.cylinder(n), method="cotan", tol=1e-6, max_iter=4000)
    plot_laplace.minimal_surface(V, F, ctx.figure("catenoid.png"), history=info["history"],
                                 title=f"Fig 6.5: catenoid, n = {n}")
    if not info["area"][-1] < info["area"][0]:
        return float("inf")
    c = references.catenoid_neck()
    return n**2 * float(np.max(np.abs(np.linalg.norm(V[:, :2], axis=1) - c * np.cosh(V[:, 2] / c))))


@check("Fig 6.5", "the neck radius of the simplicial catenoid converges to the smooth catenoid's c (c cosh(H/c) = R), O(h²)",
       quantity="fitted order of |min r − c|", target=2.0, within=0.3, quick=dict(ns=(4, 6, 8, 12)),
       full=dict(ns=(8, 12, 16, 24, 32)))
def catenoid_neck_order(ctx, ns):
    c = references.catenoid_neck()
    table = dg.limits.convergence(lambda n: abs(references.neck_radius(_catenoid(n)[0]) - c), ns, label="neck radius error")
    return ctx.convergence(table, "convergence_catenoid_neck", title="Fig 6.5: catenoid neck radius").fitted_order


@check("Fig 6.5", "Newton on the area (solvers.solve) from the Pinkall–Polthier iterate (which lowered the area) "
       "converges in ≤ 5 steps to a critical point within 1e-3 of it",
       quantity="max_(i interior) |(L f)_i| after Newton", at_most=1e-11, quick=dict(n=4), full_only=True)
def catenoid_newton_polish(ctx, n):
    V1, F, info1 = area.minimal_surface(*dg.mesh.builtin.cylinder(n), tol=1e-6)
    V2, _, info = area.minimal_surface(V1, F, method="newton", tol=1e-11)
    inner = _interior(len(V2), dg.mesh.boundary_vertices(F, len(V2)))
    residual = float(np.max(np.abs((dg.laplace.cotan_laplacian(V2, F) @ V2)[inner])))
    ok = (info["converged"] and info["iterations"] <= 5 and np.max(np.abs(V2 - V1)) < 1e-3
          and info1["area"][-1] < info1["area"][0])
    return residual if ok else float("inf")


def _star(h: float, r: float = 0.3, s: float = 1.0):
    """Fig 6.6: a vertex at (0, 0, h) joined to a hexagon whose corners alternate between radius 1
    at height 0 and radius r at height s."""
    phi = np.arange(6) * np.pi / 3
    radius = np.where(np.arange(6) % 2 == 0, 1.0, r)
    hexagon = np.stack([radius * np.cos(phi), radius * np.sin(phi), np.where(np.arange(6) % 2 == 0, 0.0, s)], 1)
    return np.vstack([[0.0, 0.0, h], hexagon]), np.array([[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)])


def _fig_6_6():
    """The star whose centre is critical for the area (the z-component of ∇A = L f vanishes; x, y
    vanish by symmetry), found by bracketing in h above the hexagon."""
    h = brentq(lambda h: (dg.laplace.cotan_laplacian(*_star(h)) @ _star(h)[0])[0, 2], 1.02, 1.1, xtol=1e-15)
    return _star(h)


@check("Fig 6.6, eq (6.3)", "a simplicial minimal surface with negative weights (α_ij + α_ji > π): ∇A = 0 at the centre",
       quantity="|∇A| at the centre vertex", at_most=1e-12, quick=dict())
def negative_weights_star_is_critical(ctx):
    V, F = _fig_6_6()
    dg.plot.surface.surface(V, F, ctx.figure("fig_6_6_star.png"), title="Fig 6.6: minimal, outside the convex hull")
    return float(np.max(np.abs((dg.laplace.cotan_laplacian(V, F) @ V)[0])))


@check("Prop 6.8, Fig 6.6", "negative control: the critical centre of Fig 6.6 lies above all its neighbours, outside "
       "their convex hull (the weights of the three spokes to the far corners are negative: α_ij + α_ji > π, eq 6.3)",
       quantity="height of the centre above the highest neighbour (−∞ unless ν < −0.1 at the far spokes, ν > 0 at the "
       "others, and α_ij + α_ji > π exactly where ν < 0)", at_least=0.02, quick=dict())
def negative_weights_break_convex_hull(ctx):
    V, F = _fig_6_6()
    weights = dg.laplace.cotan_weights(V, F).toarray()[0, 1:]
    alpha = np.asarray(dg.mesh.corner_angles(V, F))
    opposite = np.array([alpha[k, 2] + alpha[k - 1, 1] for k in range(6)])  # the two angles opposite spoke (0, 1 + k)
    ok = np.all(weights[::2] < -0.1) and np.all(weights[1::2] > 0) and np.array_equal(opposite > np.pi, weights < 0)
    return float(V[0, 2] - V[1:, 2].max()) if ok else float("-inf")


JITTER = 0.2  # interior vertices move by ≤ 0.2 h in x and y: ≤ 0.57 h relative to an opposite side, < h/√2


def _cot(p, q, r) -> np.ndarray:
    """cot of the angle at p of the planar triangles (p, q, r), rows of (k, 2) arrays."""
    u, v = q - p, r - p
    return np.sum(u * v, 1) / np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])


def _irregular_square(n: int, seed: int = 0):
    """`(V, F, boundary)`: `unit_square(n)` with the interior vertices moved uniformly by up to
    JITTER · h in x and y, each grid quad cut along its non-Delaunay diagonal (the two angles
    opposite it sum to more than π: ν < 0 there, eq 6.3)."""
    V, _, b = dg.mesh.builtin.unit_square(n)
    inner = _interior(len(V), b)
    V[inner, :2] += JITTER / n * np.random.default_rng(seed).uniform(-1, 1, size=(len(inner), 2))
    Q = dg.mesh.builtin.grid_quads(n + 1, n + 1, False, False)  # (a, b, c, d) counterclockwise
    a, p, c, d = (V[Q[:, k], :2] for k in range(4))
    ac_not_delaunay = _cot(p, c, a) + _cot(d, a, c) < 0
    return V, dg.mesh.builtin.triangulate(np.where(ac_not_delaunay[:, None], Q, np.roll(Q, -1, axis=1))), b


LAPLACIANS = {"extrinsic": dg.laplace.cotan_laplacian, "intrinsic": dg.intrinsic.laplace_beltrami}


def _laplacian_error(n: int, mesh=dg.mesh.builtin.unit_square, laplacian=dg.laplace.cotan_laplacian) -> float:
    """max over interior vertices of |−(L f)_i / M_i − Δf(x_i)|, f = sin(πx) cos(2y)."""
    V, F, b = mesh(n)
    f = np.sin(np.pi * V[:, 0]) * np.cos(2 * V[:, 1])
    approx = -(laplacian(V, F) @ f) / dg.laplace.barycentric_areas(V, F)
    return float(np.max(np.abs(approx + (np.pi**2 + 4) * f)[_interior(len(V), b)]))


def _irregular_harmonic_error(n: int, laplacian) -> float:
    """√(Σ_i M_i (f_i − u_i)²) for the dDBVP solution f of `laplacian` on `_irregular_square(n)`
    with the boundary values of the harmonic u = eˣ sin y (sparse LU of L_II)."""
    V, F, b = _irregular_square(n)
    u = np.exp(V[:, 0]) * np.sin(V[:, 1])
    L, inner, f = laplacian(V, F).tocsr(), _interior(len(V), b), u.copy()
    f[inner] = spsolve(L[inner][:, inner].tocsc(), -(L[inner][:, b] @ u[b]))
    return float(np.sqrt(np.sum(dg.laplace.barycentric_areas(V, F) * (f - u) ** 2)))


def _harmonic_error(n: int, figure=None) -> float:
    """max |f − u| for the dDBVP solution f of the cotan Laplacian with the boundary values of the
    harmonic u = eˣ sin y."""
    V, F, b = dg.mesh.builtin.unit_square(n)
    u = np.exp(V[:, 0]) * np.sin(V[:, 1])
    f = dirichlet.cotan_sparse(V, F, b, u[b])
    if figure is not None:
        plot_laplace.harmonic_function(V, F, f, figure, title="dDBVP with the boundary values of eˣ sin y")
    return float(np.max(np.abs(f - u)))


@check("Def 6.2, Sec 6.3", "smooth limit: −(L f)_i / M_i → Δf(x_i) on the regular triangulated square, O(h²)",
       quantity="fitted order of max |−Lf/M − Δf|", target=2.0, within=0.3, quick=dict(ns=(8, 16, 32)),
       full=dict(ns=(8, 16, 32, 64, 128)))
def cotan_laplacian_limit(ctx, ns):
    table = dg.limits.convergence(_laplacian_error, ns, label="max error of −Lf/M against Δf")
    return ctx.convergence(table, "convergence_cotan_laplacian").fitted_order


@check("Cor 6.4, Thm 6.6", "smooth limit: the dDBVP solution with the boundary values of a harmonic u tends to u, O(h²)",
       quantity="fitted order of max |f − u|", target=2.0, within=0.3, quick=dict(ns=(8, 16, 32)),
       full=dict(ns=(8, 16, 32, 64, 128)))
def ddbvp_limit(ctx, ns):
    _harmonic_error(ns[0], figure=ctx.figure("ddbvp_harmonic.png"))
    table = dg.limits.convergence(_harmonic_error, ns, label="max error of f against u")
    return ctx.convergence(table, "convergence_ddbvp").fitted_order


@check("Def 6.2, Def 7.8", "negative control: on jittered squares cut along their non-Delaunay diagonals −(L f)_i / M_i "
       "does not tend to Δf(x_i), neither for the extrinsic cotan Laplacian nor for the intrinsic Delaunay one",
       quantity="max over the two Laplacians of the fitted order of max |−Lf/M − Δf| (+∞ unless the error at the "
       "finest n is ≥ 1)", at_most=0.5, quick=dict(ns=(8, 16, 32)), full=dict(ns=(8, 16, 32, 64, 128)))
def cotan_laplacian_limit_irregular(ctx, ns):
    orders = []
    for name, laplacian in LAPLACIANS.items():
        table = dg.limits.convergence(lambda n: _laplacian_error(n, _irregular_square, laplacian), ns,
                                      label=f"max error of −Lf/M against Δf ({name})")
        ctx.convergence(table, f"convergence_{name}_laplacian_irregular", title=f"{name} Laplacian, jittered square")
        orders.append(table.fitted_order if table.errors[-1] >= 1.0 else float("inf"))
    return max(orders)


def _irregular_ddbvp_table(ctx, ns, name: str):
    table = dg.limits.convergence(lambda n: _irregular_harmonic_error(n, LAPLACIANS[name]), ns,
                                  label=f"mass-weighted L² error of f against u ({name})")
    return ctx.convergence(table, f"convergence_ddbvp_{name}_irregular", title=f"dDBVP, {name} Laplacian, jittered square")


@check("Def 6.2, Thm 6.6", "smooth limit (weak form): on jittered squares cut along their non-Delaunay diagonals "
       "(negative weights) the dDBVP solution of the extrinsic cotan Laplacian still tends to the harmonic u, O(h²)",
       quantity="fitted order of √(Σ M_i (f_i − u_i)²)", target=2.0, within=0.3, quick=dict(ns=(8, 16, 32)),
       full=dict(ns=(8, 16, 32, 64, 128)))
def ddbvp_limit_irregular(ctx, ns):
    return _irregular_ddbvp_table(ctx, ns, "extrinsic").fitted_order


@check("Def 7.8, Thm 6.6", "smooth limit (weak form): on the same meshes the dDBVP solution of the intrinsic Delaunay "
       "Laplacian (Laplace–Beltrami) tends to u, O(h²), with a smaller error than the extrinsic one at every n",
       quantity="fitted order of √(Σ M_i (f_i − u_i)²) (+∞ unless below the extrinsic error at every n)",
       target=2.0, within=0.3, quick=dict(ns=(8, 16, 32)), full=dict(ns=(8, 16, 32, 64, 128)))
def laplace_beltrami_ddbvp_limit_irregular(ctx, ns):
    table = _irregular_ddbvp_table(ctx, ns, "intrinsic")
    extrinsic = [_irregular_harmonic_error(n, LAPLACIANS["extrinsic"]) for n in ns]
    return table.fitted_order if np.all(table.errors < extrinsic) else float("inf")
