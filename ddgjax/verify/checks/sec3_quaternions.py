"""Quaternions, Euclidean motions and frames (Sec 3.2, 3.4)."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import frames
from ddgjax import quaternion as qt
from ddgjax.verify import check

from ._shared import unit_rows


def _samples(count: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-3, 3, size=(count, 3)), rng.uniform(-3, 3, size=(count, 3)), unit_rows(rng.normal(size=(count, 4)))


def _rodrigues(v, n, theta):
    """v turned by θ about the unit n (right-hand rule), rows."""
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    return v * c + np.cross(n, v) * s + n * np.sum(n * v, axis=1, keepdims=True) * (1 - c)


@check("Lemma 3.4", "for imaginary quaternions vw = −<v, w> + v × w",
       quantity="max |vw − (−<v, w>, v × w)| over random v, w", at_most=1e-12, quick=dict(count=1000), full=dict(count=100000))
def lemma_3_4_product(ctx, count):
    v, w, _ = _samples(count)
    vw = qt.mul(qt.from_vector(v), qt.from_vector(w))
    expected = np.concatenate([-np.sum(v * w, axis=1, keepdims=True), np.cross(v, w)], axis=1)
    return float(np.max(np.abs(np.asarray(vw) - expected)))


@check("Prop 3.6", "q = cos α + sin α n rotates by 2α about n: q v q⁻¹ is Rodrigues' rotation",
       quantity="max |q v q⁻¹ − R_(n, 2α) v|", at_most=1e-12, quick=dict(count=1000), full=dict(count=100000))
def prop_3_6_rotation(ctx, count):
    v, n, _ = _samples(count, 1)
    n = unit_rows(n)
    alpha = np.random.default_rng(2).uniform(0, np.pi, count)
    q = np.concatenate([np.cos(alpha)[:, None], np.sin(alpha)[:, None] * n], axis=1)
    return float(np.max(np.abs(np.asarray(qt.rotate(q, v)) - _rodrigues(v, n, 2 * alpha))))


@check("Remark 3.5", "R_(q2 q1) = R_(q2) ∘ R_(q1) and R_(−q) = R_q (the double cover)",
       quantity="max |R_(q2 q1) v − R_(q2) R_(q1) v| + |R_(−q) v − R_q v|", at_most=1e-12, quick=dict(count=1000),
       full=dict(count=100000))
def remark_3_5_composition(ctx, count):
    v, _, q1 = _samples(count, 3)
    q2 = _samples(count, 4)[2]
    composed = np.max(np.abs(np.asarray(qt.rotate(qt.mul(q2, q1), v) - qt.rotate(q2, qt.rotate(q1, v)))))
    return float(composed + np.max(np.abs(np.asarray(qt.rotate(-q1, v) - qt.rotate(q1, v)))))


@check("Cor 3.7", "the flow of v ↦ a × v + b is a one-parameter group of motions whose generator is (a, b)",
       quantity="max |d/dt m(t)(v) − (a × m(t)(v) + b)| + |generator − (a, b)|", at_most=1e-12, quick=dict(count=100),
       full=dict(count=10000))
def cor_3_7_generator(ctx, count):
    v, a, _ = _samples(count, 5)
    return float(_cor_3_7_defect(v, a, _samples(count, 6)[0], np.full(count, 0.7)))


@jax.jit
def _cor_3_7_defect(v, a, b, t):
    m, m_dot = jax.jvp(lambda s: qt.motion_exp(a, b, s), (t,), (jnp.ones_like(t),))
    point, velocity = jax.jvp(lambda s: qt.apply(qt.motion_exp(a, b, s), v), (t,), (jnp.ones_like(t),))
    a_back, b_back = qt.generator(m, m_dot)
    return (jnp.max(jnp.abs(velocity - qt.infinitesimal_motion(a, b, point)))
            + jnp.max(jnp.abs(a_back - a)) + jnp.max(jnp.abs(b_back - b)))


# --- frames -----------------------------------------------------------------------------------

HELIX = (1.3, 0.7, 0.6)  # κ0, τ0, amplitude of the extra twist θ(s) = A sin 2s


def twisted_helix_frame(s, kappa0, tau0, amplitude):
    """exp(s(τ0, 0, κ0)/2) turned about T by θ(s) = A sin 2s: κ1 = κ0 cos θ, κ2 = −κ0 sin θ,
    τ = τ0 + θ'."""
    return qt.mul(qt.exp(0.5 * s * jnp.stack([tau0, 0.0, kappa0])),
                  qt.from_axis_angle(jnp.array([1.0, 0.0, 0.0]), amplitude * jnp.sin(2 * s)))


def twisted_helix_curvatures(s, kappa0, tau0, amplitude):
    theta = amplitude * np.sin(2 * s)
    return np.stack([kappa0 * np.cos(theta), -kappa0 * np.sin(theta), tau0 + 2 * amplitude * np.cos(2 * s)])


@functools.partial(jax.jit, static_argnums=0)
def _discrete_curvatures(n: int, length: float = 2.0):
    """Discrete (κ1, κ2, τ) of the edge frames Φ_k = Φ((k + ½)h), h = length/n (compiled whole:
    one compilation per n costs less than eager dispatch of every operation at a new shape)."""
    h = length / n
    Phi = jax.vmap(lambda s: twisted_helix_frame(s, *HELIX))((jnp.arange(n) + 0.5) * h)
    return jnp.stack(frames.discrete_curvatures(Phi, h))


@check("Def 3.4, Sec 3.4", "the discrete curvatures κ1, κ2, τ of sampled edge frames converge with order 2",
       quantity="fitted order (worst of κ1, κ2, τ)", target=2.0, within=0.1, quick=dict(ns=(16, 32, 64)),
       full=dict(ns=(16, 32, 64, 128, 256, 512)))
def discrete_frame_curvatures_limit(ctx, ns):
    def error(n):
        discrete = np.asarray(_discrete_curvatures(n))
        return float(np.max(np.abs(discrete - twisted_helix_curvatures(np.arange(1, n) * 2.0 / n, *HELIX))))

    return ctx.convergence(dg.limits.convergence(error, ns, label="max error of (κ1, κ2, τ)"),
                           "convergence_frame_curvatures").fitted_order


@check("Def 3.4, eq (3.5)–(3.7)", "the frame equations: Φ' = ½ωΦ = ½ΦΩ, T' = ω × T, (κ1, κ2, τ) = (Ω3, −Ω2, Ω1)",
       quantity="max residual over sample points", at_most=1e-12, quick=dict(samples=8))
def frame_equations(ctx, samples):
    return max(float(_frame_equation_defect(s)) for s in np.linspace(0.0, 3.0, samples))


@jax.jit
def _frame_equation_defect(s):
    """The largest residual of (3.5)–(3.7) and of the curvatures at the parameter s."""
    Phi, dPhi = jax.jvp(lambda t: twisted_helix_frame(t, *HELIX), (s,), (1.0,))
    T, dT = jax.jvp(lambda t: frames.frame(twisted_helix_frame(t, *HELIX))[0], (s,), (1.0,))
    omega, Omega = frames.angular_velocity(Phi, dPhi), frames.body_angular_velocity(Phi, dPhi)
    theta = HELIX[2] * jnp.sin(2 * s)
    exact = jnp.stack([HELIX[0] * jnp.cos(theta), -HELIX[0] * jnp.sin(theta), HELIX[1] + 2 * HELIX[2] * jnp.cos(2 * s)])
    residuals = [frames.frame_velocity(Phi, omega=omega) - dPhi, frames.frame_velocity(Phi, Omega=Omega) - dPhi,
                 jnp.cross(omega, T) - dT, jnp.stack(frames.curvatures(Phi, dPhi)) - exact]
    return jnp.max(jnp.stack([jnp.max(jnp.abs(r)) for r in residuals]))


@check("Sec 3.4.1", "the Lagrange top (equations by autodiff of (3.10)) keeps its energy and axial momentum (Gauss6)",
       quantity="max drift of energy and <M, e1>", at_most=1e-11, quick=dict(t1=20.0, steps=800),
       full=dict(t1=100.0, steps=4000))
def lagrange_top_conservation(ctx, t1, steps):
    alpha, a = 2.5, np.array([0.0, 0.0, -1.0])
    Phi0 = qt.from_axis_angle(np.array([1.0, 1.0, 0.0]), 0.9)
    _, states = dg.smooth.top.simulate(Phi0, np.array([3.0, 0.4, -0.2]), t1, alpha=alpha, a=a, steps=steps)
    c = dg.smooth.top.conserved_quantities(states, alpha=alpha, a=a)
    return max(float(jnp.max(jnp.abs(c[k] - c[k][0]))) for k in ("energy", "axial_momentum"))
