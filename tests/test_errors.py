"""Bad input gets a clear DDGError naming the offending leaf/index; inputs are never mutated."""

import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import (
    ConvergenceError, DDGError, NonFiniteError, NotScalarError, OverconstrainedError, ShapeError,
)
from solvers import solve


def test_nan_in_x0_names_leaf_and_index():
    x0 = {"T": np.zeros((4, 3)), "s": np.ones(2)}
    x0["T"][2, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"x0\['T'\] has the non-finite value nan at index \(2, 1\)"):
        dg.Problem(lambda x, _: jnp.sum(x["T"] ** 2), x0)


def test_non_scalar_energy():
    with pytest.raises(NotScalarError, match=r"scalar, got shape \(3,\)"):
        dg.Problem(lambda x, _: x**2, np.ones(3))


def test_overconstrained_problem():
    with pytest.raises(OverconstrainedError, match="4 constraints but only 3 free unknowns"):
        dg.Problem(lambda x, _: jnp.sum(x), np.ones(3), constraints=lambda x, _: jnp.concatenate([x, x[:1]]))
    fixed = np.array([True, True, False])
    with pytest.raises(OverconstrainedError, match="2 constraints but only 1 free"):
        dg.Problem(lambda x, _: jnp.sum(x), np.ones(3), constraints=lambda x, _: x[:2] - 1, fixed=fixed)


def test_fixed_mask_shape_and_dtype():
    with pytest.raises(ShapeError, match=r"fixed has shape \(2,\), expected \(3,\)"):
        dg.Problem(lambda x, _: jnp.sum(x), np.ones(3), fixed=np.array([True, False]))
    with pytest.raises(ShapeError, match="bool"):
        dg.Problem(lambda x, _: jnp.sum(x), np.ones(3), fixed=np.array([1, 0, 0]))


def test_constraints_must_be_one_dimensional():
    with pytest.raises(ShapeError, match=r"1-D array, got shape \(2, 2\)"):
        dg.Problem(lambda x, _: jnp.sum(x), np.ones(4), constraints=lambda x, _: x.reshape(2, 2))


def test_nan_in_params():
    with pytest.raises(NonFiniteError, match=r"params\['a'\].*index \(1,\)"):
        dg.Problem(lambda x, p: jnp.sum(x * p["a"]), np.ones(2), params={"a": np.array([1.0, np.inf])})


def test_unsolvable_problem_raises_convergence_error_with_residual():
    """|x|² + 1 = 0 has no real solution: the solver must stop and say so, never return NaN."""
    problem = dg.Problem(lambda x, _: jnp.sum(x**2), np.ones(2), constraints=lambda x, _: jnp.array([x @ x + 1.0]))
    with pytest.raises(ConvergenceError) as info:
        solve(problem, max_steps=60)
    assert np.isfinite(info.value.residual) and info.value.residual >= 0.99  # |g| >= 1 everywhere
    sol = solve(problem, max_steps=60, throw=False)
    assert not bool(sol.converged) and np.all(np.isfinite(np.asarray(sol.x)))


def test_linear_energy_has_no_critical_point():
    with pytest.raises(ConvergenceError, match="did not converge"):
        solve(dg.Problem(lambda x, _: jnp.sum(x), np.ones(3)), max_steps=30)


def test_energy_nan_at_start():
    problem = dg.Problem(lambda x, _: jnp.sum(jnp.log(x)), np.array([1.0, -1.0]))
    with pytest.raises(NonFiniteError, match="not finite at x0"):
        solve(problem)


def test_inputs_are_not_mutated():
    x0 = np.array([[1.0, 0.2, 0.1], [0.3, 1.0, 0.0]])
    fixed = np.array([[True, False, False], [False, False, False]])
    params = np.array([0.5, -0.2, 0.1])
    copies = [a.copy() for a in (x0, fixed, params)]
    problem = dg.Problem(
        lambda X, f: jnp.sum((X - f) ** 2), x0, fixed=fixed, params=params,
        constraints=lambda X, f: jnp.array([X[1] @ X[1] - 1.0]),
    )
    x0[0, 0] = 99.0  # the problem kept its own copy
    sol = solve(problem)
    x0[0, 0] = 1.0
    for a, b in zip((x0, fixed, params), copies):
        assert np.array_equal(a, b)
    assert float(sol.x[0, 0]) == 1.0


def test_bad_options():
    problem = dg.Problem(lambda x, _: jnp.sum(x**2), np.ones(2))
    for kwargs in ({"method": "newton"}, {"tol": 0.0}, {"warm_start": "bfgs"}, {"max_steps": -1}):
        with pytest.raises(DDGError):
            solve(problem, **kwargs)
    with pytest.raises(ShapeError, match=r"multipliers must have shape \(0,\)"):
        solve(problem, multipliers0=np.ones(2))


def test_sparse_requires_locality():
    with pytest.raises(DDGError, match="local_sum"):
        solve(dg.Problem(lambda x, _: jnp.sum(x**2), np.ones(2)), method="sparse")


def test_with_params_and_with_x0_check_what_they_replace():
    """`with_params` / `with_x0` keep the declaration's checks: non-finite values are named, a
    copy of x0 is taken, and parameters of new shapes are checked against the energy (its
    output shape is traced anew); with unchanged trees, shapes and dtypes nothing is traced."""
    calls = []

    def energy(x, p):
        calls.append(1)
        return p["a"] * jnp.sum(x**2)

    problem = dg.Problem(energy, np.ones(3), params={"a": 2.0}, constraints=lambda x, p: x[:1] - p["a"])
    traced = len(calls)
    moved = problem.with_params({"a": 3.0})
    assert len(calls) == traced and moved.params == {"a": 3.0} and problem.params == {"a": 2.0}
    assert moved.constraint_structure == problem.constraint_structure and moved.n_constraints == 1
    with pytest.raises(NonFiniteError, match=r"params\['a'\]"):
        problem.with_params({"a": float("nan")})
    with pytest.raises(NotScalarError):
        problem.with_params({"a": np.ones(2)})  # a new shape is traced again: the energy is (2,)-shaped
    x0 = np.array([1.0, 2.0, 3.0])
    started = problem.with_x0(x0)
    x0[0] = 5.0  # the problem holds a copy
    assert np.asarray(started.x0).tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(NonFiniteError, match=r"x0 has the non-finite value inf at index \(1,\)"):
        problem.with_x0(np.array([0.0, np.inf, 0.0]))
