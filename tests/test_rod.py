"""Discrete isotropic elastic rods (Def 3.6, 3.7): bad input, the uniform helix.  Lemma 3.12, Def 3.6
and Def 3.7 at solved rods are `ddgjax verify` checks (`sec3_rods`)."""

import jax.numpy as jnp
import numpy as np
import pytest

from ddgjax import quaternion as qt
from ddgjax.errors import InvalidInputError
from energies import elastica, rod
from solvers import solve

E2, E3 = jnp.array([0.0, 1.0, 0.0]), jnp.array([0.0, 0.0, 1.0])
START = qt.from_axis_angle(E3, np.pi / 2)  # tangent e1 -> e2
END = qt.from_axis_angle(E3, -np.pi / 2)  # tangent e1 -> -e2


def test_bad_input():
    for alpha in (-1.0, 0.0):
        with pytest.raises(InvalidInputError, match="alpha"):
            rod.clamped(10, alpha=alpha, chord=[0.6, 0, 0], frame_start=START, frame_end=END)
    with pytest.raises(elastica.InfeasibleChordError):
        rod.clamped(10, alpha=1.0, chord=[1.5, 0, 0], frame_start=START, frame_end=END)
    with pytest.raises(InvalidInputError):
        rod.clamped(10, alpha=1.0, chord=[0.6, 0, 0], frame_start=2 * START, frame_end=END)
    with pytest.raises(InvalidInputError, match="NaN|finite"):
        rod.clamped(10, alpha=1.0, chord=[0.6, 0, 0], frame_start=START * np.nan, frame_end=END)
    with pytest.raises(InvalidInputError, match="clamp"):
        rod.clamped(10, alpha=1.0, chord=[0.6, 0, 0], frame_start=START, frame_end=END, clamp="middle")
    # end frames whose tangents disagree with the clamped tangents name the end
    with pytest.raises(rod.ClampMismatchError, match="frame_end"):
        rod.clamped(10, alpha=1.0, chord=[0.6, 0, 0], frame_start=START, frame_end=END, t_start=[0, 1, 0], t_end=[0, 1, 0])
    rod.clamped(10, alpha=1.0, chord=[0.6, 0, 0], frame_start=START, frame_end=END, t_start=[0, 1, 0], t_end=[0, -1, 0])


def test_uniform_helix_with_matching_end_frames_is_a_critical_point():
    """Issue item 5(c): frames Φ_k = R_z(kφ) Φ_0 R_{e1}(kψ) (a screw motion) make a discrete helix
    with constant bending and twist; clamped with its own end frames and chord, it is already a
    critical point: the KKT residual with least-squares multipliers is at round-off."""
    n, beta, phi, psi = 30, 0.5, 0.25, 0.1
    T0 = jnp.array([np.sin(beta), 0.0, np.cos(beta)])
    e1 = jnp.array([1.0, 0.0, 0.0])
    Phi0 = qt.mul(qt.from_axis_angle(jnp.cross(e1, T0), np.arccos(float(T0[0]))), qt.from_axis_angle(e1, 0.3))
    Phis = jnp.stack([qt.mul(qt.mul(qt.from_axis_angle(E3, k * phi), Phi0), qt.from_axis_angle(e1, k * psi))
                      for k in range(n)])
    chord = np.asarray(rod.tangents(Phis)).sum(axis=0) / n
    problem = rod.clamped(n, alpha=0.7, chord=chord, frame_start=Phis[0], frame_end=Phis[-1], x0=np.asarray(Phis))
    sol = solve(problem, max_steps=0)  # converged without a single step
    assert float(sol.residual) <= 1e-10
    theta = np.asarray(rod.twist_angles(Phis))
    assert np.max(np.abs(theta - theta[0])) <= 1e-12 and abs(theta[0]) > 0.1
