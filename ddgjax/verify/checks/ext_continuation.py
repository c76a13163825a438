"""Branches of solutions: the catenoid's fold (Sec 6.4; pseudo-arclength continuation, Keller 1977).

`solvers.continuation` follows a branch of critical points through its folds.  Objects: the
scalar fold `E(x) = x³/3 + (p − 1)x` (critical points x² = 1 − p: a fold at p = 1, x = 0, the
branch x > 0 stable, x < 0 unstable), and the simplicial catenoid (Thm 6.7) spanned by the unit
circles at z = ±H, followed in the half-distance H.  The smooth catenoid r = c·cosh(z/c) exists
while c·cosh(H/c) = 1 has a root: up to H* = t*/cosh t* ≈ 0.6627 (t* tanh t* = 1, 2H* ≈ 1.3255),
where the stable catenoid (larger neck) and the unstable one (smaller neck) meet; beyond the
fold the branch continues onto the unstable catenoid, whose neck keeps shrinking, with Morse index
1 (Sec 3.1's second-order condition, `solvers.stability`).
"""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np
from scipy.optimize import brentq

import ddgjax as dg
from ddgjax.verify import check
from energies.area import face_area
from solvers import continuation

H_START = 0.45  # the branch starts on the stable catenoid at this half-distance


def fold_half_distance() -> float:
    """H* = t*/cosh t*, t* tanh t* = 1: the largest H with a catenoid between the circles."""
    t = brentq(lambda t: t * np.tanh(t) - 1.0, 0.5, 2.0)
    return t / np.cosh(t)


def catenoid_family(n: int):
    """`(problem_of, x0)`: the area of `cylinder(n)` with its z-coordinates scaled by the
    parameter, `X = (x, y, H·ζ)`, ζ = ±1 on the fixed circles (H enters through `params`, so
    every H shares one declaration); x0 the stable smooth catenoid at `H_START` on that mesh."""
    V, F = dg.mesh.builtin.cylinder(n, 1.0, 1.0)
    fixed = np.zeros(V.shape, dtype=bool)
    fixed[np.abs(np.abs(V[:, 2]) - 1.0) < 1e-12] = True
    energy = dg.local_sum(lambda P, params: face_area(P * jnp.array([1.0, 1.0, params["H"]])), F)

    def problem_of(H):
        return dg.Problem(energy, V, params={"H": H}, fixed=fixed, name=f"catenoid on cylinder({n})")

    c = brentq(lambda c: c * np.cosh(H_START / c) - 1.0, 0.55, 1.0)  # the stable root
    x0 = V.copy()
    x0[:, :2] *= (c * np.cosh(H_START * V[:, 2] / c) / np.linalg.norm(V[:, :2], axis=1))[:, None]
    return problem_of, x0


@functools.cache
def catenoid_branch(n: int):
    """The branch from H = 0.45 past the fold and back to H = 0.45 on the unstable catenoid."""
    problem_of, x0 = catenoid_family(n)
    return continuation(problem_of, H_START, 0.9, x0=x0, max_points=60)


def neck_radius(branch, n: int) -> np.ndarray:
    """(K,) the mean distance from the axis of the middle circle (z = 0) at every point."""
    V, _ = dg.mesh.builtin.cylinder(n, 1.0, 1.0)
    middle = np.abs(V[:, 2]) < 1e-12
    return np.linalg.norm(branch.x[:, middle, :2], axis=2).mean(axis=1)


@check("Sec 6.4, Thm 6.7", "the branch of simplicial catenoids between the unit circles at z = ±H, followed in H by "
       "pseudo-arclength continuation, turns back at a fold within 1 % of the smooth H* ≈ 0.6627 (2H* ≈ 1.3255)",
       quantity="|H_fold / H* − 1|", at_most=0.01, quick=dict(n=8), full=dict(n=16))
def catenoid_fold(ctx, n):
    branch = catenoid_branch(n)
    if len(branch.folds) != 1 or not branch.folds[0].refined:
        return float("inf")
    return abs(branch.folds[0].p / fold_half_distance() - 1.0)


@check("Sec 3.1, 6.4", "along the catenoid branch the Morse index is 0 before the fold and 1 after it (the "
       "unstable catenoid), changing once, between the two points that bracket the fold",
       quantity="points with the wrong index + |index changes − 1|", target=0.0, within=0.0,
       quick=dict(n=8), full=dict(n=16))
def catenoid_index_across_fold(ctx, n):
    branch = catenoid_branch(n)
    if len(branch.folds) != 1:
        return float("inf")
    k = branch.folds[0].after
    expected = np.where(np.arange(len(branch.p)) <= k, 0, 1)
    changes_at_fold = [change for change in branch.index_changes if change.after == k]
    return float(np.sum(branch.index != expected) + abs(len(branch.index_changes) - 1) + (1 - len(changes_at_fold)))


@check("Sec 6.4", "past the fold the branch continues onto the catenoid with the smaller neck: the neck radius "
       "decreases strictly along the whole branch, and the branch returns to H = 0.45 with a neck below the "
       "stable one's", quantity="steps along the branch where the neck does not shrink", target=0.0, within=0.0,
       quick=dict(n=8), full=dict(n=16))
def catenoid_neck_shrinks(ctx, n):
    branch = catenoid_branch(n)
    neck = neck_radius(branch, n)
    if branch.stopped != "returned to p0" or not neck[-1] < 0.5 * neck[0]:
        return float("inf")
    return float(np.sum(np.diff(neck) >= 0))


@check("Sec 6.4", "the discrete fold converges to the smooth one at second order in the mesh size "
       "(cylinder(n), n = 6, 8, 12, 16)", quantity="fitted order of |H_fold(n) − H*|", target=2.0, within=0.3,
       quick=dict(ns=(6, 8, 12, 16)), full_only=True)
def catenoid_fold_order(ctx, ns):
    errors = lambda n: abs(catenoid_branch(n).folds[0].p - fold_half_distance())
    table = ctx.convergence(dg.limits.convergence(errors, list(ns)), "catenoid_fold_order",
                            title="catenoid fold: |H_fold − H*| against n")
    return float(table.fitted_order)


def scalar_problem_of(p):
    """`E(x) = x³/3 + (p − 1)x` on x ∈ R¹."""
    return dg.Problem(_scalar_energy, jnp.array([1.0]), params={"p": p}, name="scalar fold")


def _scalar_energy(x, params):
    return x[0] ** 3 / 3 + (params["p"] - 1.0) * x[0]


@check("Keller 1977", "the scalar fold x² + p − 1 = 0 (critical points of x³/3 + (p − 1)x) is found at p = 1, x = 0, "
       "and the branch returns to p = 0 at x = −1 with index 1",
       quantity="|p_fold − 1| + |x_fold| + |x_end + 1| + |index_end − 1|", at_most=1e-9, quick=dict(ds=0.05))
def scalar_fold(ctx, ds):
    branch = continuation(scalar_problem_of, 0.0, 2.0, ds=ds)
    if len(branch.folds) != 1:
        return float("inf")
    fold = branch.folds[0]
    end = branch.x[-1, 0]
    return abs(fold.p - 1.0) + abs(float(fold.x[0])) + abs(end + 1.0) + abs(branch.index[-1] - 1)
