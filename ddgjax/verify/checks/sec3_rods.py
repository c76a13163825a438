"""Discrete elastic rods (Sec 3.5, 3.6: Def 3.6, 3.7, Lemma 3.12, Thm 3.11, 3.13, Cor 3.14, Remark 3.16)."""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import frames
from ddgjax import quaternion as qt
from ddgjax.verify import check
from energies import rod
from solvers import solve

from ._shared import euclidean_motion_fit, max_abs, planar_elastica

GROUP = "clamped elastica"  # share the solved elastica of _shared (one compilation per size)

E1, E2, E3 = np.eye(3)
START_ANGLE, END_ANGLE = np.pi / 2, -np.pi / 2  # the end frames' turns about e3: tangent e1 -> e2, e1 -> -e2
CHORD, ALPHA, TWIST = 0.6, 0.7, 2.5


def clamped_problem(n: int, twist: float, **options):
    """The rod from tangent e2 to −e2 with chord (0.6, 0, 0), the end frame twisted by `twist`
    (`options` go to `rod.clamped`)."""
    end = qt.mul(qt.from_axis_angle(-E2, twist), qt.from_axis_angle(E3, END_ANGLE))
    return rod.clamped(n, **{"alpha": ALPHA, **options}, chord=[CHORD, 0, 0], frame_start=qt.from_axis_angle(E3, START_ANGLE),
                       frame_end=end)


@functools.cache
def clamped_rod(n: int, twist: float):
    """`(problem, solution)` of `clamped_problem(n, twist)`."""
    problem = clamped_problem(n, twist)
    return problem, solve(problem)


@check("Lemma 3.12 (discrete)", "the twist angles θ_k of a critical twisted rod are all equal (τ' = 0)",
       quantity="max_k |θ_k − θ_1| (twist 2.5)", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def rod_twist_is_constant(ctx, n):
    _, sol = clamped_rod(n, TWIST)
    theta = np.asarray(rod.twist_angles(sol.x))
    gamma = np.asarray(dg.curves.from_tangents(rod.tangents(sol.x), edge_length=1.0 / n))
    dg.plot.curve(gamma, path=ctx.figure("twisted_rod.png"))
    return float(np.max(np.abs(theta - theta[0]))) if abs(theta[0]) > 1e-3 else float("inf")


@check("Def 3.6", "an untwisted planar rod is the discrete elastica with the same ends",
       quantity="max_k |T_k(rod) − T_k(elastica)|", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def untwisted_rod_is_elastica(ctx, n):
    _, sol = clamped_rod(n, 0.0)
    _, curve = planar_elastica(n, CHORD)
    return max_abs(rod.tangents(sol.x), curve.x)


# --- Def 3.7 and Cor 3.14: Heisenberg flow + c · tangent flow ---------------------------------


def combined_flow_fit(Phi, h: float, c: float | None = None) -> tuple[float, float]:
    """`(residual / max_k |w_k|, c)` of the least-squares fit `w_k + c v_k = a × γ_k + b` at the
    interior vertices of the centreline of the edge frames Φ (edge length h), with w the discrete
    Heisenberg flow and v the discrete tangent flow (Def 3.7); c is fitted unless given."""
    gamma = np.asarray(dg.curves.from_tangents(rod.tangents(Phi), edge_length=h))
    w = np.asarray(dg.curves.heisenberg_flow(gamma, closed=False))[1:-1]
    v = np.asarray(dg.curves.tangent_flow(gamma, closed=False))[1:-1]
    if c is None:
        residual, (*_, c) = euclidean_motion_fit(gamma[1:-1], w, extra=v)
    else:
        residual, _ = euclidean_motion_fit(gamma[1:-1], w + c * v)
    return residual / float(np.max(np.abs(w))), float(c)


def discrete_c(problem, sol) -> float:
    """`c = −αθ/2`: Thm 3.13's `c = −ατ` with `τ ≈ θ/h`, scaled as the discrete Heisenberg flow
    `w_k ≈ (h/2) T' × T` is (the tangent flow `v_k ≈ T`), for a rod with constant twist θ."""
    return -float(problem.params["alpha"]) * float(rod.twist_angles(sol.x)[0]) / 2


@check("Def 3.7", "at a twisted rod, Heisenberg flow + c·tangent flow is an infinitesimal Euclidean motion (c ≠ 0)",
       quantity="least-squares residual / max |w|", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def rod_combined_flow_is_euclidean(ctx, n):
    problem, sol = clamped_rod(n, TWIST)
    residual, c = combined_flow_fit(sol.x, problem.params["h"])
    if abs(c) <= 1e-3:
        raise AssertionError(f"c = {c:.2e}: not a genuine combination with the tangent flow")
    return residual


@check("Cor 3.14", "at a twisted rod, Heisenberg flow + c·tangent flow with the non-zero coefficient c = −αθ/2 "
       "(Thm 3.13's c = −ατ, discrete) moves the rod by an infinitesimal Euclidean motion a × γ + b",
       quantity="least-squares residual / max |w| (c fixed)", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def cor_3_14_rod_moves_rigidly(ctx, n):
    problem, sol = clamped_rod(n, TWIST)
    c = discrete_c(problem, sol)
    if abs(c) <= 1e-3:
        raise AssertionError(f"c = {c:.2e}: not a genuine combination with the tangent flow")
    return combined_flow_fit(sol.x, problem.params["h"], c)[0]


@check("Cor 3.14", "negative controls: with the wrong coefficient c = +αθ/2, or on a framed polygon that is not a "
       "rod (Newton's start, any c), the combined flow is no Euclidean motion",
       quantity="min of the two least-squares residuals / max |w|", at_least=1e-3, quick=dict(n=32), full=dict(n=200))
def cor_3_14_negative_controls(ctx, n):
    problem, sol = clamped_rod(n, TWIST)
    h = problem.params["h"]
    return min(combined_flow_fit(sol.x, h, -discrete_c(problem, sol))[0], combined_flow_fit(problem.x0, h)[0])


# --- Remark 3.16: anisotropic rods --------------------------------------------------------------

ANISOTROPIC = (1.0, 3.0)


@functools.cache
def anisotropic_rod(n: int, bending: tuple, alpha: float = ALPHA):
    """`(problem, solution)` of the rod of `clamped_rod(n, TWIST)` with bending stiffnesses
    (b1, b2) (Remark 3.16).  Equal ones start where `clamped_rod` does; unequal ones start from
    the isotropic solution (the anisotropic rod's branch)."""
    x0 = None if bending[0] == bending[1] else clamped_rod(n, TWIST)[1].x
    problem = clamped_problem(n, TWIST, alpha=alpha, bending=bending, x0=x0)
    return problem, solve(problem)


@check("Remark 3.16", "with equal stiffnesses (β, β) the anisotropic rod is the isotropic rod with twist stiffness "
       "α/β: the same frames, loads β·λ (β = 1, 2; Newton from the same start)",
       quantity="max_β (max |Φ − Φ_iso| + max |λ/β − λ_iso|)", at_most=1e-10, quick=dict(n=32),
       full=dict(n=200))
def anisotropic_rod_equal_stiffnesses(ctx, n):
    _, iso = clamped_rod(n, TWIST)

    def distance(beta):
        _, sol = anisotropic_rod(n, (beta, beta), beta * ALPHA)
        return max_abs(sol.x, iso.x) + max_abs(np.asarray(rod.load(sol)) / beta, rod.load(iso))

    return max(distance(1.0), distance(2.0))


def twist_equation_defect(problem, sol, sign: float = 1.0) -> float:
    """`max_k |α(θ_{k+1} − θ_k)/h² − sign (b1 − b2) ½ Σ_j g(t_j) (κ1κ2)_j|`, relative to
    `max_k |α(θ_{k+1} − θ_k)/h²|`: the sum over the two vertices j = k, k + 1 of the edge k,
    `t = h²(κ1² + κ2²)/4`, `g(t) = log(1 + t)/t`.  It vanishes at a critical anisotropic rod:
    turning Φ_k about T_k by ψ changes θ_k, θ_{k+1} by ±ψ and turns the curvature vectors at both
    vertices by ψ/2 in the material frame, where the bending term is `(2/h) w E` with
    `E = t g(t)` and `w = (b1 κ1² + b2 κ2²)/κ²`.  As g → 1 it is the smooth `ατ' = (b1 − b2)κ1κ2`,
    the axial Euler equation of the top with J = diag(α, b2, b1)."""
    p = problem.params
    h, alpha, (b1, b2) = p["h"], float(p["alpha"]), np.asarray(p["bending"])
    k1, k2, tau = (np.asarray(x) for x in frames.discrete_curvatures(sol.x, h))
    t = h * h * (k1**2 + k2**2) / 4
    torque = (b1 - b2) * np.log1p(t) / t * k1 * k2
    lhs = alpha * np.diff(tau) / h
    return float(np.max(np.abs(lhs - sign * (torque[1:] + torque[:-1]) / 2)) / np.max(np.abs(lhs)))


@check("Remark 3.16", "an anisotropic rod, (b1, b2) = (1, 3), is critical: it satisfies the discrete twist equation "
       "α(θ_{k+1} − θ_k)/h² = (b1 − b2)·½Σ_j g(t_j)(κ1κ2)_j, the discrete ατ' = (b1 − b2)κ1κ2",
       quantity="max_k defect / max_k |α(θ_{k+1} − θ_k)/h²|", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def anisotropic_rod_twist_equation(ctx, n):
    problem, sol = anisotropic_rod(n, ANISOTROPIC)
    dg.plot.curves([np.asarray(rod.curve(x, problem)) for x in (clamped_rod(n, TWIST)[1].x, sol.x)],
                   labels=["isotropic", f"(b1, b2) = {ANISOTROPIC}"], path=ctx.figure("anisotropic_rod.png"))
    return twist_equation_defect(problem, sol)


@check("Remark 3.16", "negative controls: Lemma 3.12 needs isotropy (the anisotropic rod's twist is not constant), "
       "and the twist equation with b1 ↔ b2 fails",
       quantity="min(max_k |θ_k − θ_1| / max_k |θ_k|, defect with b1 ↔ b2)", at_least=1e-2, quick=dict(n=32),
       full=dict(n=200))
def anisotropic_rod_twist_not_constant(ctx, n):
    problem, sol = anisotropic_rod(n, ANISOTROPIC)
    theta = np.asarray(rod.twist_angles(sol.x))
    return min(float(np.ptp(theta) / np.max(np.abs(theta))), twist_equation_defect(problem, sol, sign=-1.0))
