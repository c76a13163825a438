"""Benchmark of spin-chain integration (Appendix A): ddgjax's Gauss–Legendre (order 6, `jit`,
right-hand side from the Hamiltonian by autodiff) against the same right-hand side written in
plain NumPy and integrated by `scipy.integrate.solve_ivp(method="DOP853")`.

For each chain size N: the integrable chain (Remark A.1, J = 1) from a smooth perturbed spin
wave, integrated to t1 = `--t1` with `--dt`.  Reported: compile time (ddgjax), integration steps
per second, energy drift per unit time |H(t1) − H(0)|/t1, max ||S_i| − 1|, and the wall time.
scipy is run with rtol chosen so that its energy drift is no worse than ddgjax's where it can
(`--rtol`), which is the "same accuracy" comparison.

Also prints the energy drift of ddgjax against the step size (a table with observed orders).

    python benchmarks/heisenberg.py [--sizes 1000 10000 100000] [--t1 1.0] [--dt 0.01]

(10⁶ spins: add 1000000 to --sizes; each method then takes minutes on 2 cores.)
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np
import scipy.integrate

import ddgjax as dg
from energies import heisenberg as hz


def initial_spins(N: int) -> np.ndarray:
    """A spin wave plus seeded noise: neighbouring spins differ by ~0.3 rad, so the chain moves
    on the unit time scale of its couplings whatever N is."""
    x = 2 * np.pi * np.arange(N) / N
    S = np.stack([0.6 * np.cos(3 * x), 0.6 * np.sin(3 * x), 0.8 + 0.1 * np.sin(x)], axis=1)
    S = S + 0.3 * np.random.default_rng(0).normal(size=S.shape)
    return S / np.linalg.norm(S, axis=1, keepdims=True)


def numpy_rhs(S: np.ndarray) -> np.ndarray:
    """Remark A.1 written out: ∂_t S_i = 2 S_i × (S_{i+1}/(1 + <S_{i+1}, S_i>) + S_{i−1}/(1 + <S_i, S_{i−1}>))."""
    up, down = np.roll(S, -1, axis=0), np.roll(S, 1, axis=0)
    field = up / (1 + np.sum(up * S, 1))[:, None] + down / (1 + np.sum(S * down, 1))[:, None]
    return 2.0 * np.cross(S, field)


def run_ddgjax(S0, t1, dt):
    f, H = hz.flow("integrable", 1.0), hz.hamiltonian("integrable", 1.0)
    steps = int(round(t1 / dt))
    run = jax.jit(lambda S: dg.integrate(f, S, t1, steps=steps)[1][-1])
    t0 = time.perf_counter()
    jax.block_until_ready(run(S0))
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    S1 = jax.block_until_ready(run(S0))
    wall = time.perf_counter() - t0
    drift = abs(float(H(S1)) - float(H(S0))) / t1
    unit = float(jnp.max(jnp.abs(jnp.linalg.norm(S1, axis=1) - 1)))
    return {"compile": first - wall, "wall": wall, "steps": steps, "drift": drift, "unit": unit}


def run_scipy(S0, t1, rtol):
    N = len(S0)
    H = hz.hamiltonian("integrable", 1.0)
    t0 = time.perf_counter()
    sol = scipy.integrate.solve_ivp(
        lambda t, y: numpy_rhs(y.reshape(N, 3)).ravel(), (0.0, t1), np.asarray(S0).ravel(),
        method="DOP853", rtol=rtol, atol=rtol * 1e-2,
    )
    wall = time.perf_counter() - t0
    S1 = sol.y[:, -1].reshape(N, 3)
    unit = float(np.max(np.abs(np.linalg.norm(S1, axis=1) - 1)))
    drift = abs(float(H(S1 / np.linalg.norm(S1, axis=1, keepdims=True))) - float(H(jnp.asarray(S0)))) / t1
    return {"wall": wall, "steps": int(sol.t.size - 1), "drift": drift, "unit": unit}


def drift_against_step(N=256, t1=2.0):
    S0 = jnp.asarray(initial_spins(N))
    dts = [0.04, 0.02, 0.01]
    drifts = [run_ddgjax(S0, t1, dt)["drift"] for dt in dts]
    table = dg.limits.ConvergenceTable.from_errors([1 / d for d in dts], drifts, "energy drift / t")
    print(f"\nddgjax gauss6 energy drift against step size (N = {N}, t = {t1}); n = 1/dt:\n")
    print(table.to_markdown())


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000])
    parser.add_argument("--t1", type=float, default=1.0)
    parser.add_argument("--dt", type=float, default=0.01)
    parser.add_argument("--rtol", type=float, default=1e-10)
    args = parser.parse_args(argv)
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, scipy {scipy.__version__}")
    print("| N spins | method | compile s | wall s | steps | steps/s | energy drift / t | max ||S|−1| | scipy wall / ddgjax |")
    print("|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for N in args.sizes:
        S0 = jnp.asarray(initial_spins(N))
        ours = run_ddgjax(S0, args.t1, args.dt)
        theirs = run_scipy(np.asarray(S0), args.t1, args.rtol)
        print(f"| {N} | ddgjax gauss6 | {ours['compile']:.2f} | {ours['wall']:.3f} | {ours['steps']} | "
              f"{ours['steps'] / ours['wall']:.0f} | {ours['drift']:.1e} | {ours['unit']:.1e} | |")
        print(f"| {N} | scipy DOP853 | — | {theirs['wall']:.3f} | {theirs['steps']} | "
              f"{theirs['steps'] / theirs['wall']:.0f} | {theirs['drift']:.1e} | {theirs['unit']:.1e} | "
              f"{theirs['wall'] / ours['wall']:.1f}× |")
    drift_against_step()


if __name__ == "__main__":
    main()
