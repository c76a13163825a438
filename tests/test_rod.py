"""Discrete isotropic elastic rods (Def 3.6, 3.7): quaternion edge frames, bending + twist."""

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


def test_untwisted_planar_rod_is_the_elastica():
    """With end frames that differ by no twist, the rod's centreline is the discrete elastica."""
    n = 40
    sol = solve(rod.clamped(n, alpha=0.7, chord=[0.6, 0, 0], frame_start=START, frame_end=END))
    assert float(sol.residual) <= 1e-10
    assert float(jnp.max(jnp.abs(rod.twist_angles(sol.x)))) <= 1e-12
    curve = solve(elastica.clamped(n, chord=[0.6, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0]))
    assert float(jnp.max(jnp.abs(rod.tangents(sol.x) - curve.x))) <= 1e-10


@pytest.mark.parametrize("twist", [1.0, 2.5])
def test_twisted_rod_has_constant_twist(twist):
    """Discrete analogue of Lemma 3.12 (τ' = 0): all twist angles θ_k equal at a critical rod,
    and the twisted rod leaves the plane of its untwisted elastica."""
    n = 40
    end = qt.mul(qt.from_axis_angle(-E2, twist), END)  # twist the end frame about its tangent −e2
    sol = solve(rod.clamped(n, alpha=0.7, chord=[0.6, 0, 0], frame_start=START, frame_end=end))
    assert float(sol.residual) <= 1e-10
    theta = np.asarray(rod.twist_angles(sol.x))
    assert np.max(np.abs(theta - theta[0])) <= 1e-10
    assert abs(theta[0]) > 1e-3
    assert float(jnp.max(jnp.abs(rod.tangents(sol.x)[:, 2]))) > 1e-3  # non-planar centreline


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


def _cross_matrix(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def test_def_3_7_combined_flow_is_a_euclidean_motion():
    """Issue item 5(e): at a solved twisted rod, (∂_t + c ∂_x) γ_k = a × γ_k + b at every interior
    vertex (∂_t: Heisenberg flow, ∂_x: tangent flow) for one (a, b, c), c ≠ 0: it holds exactly
    (to round-off) at every n, not only in the limit."""
    import ddgjax as dg

    n = 40
    end = qt.mul(qt.from_axis_angle(-E2, 2.0), END)
    sol = solve(rod.clamped(n, alpha=0.7, chord=[0.6, 0, 0], frame_start=START, frame_end=end))
    gamma = np.asarray(dg.curves.from_tangents(rod.tangents(sol.x), edge_length=1.0 / n))
    w = np.asarray(dg.curves.heisenberg_flow(gamma, closed=False))[1:-1]
    v = np.asarray(dg.curves.tangent_flow(gamma, closed=False))[1:-1]
    A = np.vstack([np.hstack([-_cross_matrix(g), np.eye(3), -vk[:, None]]) for g, vk in zip(gamma[1:-1], v)])
    abc = np.linalg.lstsq(A, w.ravel(), rcond=None)[0]
    assert np.max(np.abs(A @ abc - w.ravel())) <= 1e-10 * np.max(np.abs(w))
    assert abs(abc[-1]) > 1e-3  # c ≠ 0: a genuine combination with the tangent flow
