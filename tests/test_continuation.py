"""`solvers.continuation`: pseudo-arclength continuation (Keller 1977) through folds.

Closed forms: the scalar fold x² + p − 1 = 0 (critical points of x³/3 + (p − 1)x, Sec 3.1 with no
constraint) and a constrained one, x² + x + p − 1 = 0 (x³/3 + (p − 1)x + y²/2 on y = x, multiplier
λ = y); then the catenoid of Sec 6.4 (`ddgjax/verify/checks/ext_continuation.py`) and negative
controls.  Tolerances: points and folds are solved to the KKT residual 1e-10, so closed-form
values hold to ~1e-9.
"""

import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
import solvers
from ddgjax.errors import ConvergenceError, InvalidInputError
from ddgjax.verify.checks.ext_continuation import (
    catenoid_branch,
    fold_half_distance,
    neck_radius,
    scalar_problem_of,
)


def test_scalar_fold_at_p_1_x_0_stable_branch_turns_unstable():
    branch = solvers.continuation(scalar_problem_of, 0.0, 2.0)
    x = branch.x[:, 0]
    assert np.max(np.abs(x**2 + branch.p - 1.0)) <= 1e-9  # every point on x² = 1 − p
    assert np.all(branch.residual <= 1e-10)
    assert branch.stopped == "returned to p0" and branch.p[-1] == 0.0 and abs(x[-1] + 1.0) <= 1e-9
    (fold,) = branch.folds
    assert fold.refined and abs(fold.p - 1.0) <= 1e-9 and abs(float(fold.x[0])) <= 1e-9
    assert abs(fold.energy) <= 1e-9 and abs(fold.dp_ds) <= 1e-10
    # second-order condition: E'' = 2x, index 0 on x > 0 and 1 on x < 0, one change at the fold
    np.testing.assert_array_equal(branch.index, np.where(x > 0, 0, 1))
    (change,) = branch.index_changes
    assert (change.after, change.before, change.after_index) == (fold.after, 0, 1)
    assert branch.dp_ds[0] > 0 > branch.dp_ds[-1]  # towards p1, then back
    assert np.all(np.diff(branch.s) > 0)


def _tied_energy(v, params):
    x, y = v
    return x**3 / 3 + (params["p"] - 1.0) * x + y**2 / 2


def _tie(v, params):
    return {"tie": jnp.atleast_1d(v[1] - v[0])}


def _tied_problem_of(p):
    return dg.Problem(_tied_energy, jnp.array([0.6, 0.6]), constraints=_tie, params={"p": p}, name="tied fold")


def test_constrained_fold_and_named_multipliers():
    """x³/3 + (p − 1)x + y²/2 on y = x: x² + x + p − 1 = 0, fold at x = −½, p = 5/4; λ = y."""
    branch = solvers.continuation(_tied_problem_of, 0.0, 2.0)
    x, y, lam = branch.x[:, 0], branch.x[:, 1], branch.multipliers["tie"][:, 0]
    assert branch.multipliers["tie"].shape == (len(branch.p), 1)
    assert np.max(np.abs(x**2 + x + branch.p - 1.0)) <= 1e-9
    assert np.max(np.abs(y - x)) <= 1e-10 and np.max(np.abs(lam - y)) <= 1e-9
    (fold,) = branch.folds
    assert abs(fold.p - 1.25) <= 1e-9 and abs(float(fold.x[0]) + 0.5) <= 1e-9
    assert abs(float(fold.multipliers["tie"][0]) + 0.5) <= 1e-9
    np.testing.assert_array_equal(branch.index, np.where(2 * x + 1 > 0, 0, 1))  # reduced Hessian 2x + 1


def test_monotone_branch_reaches_p1_exactly_without_folds():
    """Negative control for the fold detection: E = x²/2 − p x, x = p, no fold, index 0."""
    problem_of = lambda p: dg.Problem(_quadratic, jnp.zeros(1), params={"p": p})
    branch = solvers.continuation(problem_of, 0.0, 1.0, ds=0.3)
    assert branch.stopped == "reached p1" and branch.p[-1] == 1.0
    assert np.max(np.abs(branch.x[:, 0] - branch.p)) <= 1e-10
    assert branch.folds == () and branch.index_changes == () and np.all(branch.index == 0)


def _pitchfork(x, params):
    return 0.25 * x[0] ** 4 + 0.5 * (1.0 - params["p"]) * x[0] ** 2


def test_pitchfork_is_a_bifurcation_refined_to_the_zero_eigenvalue():
    """E = x⁴/4 + (1 − p) x²/2: x = 0 is critical for every p with Hessian 1 − p, so the
    index changes 0 → 1 at p = 1 while the branch goes on (dp/ds > 0 throughout): one
    bifurcation, at p = 1, eigenvalue 0, mode ±e₁ (where x = ±√(p − 1) leaves); no fold."""
    problem_of = lambda p: dg.Problem(_pitchfork, jnp.zeros(1), params={"p": p})
    branch = solvers.continuation(problem_of, 0.3, 1.8, ds=0.25)
    assert branch.stopped == "reached p1" and branch.folds == () and np.all(branch.dp_ds > 0)
    (change,) = branch.index_changes
    (bif,) = branch.bifurcations
    assert (bif.before, bif.after_index, bif.after) == (0, 1, change.after) and bif.refined
    assert abs(bif.p - 1.0) <= 1e-9 and abs(bif.eigenvalue) <= 1e-9
    assert abs(abs(float(bif.mode[0])) - 1.0) <= 1e-12 and abs(float(bif.x[0])) <= 1e-12


def test_a_fold_is_not_a_bifurcation():
    """Negative control: at the fold of E = x³/3 + (p − 1)x the index changes too, but the fold
    explains it: no bifurcation is reported."""
    problem_of = lambda p: dg.Problem(_numpy_energy, jnp.array([1.0]), params=jnp.array([p]))
    branch = solvers.continuation(problem_of, 0.0, 2.0)
    assert len(branch.folds) == 1 and len(branch.index_changes) == 1 and branch.bifurcations == ()


def _quadratic(x, params):
    return 0.5 * x[0] ** 2 - params["p"] * x[0]


def test_parameter_through_numpy_uses_differences_and_agrees():
    """`problem_of` that does not trace (NumPy on p): F_p by central differences, same fold."""
    problem_of = lambda p: dg.Problem(_numpy_energy, jnp.array([1.0]), params=np.array([float(p)]))
    branch = solvers.continuation(problem_of, 0.0, 2.0, index=False)
    (fold,) = branch.folds
    assert abs(fold.p - 1.0) <= 1e-9 and abs(float(fold.x[0])) <= 1e-9
    assert np.all(branch.index == -1)


def _numpy_energy(x, params):
    return x[0] ** 3 / 3 + (params[0] - 1.0) * x[0]


def test_catenoid_fold_within_one_percent_and_turns_onto_the_unstable_catenoid():
    """Sec 6.4: cylinder(8), the fold H ≈ 0.6596 against the smooth H* = 0.66274 (−0.48 %, O(h²))."""
    branch = catenoid_branch(8)
    (fold,) = branch.folds
    assert fold.refined and abs(fold.p / fold_half_distance() - 1.0) <= 0.01
    assert np.all(branch.p <= fold.p + 1e-12)  # the fold is the largest H on the branch
    neck = neck_radius(branch, 8)
    assert np.all(np.diff(neck) < 0)  # the neck keeps shrinking through the fold
    np.testing.assert_array_equal(branch.index, np.where(np.arange(len(branch.p)) <= fold.after, 0, 1))
    assert branch.stopped == "returned to p0" and branch.p[-1] == branch.p[0] and neck[-1] < 0.5 * neck[0]


def test_problem_of_must_keep_its_declaration():
    """p inside a new energy closure at every p: another declaration, refused (it would recompile
    at every point, and p would not be seen by the parameter derivative)."""
    problem_of = lambda p: dg.Problem(lambda x, params: x[0] ** 3 / 3 + (p - 1.0) * x[0], jnp.array([1.0]))
    with pytest.raises(InvalidInputError, match="declaration"):
        solvers.continuation(problem_of, 0.0, 2.0)


@pytest.mark.parametrize("kwargs, match", [
    (dict(p1=0.0), "differ"),
    (dict(p1=float("nan")), "finite"),
    (dict(ds=-1.0), "ds"),
    (dict(max_points=0), "max_points"),
])
def test_bad_options_raise(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        solvers.continuation(scalar_problem_of, 0.0, **{"p1": 2.0, **kwargs})


def test_no_critical_point_at_p0_raises():
    """x² = 1 − p has no real root at p = 2."""
    with pytest.raises(ConvergenceError):
        solvers.continuation(scalar_problem_of, 2.0, 3.0)


def test_max_points_stops_early():
    branch = solvers.continuation(scalar_problem_of, 0.0, 2.0, max_points=3, index=False)
    assert branch.stopped == "max_points" and len(branch.p) == 3 and branch.folds == ()


def _anchored_energy(v, params):
    a, x = v
    return x**3 / 3 + (a - 1.0) * x


@pytest.mark.parametrize("traced", [True, False])
def test_parameter_in_a_fixed_entry_of_x0(traced):
    """p as the fixed first entry of x0 (a boundary value), traced by jax or differenced."""
    def problem_of(p):
        a = p if traced else np.float64(p)  # np.float64(tracer) fails: differences
        return dg.Problem(_anchored_energy, jnp.stack([jnp.asarray(a, float), jnp.asarray(1.0)]),
                          fixed=np.array([True, False]))

    branch = solvers.continuation(problem_of, 0.0, 2.0, index=False)
    (fold,) = branch.folds
    assert abs(fold.p - 1.0) <= 1e-9 and abs(float(fold.x[1])) <= 1e-9
    assert np.array_equal(branch.x[:, 0], branch.p)  # the fixed entry is problem_of(p)'s, bit for bit


def test_one_compiled_system_per_declaration():
    """p enters through params: a second branch of the same declaration compiles nothing new."""
    from solvers import _continuation

    solvers.continuation(scalar_problem_of, 0.0, 2.0, index=False)
    compiled = _continuation._system._cache_size()
    solvers.continuation(scalar_problem_of, 0.2, 0.8, index=False)
    assert _continuation._system._cache_size() == compiled


def _ending_energy(x, params):
    return 0.5 * x[0] ** 2 - params["p"] * x[0] + 0.0 * jnp.log(1.5 - params["p"])  # NaN for p ≥ 1.5


def test_branch_that_ends_stops_with_step_too_small():
    """Negative control: no critical point (a NaN energy) beyond p = 1.5: the step length shrinks
    to ds_min and the branch stops there, every point kept still a critical point."""
    problem_of = lambda p: dg.Problem(_ending_energy, jnp.zeros(1), params={"p": p})
    branch = solvers.continuation(problem_of, 0.0, 2.0, ds_min=1e-3, index=False)
    assert branch.stopped.startswith("step too small") and 1.4 < branch.p[-1] < 1.5
    assert np.max(np.abs(branch.x[:, 0] - branch.p)) <= 1e-10 and np.all(np.isfinite(branch.energy))
