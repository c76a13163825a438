"""`solvers.stability`: the Hessian of the Lagrangian L = E − λ·g on the constraints' tangent space
(second-order condition for the Lagrange multipliers of Sec 3.1), its Morse index and the symmetry
zero modes it excludes.  The catenoid and elastica indices are also `ddgjax verify` checks
(`ext_stability`)."""

import functools

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import ddgjax as dg
import solvers
from ddgjax.errors import InvalidInputError, NonFiniteError, ShapeError
from ddgjax.smooth import elastica as exact
from energies import area, elastica
from solvers import Stability, solve, stability

# --- an explicit constrained quadratic ----------------------------------------------------------

A = np.array([2.0, 1.0, 3.0, 5.0])  # E = ½ Σ a_i x_i² on the unit sphere of R⁴ (+ a fixed fifth entry)


def sphere_quadratic(start):
    """E(x) = ½ Σ a_i x_i² + x_5² on |x_1..4|² = 1, x_5 fixed: at x = e_j, λ = a_j/2 (∇E = Jᵀλ with
    J = 2xᵀ) and ∇²L = diag(a) − 2λ I, so the reduced Hessian on e_j^⊥ has eigenvalues a_i − a_j."""
    x0 = np.append(np.asarray(start, float), 0.3)
    fixed = np.array([False] * 4 + [True])
    return dg.Problem(_quadratic, x0, constraints=_sphere, params={"a": A}, fixed=fixed, name="sphere quadratic")


def _quadratic(x, p):  # module-level: every problem of the family shares the compiled solver
    return 0.5 * jnp.sum(p["a"] * x[:4] ** 2) + x[4] ** 2


def _sphere(x, p):
    return jnp.array([jnp.sum(x[:4] ** 2) - 1.0])


@pytest.mark.parametrize("j", range(4))
def test_reduced_hessian_of_a_quadratic_on_the_sphere(j):
    problem = sphere_quadratic(np.eye(4)[j] + 0.01 * np.arange(1, 5) * (np.arange(4) != j))
    sol = solve(problem)
    assert abs(float(sol.multipliers[0]) - A[j] / 2) < 1e-12  # the sign convention: ∇E = Jᵀλ
    result = stability(problem, sol, k=6)
    expected = np.sort(np.delete(A - A[j], j))
    assert isinstance(result, Stability)
    assert result.eigenvalues.shape == (3,)  # k capped at the dimension of the tangent space
    np.testing.assert_allclose(result.eigenvalues, expected, atol=1e-10)
    assert result.index == int(np.sum(expected < 0)) == j_index(j)
    assert result.zero_modes == 0
    # eigenvectors: orthonormal, tangent to the sphere, eigenvectors of diag(a) − a_j I
    V = result.vectors
    assert V.shape == (4, 3)
    np.testing.assert_allclose(V.T @ V, np.eye(3), atol=1e-12)
    assert np.max(np.abs(np.asarray(sol.x)[:4] @ V)) < 1e-10
    np.testing.assert_allclose((A - A[j])[:, None] * V, V * result.eigenvalues, atol=1e-10)
    assert result.mode(0).shape == (5,) and float(result.mode(0)[4]) == 0.0  # fixed entry: no motion


def j_index(j):
    return int(np.sum(A < A[j]))  # the number of smaller a_i: the Morse index of e_j


# --- closed elastica: the regular polygon and Euler's figure-eight ------------------------------


@functools.cache
def regular_polygon(n):
    angles = 2 * np.pi * (np.arange(n) + 0.5) / n
    problem = elastica.closed(n, x0=np.stack([np.cos(angles), np.sin(angles), 0 * angles], 1))
    return problem, solve(problem)


@functools.cache
def figure_eight(n):
    """The closed discrete elastica near Euler's figure-eight (as `sec3_elastica` builds it)."""
    eight = exact.figure_eight(lam=exact.figure_eight(lam=1.0).period)  # period 1
    problem = elastica.closed(n, x0=eight.tangent((np.arange(n) + 0.5) * eight.length / n))
    return problem, solve(problem)


def test_regular_polygon_is_stable_with_three_rotation_zero_modes():
    """The n-gon is the minimum (Fenchel): index 0; the three rotations of R³ act on its tangents
    and are removed (translations do not act on tangents and are rejected)."""
    problem, sol = regular_polygon(32)
    result = stability(problem, sol, k=4)
    assert result.index == 0 and result.zero_modes == 3
    assert result.eigenvalues[0] > 1e-2 * 1.0  # bounded away from 0: no symmetry left in the spectrum
    # the eigenvectors avoid the rotations ω × T and lie in ker J
    T = np.asarray(sol.x)
    rotations = np.stack([np.cross(e, T).ravel() for e in np.eye(3)], 1)
    assert np.max(np.abs(rotations.T @ result.vectors)) < 1e-10
    J = np.asarray(__import__("jax").jacfwd(lambda t: dg.problem.constraint_values(problem, t, problem.params))(sol.x))
    assert np.max(np.abs(J.reshape(len(J), -1) @ result.vectors)) < 1e-10


def test_figure_eight_is_a_saddle():
    """Index 1; zero modes 3 (rotations), and one more null eigenvalue that is no Euclidean motion:
    the discrete figure-eight lies in a one-parameter family of critical points of equal energy
    (the phase of its sampling), so it is reported, not removed, and not counted in the index."""
    problem, sol = figure_eight(32)
    result = stability(problem, sol, k=4)
    assert result.index == 1 and result.zero_modes == 3
    assert result.eigenvalues[0] < -1e-2 * result.scale
    assert abs(result.eigenvalues[1]) < 1e-10 * result.scale
    assert result.eigenvalues[2] > 1e-3 * result.scale


def test_sparse_path_matches_dense_on_the_figure_eight():
    problem, sol = figure_eight(32)
    dense = stability(problem, sol, k=4, method="dense")
    sparse = stability(problem, sol, k=4, method="sparse")
    assert (sparse.index, sparse.zero_modes) == (dense.index, dense.zero_modes)
    np.testing.assert_allclose(sparse.eigenvalues, dense.eigenvalues, atol=1e-9 * dense.scale)
    # the nondegenerate eigenvectors agree up to sign
    for i in (0, 2):
        assert abs(abs(float(dense.vectors[:, i] @ sparse.vectors[:, i])) - 1) < 1e-8


@pytest.mark.parametrize("which", ["figure-eight", "unstable catenoid"])
def test_sparse_path_without_inertia(monkeypatch, which):
    """Without Pardiso the sparse path takes the eigenvalues nearest 0 and a Lanczos probe of the
    lowest one (the catenoid's negative eigenvalue lies beyond many soft tangential ones): same
    eigenvalues, same index."""
    problem, sol = figure_eight(32) if which == "figure-eight" else catenoid(6, False)
    dense = stability(problem, sol, k=3, method="dense")
    monkeypatch.setattr(solvers._direct, "pardiso_available", lambda: False)
    sparse = stability(problem, sol, k=3, method="sparse")
    assert sparse.index == dense.index == 1
    np.testing.assert_allclose(sparse.eigenvalues, dense.eigenvalues, atol=1e-8 * dense.scale)


# --- catenoids between the unit circles at z = ±½ ------------------------------------------------


def catenoid_roots():
    """The two roots c of c·cosh(½/c) = 1: the stable (c ≈ 0.848) and the unstable (c ≈ 0.235) catenoid."""
    f = lambda c: c * np.cosh(0.5 / c) - 1.0
    return brentq(f, 0.5, 1.0), brentq(f, 0.1, 0.4)


@functools.cache
def catenoid(n, stable):
    """The simplicial catenoid on `cylinder(n)` found by Newton from the smooth one (radius c cosh(z/c))."""
    V, F = dg.mesh.builtin.cylinder(n)
    c = catenoid_roots()[0 if stable else 1]
    r, z = np.linalg.norm(V[:, :2], axis=1), V[:, 2]
    start = V.copy()
    start[:, :2] *= (c * np.cosh(z / c) / r)[:, None]
    problem = area.simplicial(start, F)
    return problem, solve(problem)


def test_catenoid_roots():
    stable, unstable = catenoid_roots()
    assert abs(stable - 0.8483) < 1e-4 and abs(unstable - 0.2351) < 1e-4


@pytest.mark.parametrize("stable, index", [(True, 0), (False, 1)])
def test_catenoid_index(stable, index):
    """The catenoid with the larger neck is stable (index 0), the one with the smaller neck is
    not (index 1, its negative mode mostly normal).  The fixed boundary breaks the rotations."""
    problem, sol = catenoid(6, stable)
    result = stability(problem, sol, k=3)
    assert result.index == index and result.zero_modes == 0
    assert result.eigenvalues[index] > 0  # the rest is positive (tangential modes are soft, not negative)
    if not stable:
        V, mode = np.asarray(sol.x), np.asarray(result.mode(0))
        radial = V[:, :2] / np.linalg.norm(V[:, :2], axis=1, keepdims=True)
        assert np.linalg.norm(np.sum(mode[:, :2] * radial, axis=1)) > 0.8  # a change of the neck's radius
        assert result.eigenvalues[0] < -1e-3 * result.scale


def test_catenoid_sparse_path_matches_dense():
    problem, sol = catenoid(6, False)
    dense = stability(problem, sol, k=4, method="dense")
    sparse = stability(problem, sol, k=4, method="sparse")
    assert sparse.index == dense.index == 1
    np.testing.assert_allclose(sparse.eigenvalues, dense.eigenvalues, rtol=1e-8, atol=1e-10 * dense.scale)


# --- negative controls --------------------------------------------------------------------------


def test_bad_k_raises():
    problem, sol = regular_polygon(32)
    for k in (0, -1, 1.5, True):
        with pytest.raises(InvalidInputError, match="k must be"):
            stability(problem, sol, k=k)
    with pytest.raises(InvalidInputError, match="method"):
        stability(problem, sol, method="lanczos")


def test_solution_of_another_problem_raises():
    """Same shapes, another energy (a coupling x_1 x_2 added): e_1 is no critical point of it."""
    problem = sphere_quadratic(np.eye(4)[0])
    sol = solve(problem)
    coupled = dg.Problem(lambda x, p: problem.energy(x, p) + 0.5 * x[0] * x[1], problem.x0,
                         constraints=problem.constraints, params=problem.params, fixed=problem.fixed)
    with pytest.raises(InvalidInputError, match="not a critical point"):
        stability(coupled, sol)
    with pytest.raises(ShapeError):  # other shapes
        stability(regular_polygon(32)[0], sol)


def test_non_critical_point_raises():
    """The cylinder (the start of Fig 6.5, same boundary) is no critical point of the area."""
    problem, sol = catenoid(6, True)
    start = np.asarray(problem.x0).copy()
    interior = ~problem.fixed[:, 0]
    start[interior] = dg.mesh.builtin.cylinder(6)[0][interior]
    with pytest.raises(InvalidInputError, match="not a critical point"):
        stability(problem, sol._replace(x=jnp.asarray(start)))


def test_moved_fixed_entries_raise():
    problem, sol = catenoid(6, True)
    moved = np.asarray(sol.x).copy()
    moved[np.flatnonzero(problem.fixed[:, 0])[0]] += 1e-3
    with pytest.raises(InvalidInputError, match="fixed entry"):
        stability(problem, sol._replace(x=jnp.asarray(moved)))


def test_nan_and_bad_multipliers_raise():
    problem, sol = regular_polygon(32)
    bad = np.asarray(sol.x).copy()
    bad[2, 1] = np.nan
    with pytest.raises(NonFiniteError):
        stability(problem, sol._replace(x=jnp.asarray(bad)))
    with pytest.raises(ShapeError):
        stability(problem, sol._replace(multipliers={"unit": jnp.zeros(32)}))
    lam = dict(sol.multipliers)
    lam["unit"] = lam["unit"].at[0].set(np.nan)
    with pytest.raises(NonFiniteError):
        stability(problem, sol._replace(multipliers=lam))


def test_wrong_multipliers_change_the_answer():
    """Negative control of the sign convention: with −λ (the reference's S + λF convention) the
    point is no critical point of L and the call refuses; the Hessian of E alone (λ = 0) is not
    the reduced Hessian either (its eigenvalues differ on the sphere)."""
    problem = sphere_quadratic(np.eye(4)[0])
    sol = solve(problem)
    with pytest.raises(InvalidInputError, match="not a critical point"):
        stability(problem, sol._replace(multipliers=-sol.multipliers))
    right = stability(problem, sol).eigenvalues
    assert np.min(np.abs(right - np.sort(A[1:]))) > 0.5  # not diag(a) on the tangent space
