"""The Heisenberg magnet chain (Appendix A, Remark A.1, eq 2.14): the chain on tangents, bad input,
pictures.  The equations of motion, commutation, conservation and smooth limits are `ddgjax verify`
checks (`secA_heisenberg`)."""

import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import InvalidInputError, NonFiniteError
from ddgjax.verify.checks.secA_heisenberg import spin_wave
from energies import heisenberg as hz


def random_spins(N, seed):
    S = np.random.default_rng(seed).normal(size=(N, 3))
    return jnp.asarray(S / np.linalg.norm(S, axis=1, keepdims=True))


def test_integrable_chain_on_tangents_is_the_discrete_heisenberg_flow_2_14():
    """With J = −½ and S = T: ∂_t T_k = (T_{k+1}/(1+<T_{k+1},T_k>) + T_{k−1}/(1+<T_k,T_{k−1}>)) × T_k."""
    T = random_spins(10, 1)
    up, down = jnp.roll(T, -1, axis=0), jnp.roll(T, 1, axis=0)
    eq_2_14 = jnp.cross(up / (1 + jnp.sum(up * T, 1))[:, None] + down / (1 + jnp.sum(T * down, 1))[:, None], T)
    assert float(jnp.max(jnp.abs(hz.flow("integrable", -0.5)(T) - eq_2_14))) <= 1e-12


def test_bad_input():
    with pytest.raises(InvalidInputError, match="J must be finite and non-zero"):
        hz.hamiltonian("naive", 0.0)
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
    """A travelling spin wave: the frame shows one arrow per spin on the unit ring; an animated GIF."""
    ts, Ss = dg.integrate(hz.flow("integrable", 1.0), jnp.asarray(spin_wave(24, 0.0, 1.0)), 2.0, steps=40)
    fig = dg.plot.spin_chain(Ss[0])
    fig.canvas.draw()  # 3-D artists get their projected segments when drawn
    ax = fig.axes[0]
    (ring,) = ax.lines
    np.testing.assert_allclose(np.hypot(*ring.get_data_3d()[:2]), 1.0, atol=1e-12)
    (arrows,) = ax.collections
    assert len(arrows.get_segments()) == 3 * 24  # shaft and two barbs per spin
    gif = dg.plot.animate_spin_chain(np.asarray(Ss[::8]), tmp_path / "wave.gif", times=np.asarray(ts[::8]))
    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
