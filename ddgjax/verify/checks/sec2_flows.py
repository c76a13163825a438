"""Flows on discrete curves (Sec 2, Remark 3.6)."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import curves
from ddgjax.verify import check
from energies import heisenberg

ORDER_2 = dict(target=2.0, within=0.1)


def latitude_longitude_curve(s):
    """The closed arc-length curve of length 2π whose unit tangent runs at latitude s and
    longitude 2s on S²: T = (cos s cos 2s, cos s sin 2s, sin s), κ² = 1 + 4cos² s, ∫κ² = 6π."""
    return jnp.array([(jnp.sin(s) + jnp.sin(3 * s) / 3) / 2, -(jnp.cos(s) + jnp.cos(3 * s) / 3) / 2, -jnp.cos(s)])


@functools.cache
def closed_curve(n: int):
    """n equal chords inscribed in the curve, scaled to unit edges; the chord ε; the parameters."""
    gamma, s = curves.sample(latitude_longitude_curve, n, length=2 * np.pi, closed=True, equal_chords=True,
                             return_parameters=True)
    eps = float(np.mean(np.asarray(curves.edge_lengths(gamma, closed=True))))
    return jnp.asarray(gamma) / eps, eps, np.asarray(s)


def _edge_length_rate(flow, gamma) -> float:
    """max_k |d/dt |γ_{k+1} − γ_k|²| along ∂_t γ = flow(γ) (a JVP)."""
    squared = lambda g: curves.edge_lengths(g, closed=True) ** 2  # noqa: E731
    return float(jnp.max(jnp.abs(jax.jvp(squared, (gamma,), (flow(gamma, closed=True),))[1])))


@check("Prop 2.1", "the discrete tangent flow keeps every edge length (autodiff of the bending energy)",
       quantity="max_k |d/dt |Δγ_k|²| (unit edges)", at_most=1e-13, quick=dict(n=24))
def tangent_flow_keeps_lengths(ctx, n):
    return _edge_length_rate(curves.tangent_flow, closed_curve(n)[0])


@check("Prop 2.2", "the discrete Heisenberg flow keeps every edge length",
       quantity="max_k |d/dt |Δγ_k|²| (unit edges)", at_most=1e-13, quick=dict(n=24))
def heisenberg_flow_keeps_lengths(ctx, n):
    return _edge_length_rate(curves.heisenberg_flow, closed_curve(n)[0])


@check("Prop 2.2", "the Heisenberg flow commutes with the tangent flow",
       quantity="max |[v, w]| = |Dw·v − Dv·w|", at_most=1e-12, quick=dict(n=24))
def heisenberg_commutes_with_tangent_flow(ctx, n):
    gamma = closed_curve(n)[0]
    return float(jnp.max(jnp.abs(dg.lie_bracket(curves.tangent_flow, curves.heisenberg_flow)(gamma))))


@check("eq (2.14), Remark A.1", "on the tangents, the Heisenberg flow is the integrable spin chain with J = −1/2",
       quantity="max_k |∂_t T_k − (∇_k H × T_k)|", at_most=1e-13, quick=dict(n=24))
def heisenberg_flow_on_tangents_is_spin_chain(ctx, n):
    gamma = closed_curve(n)[0]
    edges = functools.partial(curves.edge_vectors, closed=True)
    dT = jax.jvp(edges, (gamma,), (curves.heisenberg_flow(gamma),))[1]
    return float(jnp.max(jnp.abs(dT - heisenberg.flow("integrable", -0.5)(edges(gamma)))))


_heisenberg_flow = jax.jit(curves.heisenberg_flow)  # one compilation per n, not one per operation


@jax.jit
def _smooth_binormal(s):
    """T' × T of the smooth curve at the parameters s (Remark 2.3)."""
    velocity = jax.vmap(jax.jacfwd(latitude_longitude_curve))(s)
    return jnp.cross(jax.vmap(jax.jacfwd(jax.jacfwd(latitude_longitude_curve)))(s), velocity)


@check("Remark 2.3", "with time scaled by ε/2 the Heisenberg flow tends to T' × T, order 2",
       quantity="fitted order", quick=dict(ns=(16, 32, 64, 128)), full=dict(ns=(16, 32, 64, 128, 256, 512)), **ORDER_2)
def heisenberg_flow_smooth_limit(ctx, ns):
    def error(n):
        gamma, eps, s = closed_curve(n)
        # w is homogeneous of degree 0 in γ: the flow of the unit-edge curve is that of γ
        return float(jnp.max(jnp.abs(2 / eps * _heisenberg_flow(gamma) - _smooth_binormal(s))))

    table = dg.limits.convergence(error, ns, label="‖(2/ε) w_k − T′ × T‖∞")
    return ctx.convergence(table, "convergence_heisenberg_flow").fitted_order


@check("Remark 3.6", "(4/ε) Σ log(1 + tan²(φ_k/2)) tends to ∫κ² ds = 6π, order 2",
       quantity="fitted order", quick=dict(ns=(16, 32, 64, 128)), full=dict(ns=(16, 32, 64, 128, 256, 512)), **ORDER_2)
def bending_energy_smooth_limit(ctx, ns):
    def error(n):
        gamma, eps, _ = closed_curve(n)
        T = curves.tangents(gamma, closed=True)
        energy = jnp.sum(jax.vmap(curves.local_bending_energy)(jnp.roll(T, 1, axis=0), T))
        return abs(4 / eps * float(energy) - 6 * np.pi)

    table = dg.limits.convergence(error, ns, label="error of (4/ε) Σ E_k")
    return ctx.convergence(table, "convergence_bending_energy").fitted_order
