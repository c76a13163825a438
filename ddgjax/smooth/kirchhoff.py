"""Smooth clamped elastic rods by the Kirchhoff analogy (Thm 3.11, Thm 3.13): shooting with the
Lagrange top.

By Thm 3.11 a framed arc-length curve (γ, Φ) is an elastic rod with torsion coefficient α iff its
frame, read with arc length as time, is a motion of the Lagrange top (Sec 3.4.1) with inertia
`J = diag(α, 1, 1)` and gravity `a` (the multiplier of the chord constraint): the rod functional
`E_a = ∫ <ω, ω> + (α − 1)<ω, T>² + 2<a, T> ds` *is* the top's action (3.10).  A clamped rod on
[0, L] with `Φ(0) = q0`, `Φ(L) = q1`, `γ(L) − γ(0) = c` is therefore the top motion from
`(q0, M0)` that satisfies

    Φ(L) = ±q1   (3 conditions: Im(q1⁻¹ Φ(L)) = 0),      ∫_0^L T ds = c   (3 conditions),

six equations for the six unknowns (M0, a): the body angular momentum at s = 0 and the load.
The top's equations of motion come from `ddgjax.smooth.top.equations_of_motion` (derived by autodiff
of (3.10)), γ' = T = Φ i Φ⁻¹ is integrated alongside with diffrax (8th-order Dormand–Prince,
tolerance 1e-13), and the shooting equations are solved by optimistix's Levenberg–Marquardt
method with the Jacobian by forward-mode differentiation through the integrator.

`jet` evaluates γ, T, T', T'' and ω, ω' along a rod (by autodiff of the top's vector field), the
ingredients of Thm 3.13 (i)–(iii).

This is the *independent* smooth reference for the discrete rods of `energies.rod`: nothing
here uses the discrete energy; the discrete solution only provides a starting guess (which
also selects the branch when the clamped problem has several solutions).
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Float

from .. import quaternion as qt
from ..curves import from_tangents
from .._host import namespace
from ..errors import ConvergenceError, InvalidInputError
from ..frames import angular_velocity, edge_frame_split
from .top import TopState, equations_of_motion

__all__ = [
    "SmoothRod", "RodJet", "shoot", "clamped_rod", "from_discrete", "discrete_errors", "sample", "jet", "torsion",
    "discrete_top_residual",
]

E1 = jnp.array([1.0, 0.0, 0.0])
RTOL = 1e-13


class SmoothRod(NamedTuple):
    """A smooth clamped rod: the initial frame and body momentum of its top motion, the load a,
    the torsion coefficient α and the length L; `sample(rod, s)` evaluates it."""

    Phi0: Float[Array, "4"]
    M0: Float[Array, "3"]
    a: Float[Array, "3"]
    alpha: float
    length: float


def _field(sigma, y, args):
    """The top's vector field with γ' = T (Thm 3.11), times `gap`: the motion over an arc length
    `gap` as a function of σ ∈ [0, 1] (s = s₀ + gap·σ)."""
    Phi, M, _gamma = y
    alpha, a, gap = args
    d = equations_of_motion(TopState(Phi, M), alpha, a)
    return gap * d.Phi, gap * d.M, gap * qt.rotate(Phi, E1)


def _flow(y, gap, alpha, a):
    """The state (Φ, M, γ) of the top motion an arc length `gap` ≥ 0 after the state y: one
    diffrax solve of `_field` over the unit interval.  Its bounds and first step are constants,
    so diffrax checks them when tracing, not with host callbacks in the program (which would
    keep it out of the persistent compilation cache)."""
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(_field),
        diffrax.Dopri8(),
        t0=0.0,
        t1=1.0,
        dt0=0.25,
        y0=y,
        args=(alpha, a, gap),
        saveat=diffrax.SaveAt(t1=True),
        stepsize_controller=diffrax.PIDController(rtol=RTOL, atol=RTOL),
        adjoint=diffrax.ForwardMode(),
        max_steps=100_000,
        throw=False,  # a diverging Newton iterate gives inf/NaN, caught by the final residual check
    )
    return jax.tree_util.tree_map(lambda v: v[0], sol.ys)


def _integrate(Phi0, M0, a, alpha, ts):
    """(Φ, M, γ) of the top motion at the arc lengths ts (non-decreasing, ≥ 0; γ(0) = 0): the
    flow from each arc length to the next (`lax.scan` of `_flow`)."""
    def step(y, gap):
        y = _flow(y, gap, alpha, a)
        return y, y

    gaps = jnp.diff(ts, prepend=jnp.zeros(1, ts.dtype))
    return jax.lax.scan(step, (Phi0, M0, jnp.zeros(3, M0.dtype)), gaps)[1]


_integrate_jit = jax.jit(_integrate)

SAMPLE_BUCKET = 64
"""Arc lengths are integrated in blocks of this many (the last one repeated), so that sampling
at m points compiles one program per ⌈m / 64⌉ rather than one per m."""


def _sample(rod: SmoothRod, s) -> tuple:
    """(Φ, M, γ) of the top motion of `rod` at the arc lengths s (m,), non-decreasing.

    **Raises:** `InvalidInputError` for concrete arc lengths that decrease somewhere (the
    integrator saves along one direction of s only)."""
    xp = namespace(s)
    s = xp.asarray(s, dtype=float)
    m = s.shape[0]
    if xp is np and m > 1 and bool(np.any(np.diff(s) < 0)):
        k = int(np.argmax(np.diff(s) < 0))
        raise InvalidInputError(f"arc lengths must be non-decreasing: s[{k + 1}] = {float(s[k + 1])!r} < s[{k}] = "
                                f"{float(s[k])!r}")
    padded = xp.concatenate([s, xp.full((-m % SAMPLE_BUCKET,), s[-1])]) if m else s
    ys = _integrate_jit(rod.Phi0, rod.M0, rod.a, rod.alpha, padded)
    return _first_rows(ys, m)


@partial(jax.jit, static_argnums=1)
def _first_rows(ys: tuple, m: int) -> tuple:
    """The first m rows of each array of `ys` (one program, not one slice per array)."""
    return tuple(y[:m] for y in ys)


def shoot(z: Float[Array, "6"], Phi0, Phi1, chord, alpha, length) -> Float[Array, "6"]:
    """The shooting residual of z = (M0, a): `(Im(Φ1⁻¹ Φ(L)), γ(L) − chord)`."""
    Phi, _M, gamma = _integrate(Phi0, z[:3], z[3:], alpha, jnp.reshape(length, (1,)))
    return jnp.concatenate([qt.mul(qt.conj(Phi1), Phi[0])[1:], gamma[0] - chord])


_shoot = jax.jit(shoot)


def _residual(z, args):
    return shoot(z, *args)


@partial(jax.jit, static_argnames="tol")
def _least_squares(z0, args, *, tol: float):
    """Levenberg–Marquardt on |shoot|² (compiled once per process: module-level functions).
    Near a buckling load the shooting Jacobian is nearly singular and undamped Newton leaves the
    branch of the guess."""
    sol = optx.least_squares(
        _residual, optx.LevenbergMarquardt(rtol=tol, atol=tol), z0, args=args, throw=False, max_steps=200
    )
    return sol.value, sol.stats["num_steps"]


def clamped_rod(
    *, alpha: float, length: float = 1.0, chord, frame_start, frame_end, M0_guess, a_guess, tol: float = 1e-11
) -> SmoothRod:
    """The smooth clamped rod (Thm 3.13) with `Φ(0) = frame_start`, `Φ(L) = frame_end` and chord,
    by shooting from the guess `(M0_guess, a_guess)` (e.g. from a discrete rod:
    `M0 = 2 J Ω(0)`, `a = rod.load(solution)`).

    **Raises:** `InvalidInputError` (α ≤ 0, non-unit frames), `ConvergenceError` if Newton does
    not reach `tol` in the shooting residual.
    """
    if not (np.isfinite(alpha) and alpha > 0):
        raise InvalidInputError(f"the torsion coefficient alpha must be positive, got {alpha}")
    qt.check_unit(frame_start, "frame_start")
    qt.check_unit(frame_end, "frame_end")
    Phi0, Phi1 = jnp.asarray(frame_start, dtype=float), jnp.asarray(frame_end, dtype=float)
    chord = jnp.asarray(chord, dtype=float)
    args = (Phi0, Phi1, chord, jnp.asarray(float(alpha)), jnp.asarray(float(length)))
    z0 = jnp.concatenate([jnp.asarray(M0_guess, dtype=float), jnp.asarray(a_guess, dtype=float)])
    value, steps = _least_squares(z0, args, tol=float(tol))
    residual = float(jnp.max(jnp.abs(_shoot(value, *args))))
    if not residual <= 10 * tol:
        raise ConvergenceError(
            f"shooting for the smooth rod did not converge: residual {residual:.3e} > {tol:.1e} "
            "(try a better guess, e.g. from a finer discrete rod)",
            residual=residual, steps=int(steps), solution=value,
        )
    return SmoothRod(Phi0, value[:3], value[3:], float(alpha), float(length))


def from_discrete(problem, solution, *, tol: float = 1e-11) -> SmoothRod:
    """The smooth clamped rod with the clamps, chord and α of a solved *vertex-clamped* discrete
    rod (`energies.rod.clamped(..., clamp="vertex")`), by shooting from its guess: the body
    angular velocity at s = 0, `Ω(0) ≈ 4 log(q0⁻¹ Φ_0)/h` (Φ_0 is the frame at s = h/2), gives
    `M0 = 2JΩ(0)`, and the chord multipliers give `a` (`energies.rod.load`)."""
    p = problem.params
    q0, h, alpha = p["frame_start"], p["h"], float(p["alpha"])
    Omega = 4 * qt.log(qt.mul(qt.conj(q0), solution.x[0])) / h
    return clamped_rod(
        alpha=alpha, length=h * solution.x.shape[0], chord=p["chord"], frame_start=q0, frame_end=p["frame_end"],
        M0_guess=2 * jnp.array([alpha, 1.0, 1.0]) * Omega, a_guess=solution.multipliers["chord"], tol=tol,
    )


def discrete_errors(problem, solution, smooth: SmoothRod) -> dict[str, float]:
    """Distances of a solved discrete rod to the smooth rod: `position` max_k |γ_k − γ(kh)| over
    the vertices (γ_0 = 0), `load` max |λ − a|, `twist` |mean θ_k / h − τ|."""
    Phi, h = jnp.asarray(solution.x), problem.params["h"]
    n = Phi.shape[0]
    _, gamma = sample(smooth, np.arange(n + 1) * h)
    position, load, mean_twist = _distances(Phi, jnp.asarray(h, dtype=float), gamma, solution.multipliers["chord"],
                                            smooth.a)
    return {"position": float(position), "load": float(load), "twist": abs(float(mean_twist) / h - torsion(smooth))}


@jax.jit
def _distances(Phi, h, gamma, chord_multipliers, a):
    """max_k |γ_k − γ(kh)|, max |λ − a| and mean θ_k of `discrete_errors`, in one compiled program
    per size (not one per array operation)."""
    nodes = from_tangents(qt.rotate(Phi, E1), edge_length=h)
    return (jnp.max(jnp.linalg.norm(nodes - gamma, axis=1)), jnp.max(jnp.abs(chord_multipliers - a)),
            jnp.mean(edge_frame_split(Phi)[1]))


def sample(rod: SmoothRod, s) -> tuple[Float[Array, "m 4"], Float[Array, "m 3"]]:
    """The frames Φ(s) and the centreline γ(s) (γ(0) = 0) at the arc lengths s (m,)."""
    Phi, _M, gamma = _sample(rod, s)
    return Phi, gamma


class RodJet(NamedTuple):
    """The centreline γ, the tangent T = γ' with its derivatives T', T'' and the spatial angular
    velocity ω = 2Φ'Φ⁻¹ with ω' of a smooth rod at m arc lengths (each (m, 3))."""

    gamma: Float[Array, "m 3"]
    T: Float[Array, "m 3"]
    dT: Float[Array, "m 3"]
    ddT: Float[Array, "m 3"]
    omega: Float[Array, "m 3"]
    domega: Float[Array, "m 3"]


def _tangent_and_angular_velocity(state: TopState, alpha, a):
    """`(T, ω, T')` at a state of the top: `T = Φ i Φ⁻¹`, `ω = 2Φ'Φ⁻¹`, `T' = ω × T` (3.7)."""
    omega = angular_velocity(state.Phi, equations_of_motion(state, alpha, a).Phi)
    T = qt.rotate(state.Phi, E1)
    return T, omega, jnp.cross(omega, T)


@jax.jit
def _jet(Phi, M, alpha, a):
    def at(Phi, M):
        state = TopState(Phi / jnp.linalg.norm(Phi), M)
        velocity = equations_of_motion(state, alpha, a)
        (T, omega, dT), (_, domega, ddT) = jax.jvp(
            lambda y: _tangent_and_angular_velocity(y, alpha, a), (state,), (velocity,)
        )
        return T, dT, ddT, omega, domega

    return jax.vmap(at)(Phi, M)


def jet(rod: SmoothRod, s) -> RodJet:
    """γ, T, T', T'', ω, ω' of the smooth rod at the arc lengths s (m,), from its top motion:
    `(T, ω, T' = ω × T)` as functions of the state (Φ, M), and their derivatives along the
    top's vector field by forward-mode autodiff (nothing typed in by hand).  Φ is normalised
    first: the integrator leaves H_1 by its tolerance, which the polynomial extension of the
    potential would turn into an O(|a| · tolerance) error of ω'."""
    Phi, M, gamma = _sample(rod, s)
    return RodJet(gamma, *_jet(Phi, M, jnp.asarray(rod.alpha), jnp.asarray(rod.a, dtype=float)))


def torsion(rod: SmoothRod) -> float:
    """The constant torsion τ = <ω, T> = Ω₁ = M₁/(2α) (Lemma 3.12; M = 2JΩ)."""
    return float(rod.M0[0] / (2 * rod.alpha))


def discrete_top_residual(Phi: Float[Array, "n 4"], h: float, alpha: float, a) -> Float[Array, "m 2 3"]:
    """The residual of the top equations (Thm 3.13 (i)) `T' = ω × T`, `ω' = (1 − α)τT' + T × a`
    on discrete edge frames Φ_k with edge length h, by central differences at the edges 1 … n−2.

    At vertex k (between edges k−1 and k): `ω_k = 2 log(Φ_k Φ_{k−1}⁻¹)/h` (`Φ_k = exp(hω/2)Φ_{k−1}`)
    and `T_k^v = (T_{k−1} + T_k)/|T_{k−1} + T_k|`; at edge k: `T' = (T_{k+1}^v − T_k^v)/h`,
    `ω = (ω_k + ω_{k+1})/2`, `ω' = (ω_{k+1} − ω_k)/h`, `τ = <ω, T_k>`.  Both rows of the result
    are O(h²) on samples of a smooth rod (Thm 3.11: a rod's frame is a top motion).
    """
    return _top_residual(jnp.asarray(Phi, dtype=float), jnp.asarray(h, dtype=float), jnp.asarray(alpha, dtype=float),
                         jnp.asarray(a, dtype=float))


@jax.jit
def _top_residual(Phi, h, alpha, a):
    """`discrete_top_residual`, one compiled program per size."""
    T = qt.rotate(Phi, E1)
    omega = 2 * qt.log(qt.mul(Phi[1:], qt.conj(Phi[:-1]))) / h
    Tv = T[:-1] + T[1:]
    Tv = Tv / jnp.linalg.norm(Tv, axis=-1, keepdims=True)
    Te = T[1:-1]
    dT = (Tv[1:] - Tv[:-1]) / h
    w = 0.5 * (omega[1:] + omega[:-1])
    dw = (omega[1:] - omega[:-1]) / h
    tau = jnp.sum(w * Te, axis=-1, keepdims=True)
    r1 = dT - jnp.cross(w, Te)
    r2 = dw - (1 - alpha) * tau * dT - jnp.cross(Te, a)
    return jnp.stack([r1, r2], axis=1)
