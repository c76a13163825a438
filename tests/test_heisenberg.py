"""The Heisenberg magnet chain (Appendix A, Remark A.1, eq 2.14): flows by autodiff, conservation,
integrability and the smooth limit."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import InvalidInputError, NonFiniteError
from energies import heisenberg as hz


def random_spins(N, seed):
    S = np.random.default_rng(seed).normal(size=(N, 3))
    return jnp.asarray(S / np.linalg.norm(S, axis=1, keepdims=True))


def smooth_spins(N, t=0.0):
    x = 2 * np.pi * np.arange(N) / N
    S = np.stack([np.cos(x) + 0.3 * np.sin(2 * x), np.sin(x), 0.5 * np.cos(3 * x) + 0.2], axis=1)
    return jnp.asarray(S / np.linalg.norm(S, axis=1, keepdims=True))


def test_flows_by_autodiff_equal_A2_and_remark_A1():
    S, J = random_spins(12, 0), 0.7
    up, down = jnp.roll(S, -1, axis=0), jnp.roll(S, 1, axis=0)
    naive = J * jnp.cross(S, up + down)  # (A.2)
    dot_up, dot_down = jnp.sum(S * up, 1)[:, None], jnp.sum(S * down, 1)[:, None]
    integrable = 2 * J * jnp.cross(S, up / (1 + dot_up) + down / (1 + dot_down))  # Remark A.1
    assert float(jnp.max(jnp.abs(hz.flow("naive", J)(S) - naive))) <= 1e-12
    assert float(jnp.max(jnp.abs(hz.flow("integrable", J)(S) - integrable))) <= 1e-12


def test_integrable_chain_on_tangents_is_the_discrete_heisenberg_flow_2_14():
    """With J = −½ and S = T: ∂_t T_k = (T_{k+1}/(1+<T_{k+1},T_k>) + T_{k−1}/(1+<T_k,T_{k−1}>)) × T_k."""
    T = random_spins(10, 1)
    up, down = jnp.roll(T, -1, axis=0), jnp.roll(T, 1, axis=0)
    eq_2_14 = jnp.cross(up / (1 + jnp.sum(up * T, 1))[:, None] + down / (1 + jnp.sum(T * down, 1))[:, None], T)
    assert float(jnp.max(jnp.abs(hz.flow("integrable", -0.5)(T) - eq_2_14))) <= 1e-12


def test_integrable_flow_commutes_with_the_tangent_flow_and_naive_does_not():
    """Remark A.1 / Prop 2.2: [∂_x, ∂_t] = 0 on tangents for the integrable chain only."""
    x_flow = hz.tangent_flow_on_tangents
    for seed in range(3):
        # random, but no neighbours close to anti-parallel (where 1/(1 + <T_k, T_k−1>) blows up)
        T = smooth_spins(9) + 0.4 * random_spins(9, 10 + seed)
        T = T / jnp.linalg.norm(T, axis=1, keepdims=True)
        assert float(jnp.min(jnp.sum(T * jnp.roll(T, 1, axis=0), axis=1))) > -0.5
        integrable = dg.lie_bracket(x_flow, hz.flow("integrable", -0.5))(T)
        naive = dg.lie_bracket(x_flow, hz.flow("naive", -0.5))(T)
        assert float(jnp.max(jnp.abs(integrable))) <= 1e-11
        assert float(jnp.max(jnp.abs(naive))) > 1e-2  # of order one: reported in the issue note


@pytest.mark.parametrize("kind", ["naive", "integrable"])
def test_gauss_integration_conserves_energy_total_spin_and_unit_length(kind):
    S0, J, t1 = smooth_spins(32), 1.0, 20.0
    H = hz.hamiltonian(kind, J)
    _, Ss = dg.integrate(hz.flow(kind, J), S0, t1, steps=2000)
    energies = jax.vmap(H)(Ss)
    assert float(jnp.max(jnp.abs(energies - energies[0]))) <= 1e-9
    assert float(jnp.max(jnp.abs(Ss.sum(axis=1) - S0.sum(axis=0)))) <= 1e-9
    assert float(jnp.max(jnp.abs(jnp.linalg.norm(Ss, axis=-1) - 1))) <= 1e-12
    assert float(jnp.max(jnp.abs(Ss[-1] - S0))) > 0.1  # it did move


def spin_wave(N, t, J, theta=0.7, k=2):
    """Exact solution of ∂_t S = J S × S'' on the circle: precession with ω = J k² cos θ."""
    x = 2 * np.pi * np.arange(N) / N
    phase = k * x - J * k**2 * np.cos(theta) * t
    return np.stack([np.sin(theta) * np.cos(phase), np.sin(theta) * np.sin(phase), np.cos(theta) + 0 * x], 1)


@pytest.mark.parametrize("kind", ["naive", "integrable"])
def test_smooth_limit_spin_wave_second_order(kind):
    """Flow of H/ε with time rescaled by 1/ε → ∂_t S = J S × S'' (A.3): O(ε²) at t = 1."""
    J, Ns = 1.0, [16, 32, 64, 128]
    errors = []
    for N in Ns:
        f = hz.scaled_flow(kind, J, 2 * np.pi / N)
        _, Ss = dg.integrate(f, jnp.asarray(spin_wave(N, 0.0, J)), 1.0, steps=N * N // 2)
        errors.append(np.max(np.abs(np.asarray(Ss[-1]) - spin_wave(N, 1.0, J))))
    table = dg.limits.ConvergenceTable.from_errors(Ns, errors)
    assert abs(table.fitted_order - 2) <= 0.15


@pytest.mark.parametrize("kind", ["naive", "integrable"])
def test_scaled_hamiltonian_converges_to_dirichlet_energy(kind):
    """(H − H_aligned)/ε → (J/2)∫|S'|² dx for a smooth periodic spin field."""
    J = 1.5
    fine = 4096
    S = np.asarray(smooth_spins(fine))
    dS = (np.roll(S, -1, 0) - np.roll(S, 1, 0)) / (2 * (2 * np.pi / fine))  # spectral-accurate enough
    exact = 0.5 * J * np.sum(dS**2) * (2 * np.pi / fine)
    Ns = [16, 32, 64, 128]
    errors = [abs(float(hz.scaled_hamiltonian(kind, J, 2 * np.pi / N)(smooth_spins(N))) - exact) for N in Ns]
    table = dg.limits.ConvergenceTable.from_errors(Ns, errors)
    assert table.fitted_order >= 1.8


def test_bad_input():
    with pytest.raises(InvalidInputError, match="J must be finite and non-zero"):
        hz.hamiltonian("naive", 0.0)
    with pytest.raises(InvalidInputError, match="closed"):
        hz.hamiltonian("naive", 1.0, closed=False)
    with pytest.raises(InvalidInputError, match="kind"):
        hz.hamiltonian("xy", 1.0)
    S = np.asarray(random_spins(6, 3)).copy()
    S[2] *= 1.01
    with pytest.raises(hz.NonUnitSpinError, match="spin 2 has length"):
        hz.hamiltonian("naive")(S)
    S[2, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"index \(2, 1\)"):
        hz.flow("integrable")(S)


def test_spin_chain_pictures(tmp_path):
    """A travelling spin wave: PNG frames and an animated GIF."""
    ts, Ss = dg.integrate(hz.flow("integrable", 1.0), jnp.asarray(spin_wave(24, 0.0, 1.0)), 2.0, steps=40)
    png = dg.plot.spin_chain(Ss[0], path=tmp_path / "frame0.png")
    gif = dg.plot.animate_spin_chain(np.asarray(Ss[::8]), tmp_path / "wave.gif", times=np.asarray(ts[::8]))
    assert png.stat().st_size > 2000 and gif.stat().st_size > 2000
    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
