"""Spin chains: the Heisenberg magnet (Appendix A, Remark A.1)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax.verify import check
from energies import heisenberg

from ._shared import max_abs, unit_rows


def spin_wave(N: int, t: float, J: float, theta: float = 0.7, k: int = 2) -> np.ndarray:
    """The exact precessing spin wave of ∂_t S = J S × S'' on the circle, ω = J k² cos θ, sampled
    at x = 2πi/N; |S'|² = k² sin²θ, so (J/2)∫|S'|² = πJ k² sin²θ."""
    x = 2 * np.pi * np.arange(N) / N
    phase = k * x - J * k**2 * np.cos(theta) * t
    return np.stack([np.sin(theta) * np.cos(phase), np.sin(theta) * np.sin(phase), np.full(N, np.cos(theta))], axis=1)


def random_spins(N: int, seed: int) -> np.ndarray:
    """Spins near a smooth field (neighbours far from anti-parallel, where the integrable flow is singular)."""
    rng = np.random.default_rng(seed)
    return unit_rows(spin_wave(N, 0.0, 1.0, theta=1.2, k=1) + 0.4 * rng.normal(size=(N, 3)))


@check("eq (A.2), Remark A.1", "the flows derived by autodiff from H are the chains' equations of motion",
       quantity="max |autodiff flow − closed form| over both chains", at_most=1e-12, quick=dict(N=12))
def spin_chain_equations(ctx, N):
    S, J = random_spins(N, 0), 0.7
    up, down = np.roll(S, -1, axis=0), np.roll(S, 1, axis=0)
    dot = lambda a, b: np.sum(a * b, axis=1, keepdims=True)  # noqa: E731
    naive = J * np.cross(S, up + down)
    integrable = 2 * J * np.cross(S, up / (1 + dot(S, up)) + down / (1 + dot(S, down)))
    return max(max_abs(jax.jit(heisenberg.flow("naive", J))(S), naive),
               max_abs(jax.jit(heisenberg.flow("integrable", J))(S), integrable))


def _bracket_with_tangent_flow(kind: str, N: int) -> float:
    bracket = jax.jit(dg.lie_bracket(heisenberg.tangent_flow_on_tangents, heisenberg.flow(kind, -0.5)))
    return max_abs(bracket(random_spins(N, 1)))


@check("Remark A.1, Prop 2.2", "the integrable chain commutes with the discrete tangent flow",
       quantity="max |[∂_x, ∂_t]|", at_most=1e-11, quick=dict(N=9))
def integrable_chain_commutes(ctx, N):
    return _bracket_with_tangent_flow("integrable", N)


@check("Remark A.1", "negative control: the naive chain does not commute with the tangent flow",
       quantity="max |[∂_x, ∂_t]|", at_least=1e-2, quick=dict(N=9))
def naive_chain_does_not_commute(ctx, N):
    return _bracket_with_tangent_flow("naive", N)


@check("Appendix A", "Gauss6 integration keeps H, the total spin and |S_i| = 1 (naive and integrable chains)",
       quantity="max drift of H, Σ S_i and |S_i| over both chains", at_most=1e-9, quick=dict(N=32, t1=5.0, steps=500),
       full=dict(N=64, t1=20.0, steps=4000))
def spin_chain_conservation(ctx, N, t1, steps):
    S0, drift = random_spins(N, 2), 0.0
    for kind in ("naive", "integrable"):
        H = heisenberg.hamiltonian(kind, 1.0)
        _, Ss = dg.integrate(heisenberg.flow(kind, 1.0), S0, t1, steps=steps)
        if kind == "integrable":
            dg.plot.spin_chain(Ss[-1], path=ctx.figure("spin_chain.png"), title=f"integrable chain, t = {t1:g}")
        energies, Ss = np.asarray(jax.jit(jax.vmap(H))(Ss)), np.asarray(Ss)
        drift = max(drift, max_abs(energies, energies[0]), max_abs(Ss.sum(axis=1), S0.sum(axis=0)),
                    max_abs(np.linalg.norm(Ss, axis=-1), 1.0))
    return drift


@check("eq (A.3)", "the flow of H/ε (time scaled by 1/ε) tends to ∂_t S = J S × S'' on a spin wave, order 2",
       quantity="fitted order furthest from 2 over both chains", target=2.0, within=0.15, quick=dict(Ns=(16, 32, 64)),
       full=dict(Ns=(16, 32, 64, 128)))
def spin_chain_smooth_limit(ctx, Ns):
    J, orders = 1.0, []
    for kind in ("naive", "integrable"):
        def error(N, kind=kind):
            flow = heisenberg.scaled_flow(kind, J, 2 * np.pi / N)
            _, Ss = dg.integrate(flow, jnp.asarray(spin_wave(N, 0.0, J)), 1.0, steps=N * N // 2)
            return float(np.max(np.abs(np.asarray(Ss[-1]) - spin_wave(N, 1.0, J))))

        table = dg.limits.convergence(error, Ns, label=f"max_i dist(S_i(1), S(x_i, 1)), {kind}")
        orders.append(ctx.convergence(table, f"convergence_spin_wave_{kind}").fitted_order)
    return max(orders, key=lambda p: abs(p - 2.0))


@check("Appendix A", "(H − H_aligned)/ε tends to (J/2)∫|S'|² dx = πJk² sin²θ on a spin wave",
       quantity="fitted order, worst of both chains", at_least=1.8, quick=dict(Ns=(16, 32, 64, 128)))
def scaled_hamiltonian_limit(ctx, Ns):
    J, theta, k = 1.5, 0.7, 2
    exact = np.pi * J * k**2 * np.sin(theta) ** 2
    orders = []
    for kind in ("naive", "integrable"):
        def error(N, kind=kind):
            H_eps = heisenberg.scaled_hamiltonian(kind, J, 2 * np.pi / N)
            return abs(float(jax.jit(H_eps)(spin_wave(N, 0.0, J, theta, k))) - exact)

        table = dg.limits.convergence(error, Ns, label=f"error of (H − H_0)/ε, {kind}")
        orders.append(ctx.convergence(table, f"convergence_scaled_hamiltonian_{kind}").fitted_order)
    return min(orders)
