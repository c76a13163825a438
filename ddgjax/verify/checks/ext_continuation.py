"""Branches of solutions: the catenoid's fold (Sec 6.4; pseudo-arclength continuation, Keller 1977).

`solvers.continuation` follows a branch of critical points through its folds.  Objects: the
scalar fold `E(x) = x³/3 + (p − 1)x` (critical points x² = 1 − p: a fold at p = 1, x = 0, the
branch x > 0 stable, x < 0 unstable), and the simplicial catenoid (Thm 6.7) spanned by the unit
circles at z = ±H, followed in the half-distance H.  The smooth catenoid r = c·cosh(z/c) exists
while c·cosh(H/c) = 1 has a root: up to H* = t*/cosh t* ≈ 0.6627 (t* tanh t* = 1, 2H* ≈ 1.3255),
where the stable catenoid (larger neck) and the unstable one (smaller neck) meet; beyond the
fold the branch continues onto the unstable catenoid, whose neck keeps shrinking, with Morse index
1 (Sec 3.1's second-order condition, `solvers.stability`).

Euler buckling: the clamped elastica (Def 3.2, vertex clamps T = e1 at both ends, length 1)
followed in its chord c·e1.  Every chord c < 1 forces the curve to bend (`clamped` refuses
|c| ≥ L), so the straight rod is reached only as the limit c → 1 of the buckled branch, where
the branch turns back (a fold in c: the pitchfork of the buckled shape and its mirror image,
meeting at the straight rod) and the chord multiplier (the load of Thm 3.2's `T'' = cT + a`)
is the critical load: 4π² for the smooth column of bending energy ½∫κ² clamped at both ends.

Euler's column: the same rod with the load prescribed instead of the chord
(`energies.elastica.loaded`), followed in the load.  The straight column is critical for every
load; at the discrete Euler load an eigenvalue of its second variation crosses zero without a
fold, a bifurcation (`solvers.continuation`'s `Branch.bifurcations`), from which the buckled
branch of the chord-controlled problem leaves.  The twisted column (`energies.rod.loaded`,
Greenhill 1883, Zajac 1962): the straight rod followed in the twist ψ of its end frame; it
bifurcates into a helix where the twisting moment reaches M L = 2ξ, tan ξ = ξ.
"""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

import ddgjax as dg
from ddgjax.verify import check
from energies import area, elastica, rod
from solvers import continuation

H_START = 0.45  # the branch starts on the stable catenoid at this half-distance


def fold_half_distance() -> float:
    """H* = t*/cosh t*, t* tanh t* = 1: the largest H with a catenoid between the circles."""
    t = brentq(lambda t: t * np.tanh(t) - 1.0, 0.5, 2.0)
    return t / np.cosh(t)


def catenoid_family(n: int):
    """`(problem_of, x0)`: `area.between_circles(n)` at the half-distance H (its parameter, so
    every H shares one declaration); x0 the stable smooth catenoid at `H_START` on that mesh."""
    family = area.between_circles(n, H_START)
    V = np.asarray(family.x0)

    def problem_of(H):
        return family.with_params({"height": H})

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
       "and the branch returns to p = 0 at x = −1 with index 1; the fold explains the index change, so no "
       "bifurcation is reported (the negative control of the bifurcation checks below)",
       quantity="|p_fold − 1| + |x_fold| + |x_end + 1| + |index_end − 1| + #bifurcations", at_most=1e-9,
       quick=dict(ds=0.05))
def scalar_fold(ctx, ds):
    branch = continuation(scalar_problem_of, 0.0, 2.0, ds=ds)
    if len(branch.folds) != 1:
        return float("inf")
    fold = branch.folds[0]
    end = branch.x[-1, 0]
    return (abs(fold.p - 1.0) + abs(float(fold.x[0])) + abs(end + 1.0) + abs(branch.index[-1] - 1)
            + len(branch.bifurcations))


# --- Euler buckling: the clamped elastica followed in its chord ---------------------------------

E1 = np.array([1.0, 0.0, 0.0])
CHORD_START = 0.9  # the branch starts on the buckled elastica with chord 0.9·e1 (length L = 1)
CHORD_BEYOND = 1.5  # a target beyond the longest chord |c| < L: the branch must turn back at c = L
EULER_LOAD = 4.0 * np.pi**2  # clamped–clamped, bending energy ½∫κ² (B = 1), L = 1
PINNED_LOAD = np.pi**2  # the pinned–pinned column's: the wrong constant here


def discrete_euler_load(n: int, length: float = 1.0) -> float:
    """λ_h = (2 sin(πh)/h)², h = L/n: the load at which the straight discrete elastica with
    vertex clamps buckles.

    Linearised about T_k = e1, with T_k = (cos θ_k, sin θ_k, 0): the energy `(2/h) Σ E_k` is
    `(1/2h) θᵀQθ`, Q the Dirichlet Laplacian on the edge midpoints s_k = (k + ½)h (the ghost
    edges of the vertex clamps give θ_{−1} = −θ_0, θ_n = −θ_{n−1}); the chord's e1 component
    contributes `−(λh/2) |θ|²` to the Lagrangian and its transverse component requires Σ θ_k = 0.
    The mode θ_k = sin(2πs_k) meets that constraint and has Qθ = 4 sin²(πh) θ, so the second
    variation degenerates on it at λ h = 4 sin²(πh)/h (the lowest such load, as for the smooth
    column, whose next constrained mode needs 8.18π²): λ_h = 4π²(1 − (πh)²/3 + O(h⁴)) → 4π²/L²,
    Euler's critical load of the clamped–clamped column of bending stiffness 1.  (λ_h differs
    from the two-term expansion by 3.6e-3 relative at n = 6, by O(h⁴) in general.)"""
    h = length / n
    return float((2.0 * np.sin(np.pi * h) / h) ** 2)


def euler_load(chord: float, length: float = 1.0) -> float:
    """The load a = (4K(m)/L)² of the clamped–clamped Euler elastica with T(0) = T(L) = e1 and
    chord `chord`·e1 (Thm 3.2; the inflectional elastica over one period of its curvature, whose
    chord over length is 2E(m)/K(m) − 1; `ddgjax.smooth.elastica`): (4K(m)/L)² → 4π²/L² as the
    chord tends to L (m → 0)."""
    m = brentq(lambda m: 2.0 * ellipe(m) / ellipk(m) - 1.0 - chord / length, 1e-14, 1.0 - 1e-12, xtol=1e-15)
    return float((4.0 * ellipk(m) / length) ** 2)


def buckling_family(n: int):
    """`problem_of(c)`: `energies.elastica.clamped(n, chord=(c, 0, 0), t_start=e1, t_end=e1,
    clamp="vertex")` for every c, one declaration (the chord enters through `params`)."""
    base = elastica.clamped(n, chord=(CHORD_START, 0.0, 0.0), t_start=E1, t_end=E1, clamp="vertex")
    return lambda c: base.with_params({**base.params, "chord": jnp.asarray(c) * jnp.asarray(E1)})


@functools.cache
def buckling_branch(n: int):
    """The buckled clamped elastica followed from c = 0.9 towards c = 1.5: it straightens at a
    fold at c = L = 1 and returns to c = 0.9 on its mirror image."""
    return continuation(buckling_family(n), CHORD_START, CHORD_BEYOND, max_points=40, index=False)


def mirror_defect(n: int) -> float:
    """max_k |T_k(end) − R T_k(start)|, R = diag(1, −1, −1) the half-turn about e1: the branch
    returns to c = 0.9 on the mirror image (in its plane) of the elastica it started from."""
    branch = buckling_branch(n)
    return float(np.max(np.abs(np.asarray(branch.x[-1]) - np.asarray(branch.x[0]) * np.array([1.0, -1.0, -1.0]))))


def fold_load(n: int) -> tuple[float, float]:
    """`(c_fold, λ_fold)`: the chord and the chord multiplier's e1 component at the branch's fold
    (inf, inf unless the branch turns back once).

    At the fold the rod is straight (to ~1e-7), where the constraints' gradients are dependent
    (the chord's e1 row is a combination of the unit rows): the KKT conditions hold for every
    load there, and λ_fold is fixed only by the branch through it, to ~1e-5 relative."""
    branch = buckling_branch(n)
    if len(branch.folds) != 1 or branch.stopped != "returned to p0":
        return float("inf"), float("inf")
    fold = branch.folds[0]
    return fold.p, float(elastica.load(fold)[0])


@check("Thm 3.2, Def 3.2", "the clamped discrete elastica (vertex clamps T = e1 at both ends) followed in its chord "
       "c·e1 from c = 0.9 straightens at a fold at c = L = 1 and returns to c = 0.9 on the mirror image of its start; "
       "the chord multiplier there is the discrete Euler load λ_h = (2 sin(πh)/h)² (the straight rod's second "
       "variation degenerates on θ_k = sin(2π(k + ½)h)), λ_h → 4π²",
       quantity="|c_fold − 1| + |λ_fold/λ_h − 1| + max_k |T_k(end) − R_π T_k(start)|", at_most=1e-3,
       quick=dict(n=8), full=dict(n=32))
def elastica_buckling_fold(ctx, n):
    c, load = fold_load(n)
    return abs(c - 1.0) + abs(load / discrete_euler_load(n) - 1.0) + mirror_defect(n)


@check("Thm 3.2, Def 3.2", "negative control: the load at the fold is not the pinned–pinned column's π² but four "
       "times it (|λ_fold/π² − 1| tends to 3)", quantity="|λ_fold/π² − 1|", at_least=2.5,
       quick=dict(n=8), full=dict(n=32))
def elastica_buckling_not_pinned(ctx, n):
    return abs(fold_load(n)[1] / PINNED_LOAD - 1.0)


@check("Thm 3.2, Def 3.2", "the buckling load converges to Euler's critical load 4π² of the clamped–clamped column "
       "(bending energy ½∫κ², L = 1) at second order (n = 8, 12, 16, 24)",
       quantity="fitted order of |λ_fold(n) − 4π²|", target=2.0, within=0.2, quick=dict(ns=(8, 12, 16, 24)),
       full_only=True)
def elastica_buckling_load_order(ctx, ns):
    table = ctx.convergence(dg.limits.convergence(lambda n: abs(fold_load(n)[1] - EULER_LOAD), list(ns)),
                            "elastica_buckling_load_order", title="Euler buckling: |λ_fold − 4π²| against n")
    return float(table.fitted_order)


def branch_load_error(n: int, chord_max: float = 0.99) -> float:
    """max |λ(c) − a(c)| / a(c) over the points of the buckling branch with c ≤ `chord_max`:
    the discrete load against the smooth Euler elastica's (`euler_load`)."""
    branch = buckling_branch(n)
    loads = np.asarray(branch.multipliers["chord"])[:, 0]
    keep = branch.p <= chord_max
    return float(max(abs(load / euler_load(c) - 1.0) for c, load in zip(branch.p[keep], loads[keep])))


@check("Thm 3.2, Def 3.2", "along the buckled branch (0.9 ≤ c ≤ 0.99) the discrete load converges to the load "
       "(4K(m))² of the smooth clamped–clamped Euler elastica with the same chord, 2E(m)/K(m) − 1 = c, at second "
       "order (n = 8, 12, 16, 24)", quantity="fitted order of max_c |λ(c)/a(c) − 1|", target=2.0, within=0.2,
       quick=dict(ns=(8, 12, 16, 24)), full_only=True)
def elastica_buckled_load_order(ctx, ns):
    table = ctx.convergence(dg.limits.convergence(branch_load_error, list(ns)), "elastica_buckled_load_order",
                            title="buckled elastica: max |λ(c)/a(c) − 1| against n")
    return float(table.fitted_order)


# --- Euler's column: the straight elastica followed in its end load ------------------------------

LOAD_START, LOAD_END = 30.0, 45.0  # below the first discrete Euler load at n ≥ 8 (37.49), beyond 4π²


@functools.cache
def column_branch(n: int):
    """`energies.elastica.loaded(n)` (vertex clamps along e1, length 1) followed in its load from
    P = 30 to 45: the straight column throughout."""
    base = elastica.loaded(n)
    return continuation(lambda P: base.with_params({**base.params, "load": P}), LOAD_START, LOAD_END, ds=3.0)


def column_bifurcation_load(n: int) -> float:
    """The load of the one refined bifurcation of `column_branch(n)` (inf if there is not exactly one)."""
    branch = column_branch(n)
    if len(branch.bifurcations) != 1 or not branch.bifurcations[0].refined:
        return float("inf")
    return branch.bifurcations[0].p


def buckling_mode_defect(n: int) -> float:
    """1 − |cos| of the angle between the bifurcation's mode and the buckling mode: the mode's
    components across the load, θ_k ∈ R² (any plane through e1 buckles alike), against
    sin(2π(k + ½)h) v, v their best direction (the mode's rank-one fit)."""
    bif = column_branch(n).bifurcations[0]
    theta = np.asarray(bif.mode)[:, 1:]  # across e1: the e2 and e3 components
    s = np.sin(2.0 * np.pi * (np.arange(n) + 0.5) / n)
    fit = np.linalg.norm(s @ theta) / (np.linalg.norm(s) * np.linalg.norm(theta))
    return float(1.0 - fit)


@check("Euler 1744; Thm 3.2, Def 3.2", "Euler's column: the straight discrete elastica (vertex clamps along e1, "
       "L = 1) under an end load P, followed in P, stays critical and loses stability without a fold, in a "
       "bifurcation (`Branch.bifurcations`) at the discrete Euler load λ_h = (2 sin(πh)/h)², with the Morse index "
       "jumping 0 → 2 (both buckling planes) and the critical mode θ_k ∝ sin(2π(k + ½)h)",
       quantity="|P_bif/λ_h − 1| + |index jump − 2| + #folds + (1 − |cos(mode, sin mode)|)", at_most=1e-8,
       quick=dict(n=16), full=dict(n=64))
def euler_column_bifurcation(ctx, n):
    branch = column_branch(n)
    if len(branch.bifurcations) != 1:
        return float("inf")
    bif = branch.bifurcations[0]
    return (abs(column_bifurcation_load(n) / discrete_euler_load(n) - 1.0) + abs(bif.after_index - bif.before - 2)
            + len(branch.folds) + buckling_mode_defect(n))


@check("Euler 1744; Thm 3.2, Def 3.2", "the column's bifurcation load converges to Euler's critical load 4π² of "
       "the clamped–clamped column (bending energy ½∫κ², L = 1) at second order",
       quantity="fitted order of |P_bif(n) − 4π²|", target=2.0, within=0.1, quick=dict(ns=(8, 16, 32)),
       full=dict(ns=(8, 16, 32, 64, 128)))
def euler_column_load_order(ctx, ns):
    table = ctx.convergence(dg.limits.convergence(lambda n: abs(column_bifurcation_load(n) - EULER_LOAD), list(ns)),
                            "euler_column_load_order", title="Euler's column: |P_bif − 4π²| against n")
    return float(table.fitted_order)


@check("Euler 1744; Thm 3.2, Def 3.2", "negative control: the column's bifurcation load is not the pinned–pinned "
       "column's π² but four times it", quantity="|P_bif/π² − 1|", at_least=2.5, quick=dict(n=16), full=dict(n=64))
def euler_column_not_pinned(ctx, n):
    return abs(column_bifurcation_load(n) / PINNED_LOAD - 1.0)


# --- the twisted column: the straight rod followed in its end twist -------------------------------

TWIST_START, TWIST_END = 7.0, 11.0  # below the critical twist at n ≥ 8 (9.94), beyond Zajac's 8.99 (α = 1)


def zajac_twist() -> float:
    """ψ* = 2ξ (α = 1, L = 1), ξ the first positive root of tan ξ = ξ: the critical twist of the
    clamped rod without load, M L = 2ξ ≈ 8.9868 (Zajac 1962; `energies.rod.loaded`)."""
    return 2.0 * brentq(lambda x: np.tan(x) - x, 4.0, 4.6)


@functools.cache
def twisted_branch(n: int):
    """`energies.rod.loaded(n, alpha=1)` (vertex clamps) followed in its end twist ψ from 7 to 11."""
    base = rod.loaded(n, alpha=1.0, twist=TWIST_START)
    return continuation(lambda psi: base.with_params({**base.params, "frame_end": rod.twisted_frame(psi)}),
                        TWIST_START, TWIST_END, ds=2.0)


def critical_twist(n: int) -> float:
    """The twist of the one refined bifurcation of `twisted_branch(n)` with index jump 2, no fold
    (inf otherwise)."""
    branch = twisted_branch(n)
    if len(branch.bifurcations) != 1 or branch.folds or not branch.bifurcations[0].refined:
        return float("inf")
    bif = branch.bifurcations[0]
    return bif.p if (bif.before, bif.after_index) == (0, 2) else float("inf")


@check("Zajac 1962; Thm 3.13, Def 3.7", "the twisted column: the straight discrete rod (α = 1, vertex clamps, "
       "L = 1, no load) followed in its end twist ψ stays critical and loses stability without a fold, in a "
       "bifurcation (index 0 → 2) at Zajac's critical twist ψ* = 2ξ ≈ 8.9868 (tan ξ = ξ) up to O(h²): the relative "
       "error times n² is about 6.8 at n = 8 and 6.1 at n = 32", quantity="n² |ψ_bif/ψ* − 1|", at_most=8.0,
       quick=dict(n=8), full=dict(n=32))
def twisted_column_bifurcation(ctx, n):
    return n * n * abs(critical_twist(n) / zajac_twist() - 1.0)


@check("Zajac 1962; Thm 3.13, Def 3.7", "the twisted column's critical twist converges to Zajac's ψ* = 2ξ at second "
       "order", quantity="fitted order of |ψ_bif(n) − ψ*|", target=2.0, within=0.2, quick=dict(ns=(8, 16, 32)),
       full_only=True)
def twisted_column_twist_order(ctx, ns):
    table = ctx.convergence(dg.limits.convergence(lambda n: abs(critical_twist(n) - zajac_twist()), list(ns)),
                            "twisted_column_twist_order", title="twisted column: |ψ_bif − ψ*| against n")
    return float(table.fitted_order)


@check("Zajac 1962; Thm 3.13, Def 3.7", "negative control: the clamped column's critical twist is not Greenhill's "
       "pinned–pinned M L = 2π", quantity="|ψ_bif/2π − 1|", at_least=0.3, quick=dict(n=8), full=dict(n=32))
def twisted_column_not_pinned(ctx, n):
    return abs(critical_twist(n) / (2.0 * np.pi) - 1.0)
