"""Moving frames (Section 3.4): frame equations, curvatures, and the discrete edge-frame split.

The test frame field is a helix's Frenet-type frame `exp(sΩ_F/2)` (constant κ0, τ0) turned about
T by θ(s) = A sin(2s): a rotating frame with κ1 = κ0 cos θ, κ2 = −κ0 sin θ, τ = τ0 + θ'
(derived: Ω = Ad_{exp(−θ e1/2)} Ω_F + θ' e1).  Identities are checked to 1e-12 (machine
precision for O(10)-flop formulas on O(1) data).
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ddgjax import curves, frames
from ddgjax import quaternion as qt
from ddgjax.errors import InvalidInputError, ShapeError, SingularVertexError

TOL = 1e-12
E1 = np.array([1.0, 0.0, 0.0])


def rotating_helix_frame(kappa0, tau0, amplitude):
    def Phi(s):
        helix = qt.exp(0.5 * s * jnp.stack([tau0, 0.0, kappa0]))
        return qt.mul(helix, qt.from_axis_angle(E1, amplitude * jnp.sin(2 * s)))

    def exact(s):
        theta = amplitude * np.sin(2 * s)
        return kappa0 * np.cos(theta), -kappa0 * np.sin(theta), tau0 + 2 * amplitude * np.cos(2 * s)

    return Phi, exact


@jax.jit
def _smooth_quantities(kappa0, tau0, amplitude, s):
    Phi_of_s, _ = rotating_helix_frame(kappa0, tau0, amplitude)
    Phi, dPhi = jax.jvp(Phi_of_s, (s,), (1.0,))
    TNB, dTNB = jax.jvp(lambda s_: jnp.stack(frames.frame(Phi_of_s(s_))), (s,), (1.0,))
    return Phi, dPhi, TNB, dTNB


parameters = st.tuples(st.floats(0.1, 2.0), st.floats(-2.0, 2.0), st.floats(-1.5, 1.5), st.floats(-3.0, 3.0))


@settings(max_examples=50, deadline=None)
@given(parameters)
def test_def_3_4_curvatures_frame_equations_3_4_to_3_7(params):
    """On the rotating helix frame: (κ1, κ2, τ) = (<T',N>, <T',B>, <N',B>) = (Ω3, −Ω2, Ω1) match the
    closed form; (T, N, B)' = A (T, N, B) (3.4); Φ' = ½ωΦ = ½ΦΩ (3.5), (3.6); T' = ω × T (3.7);
    ω = ΦΩΦ⁻¹; κ² = |T'|² = κ1² + κ2²."""
    kappa0, tau0, amplitude, s = params
    Phi, dPhi, TNB, dTNB = _smooth_quantities(kappa0, tau0, amplitude, s)
    T, N, B = np.asarray(TNB)
    dT, dN, _ = np.asarray(dTNB)
    k1, k2, tau = frames.curvatures(Phi, dPhi)
    _, exact = rotating_helix_frame(kappa0, tau0, amplitude)
    assert np.allclose([k1, k2, tau], exact(s), rtol=0, atol=TOL)
    assert np.allclose([dT @ N, dT @ B, dN @ B], [k1, k2, tau], rtol=0, atol=TOL)
    assert np.allclose(dTNB, frames.frame_equation_matrix(k1, k2, tau) @ TNB, rtol=0, atol=TOL)
    omega = frames.angular_velocity(Phi, dPhi)
    Omega = frames.body_angular_velocity(Phi, dPhi)
    assert np.allclose(frames.frame_velocity(Phi, omega=omega), dPhi, rtol=0, atol=TOL)
    assert np.allclose(frames.frame_velocity(Phi, Omega=Omega), dPhi, rtol=0, atol=TOL)
    assert np.allclose(frames.body_from_curvatures(k1, k2, tau), Omega, rtol=0, atol=TOL)
    assert np.allclose(qt.rotate(Phi, Omega), omega, rtol=0, atol=TOL)
    assert np.allclose(np.cross(omega, T), dT, rtol=0, atol=TOL)
    assert abs(dT @ dT - (k1**2 + k2**2)) <= 10 * TOL
    assert abs(dT @ dT - kappa0**2) <= 10 * TOL


def test_remark_3_10_frame_recovered_from_curvatures():
    """Integrating Φ' = ½ΦΩ(s) with Ω = (τ, −κ2, κ1) from the closed-form curvatures of the
    rotating helix frame recovers the frame on [0, 3] (Gauss6, h = 0.01: error O(h⁶) ~ 1e-12,
    observed 5e-15) within 1e-12, and |Φ| = 1 to round-off."""
    params = (1.3, 0.7, 0.6)
    Phi_of_s, _ = rotating_helix_frame(*params)
    kappa0, tau0, amplitude = params

    def curvatures_of_s(s):
        theta = amplitude * jnp.sin(2 * s)
        return kappa0 * jnp.cos(theta), -kappa0 * jnp.sin(theta), tau0 + 2 * amplitude * jnp.cos(2 * s)

    s, Phi = frames.frame_from_curvatures(Phi_of_s(0.0), curvatures_of_s, 3.0, steps=300)
    exact = jax.vmap(Phi_of_s)(s)
    assert float(jnp.max(jnp.abs(Phi - exact))) <= 1e-12
    assert float(jnp.max(jnp.abs(jnp.linalg.norm(Phi, axis=-1) - 1))) <= 1e-13


@functools.partial(jax.jit, static_argnums=(0,))
def _edge_frames(n, h, params):
    Phi_of_s, _ = rotating_helix_frame(*params)
    return jax.vmap(Phi_of_s)((jnp.arange(n) + 0.5) * h)


def sampled_edge_frames(n, length=2.0, params=(1.3, 0.7, 0.6)):
    """Edge frames Φ_k = Φ((k + ½)h) on [0, length], and the smooth (κ1, κ2, τ) at the
    interior vertices s = kh, k = 1..n − 1."""
    h = length / n
    _, exact = rotating_helix_frame(*params)
    return _edge_frames(n, h, params), h, exact(np.arange(1, n) * h)


def test_edge_frame_split_reassembles_the_relative_rotation():
    """Φ_k = ± t_k b_k Φ_{k−1}; b_k takes T_{k−1} to T_k and fixes T_{k−1} × T_k; t_k fixes T_k."""
    Phi, h, _ = sampled_edge_frames(12, length=6.0)
    b, theta = frames.edge_frame_split(Phi)
    T, _, _ = frames.frame(Phi)
    T = np.asarray(T)
    t = qt.from_axis_angle(T[1:], theta)
    rebuilt = np.asarray(qt.mul(qt.mul(t, b), Phi[:-1]))
    sign = np.sign(np.sum(rebuilt * np.asarray(Phi[1:]), axis=-1))[:, None]
    assert np.max(np.abs(sign * rebuilt - Phi[1:])) <= TOL
    assert np.max(np.abs(qt.rotate(b, T[:-1]) - T[1:])) <= TOL
    axis = np.cross(T[:-1], T[1:])
    assert np.max(np.abs(qt.rotate(b, axis) - axis)) <= TOL
    assert np.max(np.abs(theta)) > 0.5  # the frame does twist here


def test_discrete_curvature_is_the_arclength_curvature_of_the_tangent_polyline():
    """sqrt(κ1² + κ2²) = 2 tan(φ_k/2)/h = curves.curvature(from_tangents(T, h), "arclength")."""
    Phi, h, _ = sampled_edge_frames(40)
    k1, k2, _ = frames.discrete_curvatures(Phi, h)
    T, _, _ = frames.frame(Phi)
    gamma = curves.from_tangents(T, edge_length=h)
    kappa = curves.curvature(gamma, "arclength")
    assert np.max(np.abs(np.hypot(k1, k2) - kappa)) <= 1e-11  # 1/h = 20 amplifies round-off


def test_pure_twist_is_exact():
    """Φ_k = exp(k h τ e1 / 2) (a straight rod twisting at rate τ): b_k = 1 and θ_k = hτ, so the
    discrete torsion is exactly τ and both curvatures 0."""
    h, tau = 0.1, 0.8
    Phi = qt.exp(0.5 * h * np.arange(10)[:, None] * np.array([tau, 0.0, 0.0]))
    k1, k2, t = frames.discrete_curvatures(Phi, h)
    assert np.max(np.abs(t - tau)) <= TOL and np.max(np.abs(k1)) <= TOL and np.max(np.abs(k2)) <= TOL


def test_bad_edge_frames():
    Phi, h, _ = sampled_edge_frames(8)
    with pytest.raises(ShapeError):
        frames.discrete_curvatures(Phi[:, :3], h)
    with pytest.raises(InvalidInputError, match=r"entry \(3,\)"):
        frames.discrete_curvatures(np.asarray(Phi).copy() * np.array([1, 1, 1, 2, 1, 1, 1, 1.0])[:, None], h)
    flipped = np.array([[1.0, 0, 0, 0], [0, 0, 0, 1.0]])  # T_1 = −T_0
    with pytest.raises(SingularVertexError, match="vertex 1"):
        frames.edge_frame_split(flipped)
    with pytest.raises(InvalidInputError):
        frames.frame_velocity(Phi[0])
