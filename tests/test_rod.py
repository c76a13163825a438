"""Discrete elastic rods (Def 3.6, 3.7, Remark 3.16): bad input, the uniform helix, the anisotropic
bending energy.  Lemma 3.12, Def 3.6, 3.7, Cor 3.14 and Remark 3.16 at solved rods are `ddgjax
verify` checks (`sec3_rods`)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax import quaternion as qt
from ddgjax.errors import InvalidInputError, NonFiniteError, ShapeError
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


def _twisted(n, **options):
    end = qt.mul(qt.from_axis_angle(-E2, 2.5), END)
    return rod.clamped(n, **{"alpha": 0.7, **options}, chord=[0.6, 0, 0], frame_start=START, frame_end=end)


def test_remark_3_16_default_rod_is_isotropic_and_unchanged():
    """Without `bending` the energy is the isotropic one of the module docstring,
    `(2/h) Σ E_k + (α/2h) Σ θ_k²`, to round-off (and params carry no stiffnesses)."""
    problem = _twisted(12)
    assert "bending" not in problem.params
    x = jnp.asarray(problem.x0) + 0.05 * np.random.default_rng(3).normal(size=problem.x0.shape)
    x = x / jnp.linalg.norm(x, axis=1, keepdims=True)
    zero = {"unit": jnp.zeros(10), "chord": jnp.zeros(3)}
    h = 1.0 / 12
    expected = (2 / h) * elastica.bending_energy(rod.tangents(x)) + (0.7 / (2 * h)) * jnp.sum(rod.twist_angles(x) ** 2)
    assert abs(float(dg.lagrangian(problem)(x, zero, problem.params) - expected)) <= 1e-12 * float(expected)


def test_remark_3_16_equal_stiffnesses_are_the_isotropic_density():
    """`anisotropic_bending_density(Φ, Ψ, (β, β))` is β times the elastica's `bending_density`
    of the tangents, to round-off, on random frame pairs (β = 1: the isotropic rod)."""
    P = np.random.default_rng(1).normal(size=(200, 2, 4))
    P /= np.linalg.norm(P, axis=-1, keepdims=True)
    e1 = jnp.array([1.0, 0.0, 0.0])
    iso_of = jax.jit(jax.vmap(lambda p: elastica.bending_density(qt.rotate(p[0], e1), qt.rotate(p[1], e1))))
    iso = iso_of(jnp.asarray(P))
    aniso_of = jax.jit(jax.vmap(lambda p, b: rod.anisotropic_bending_density(p[0], p[1], b), in_axes=(0, None)))
    for beta in (1.0, 2.5):
        aniso = aniso_of(jnp.asarray(P), jnp.array([beta, beta]))
        assert float(jnp.max(jnp.abs(aniso - beta * iso) / jnp.maximum(1.0, beta * iso))) <= 1e-12


def test_remark_3_16_equal_stiffnesses_give_the_isotropic_rod():
    """bending = (1, 1): the rod's energy and its gradient agree with the isotropic rod's to
    1e-12 at perturbed frames (so the critical points agree; the solved rods are compared by
    the verify check `anisotropic_rod_equal_stiffnesses`)."""
    iso, aniso = _twisted(12), _twisted(12, bending=(1.0, 1.0))
    zero = {"unit": jnp.zeros(10), "chord": jnp.zeros(3)}
    x = jnp.asarray(iso.x0) + 0.05 * np.random.default_rng(2).normal(size=iso.x0.shape)
    (E_iso, g_iso), (E_aniso, g_aniso) = (
        jax.jit(jax.value_and_grad(lambda y, p=p: dg.lagrangian(p)(y, zero, p.params)))(x) for p in (iso, aniso)
    )
    assert abs(float(E_iso - E_aniso)) <= 1e-12 * abs(float(E_iso))
    assert float(jnp.max(jnp.abs(g_iso - g_aniso))) <= 1e-12 * float(jnp.max(jnp.abs(g_iso)))


def test_remark_3_16_gradient_is_finite_at_a_straight_vertex():
    """`log(1 + t)/t` is evaluated without 0/0: the density is smooth at φ = 0."""
    one = jnp.array([1.0, 0.0, 0.0, 0.0])
    density = lambda P: rod.anisotropic_bending_density(P[0], P[1], jnp.array([1.0, 3.0]))  # noqa: E731
    g = jax.jit(jax.grad(density))(jnp.stack([one, one]))
    assert np.all(np.isfinite(np.asarray(g)))


def test_remark_3_16_bad_bending_raises():
    for bad in ((1.0, 0.0), (-1.0, 2.0)):
        with pytest.raises(InvalidInputError, match="bending"):
            _twisted(10, bending=bad)
    for bad in ((np.nan, 1.0), (1.0, np.inf)):
        with pytest.raises(NonFiniteError, match="bending"):
            _twisted(10, bending=bad)
    with pytest.raises(ShapeError, match="bending"):
        _twisted(10, bending=(1.0, 2.0, 3.0))


def test_twisted_column_is_critical_with_uniform_twist():
    """`rod.loaded`: the straight column with the end twist ψ spread uniformly (θ_k = ψ/n at every
    vertex, the ghost vertices included) is critical at any twist and load: `solve` from it takes
    no step, and the lateral multipliers vanish.  A start off the column converges back to it
    below the critical twist (no other critical point nearby)."""
    problem = rod.loaded(12, alpha=1.3, twist=2.0, load=5.0)
    sol = solve(problem)
    assert int(sol.steps) == 0 and float(sol.residual) <= 1e-12
    np.testing.assert_allclose(np.asarray(rod.twist_angles(sol.x)), 2.0 / 12, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(rod.tangents(sol.x)), np.tile([1.0, 0.0, 0.0], (12, 1)), atol=1e-14)
    assert np.max(np.abs(np.asarray(sol.multipliers["lateral"]))) <= 1e-12
    kicked = np.asarray(problem.x0) + 0.02 * np.random.default_rng(0).normal(size=(12, 4))
    back = solve(problem.with_x0(jnp.asarray(kicked / np.linalg.norm(kicked, axis=1, keepdims=True))))
    np.testing.assert_allclose(np.asarray(rod.tangents(back.x)), np.tile([1.0, 0.0, 0.0], (12, 1)), atol=1e-9)


def test_twisted_column_bad_input():
    with pytest.raises(InvalidInputError, match="twist"):
        rod.loaded(10, alpha=1.0, twist=float("nan"))
    with pytest.raises(InvalidInputError, match="load"):
        rod.loaded(10, alpha=1.0, load=float("inf"))
    with pytest.raises(InvalidInputError, match="alpha"):
        rod.loaded(10, alpha=0.0)
    with pytest.raises(InvalidInputError, match="n"):
        rod.loaded(2, alpha=1.0)
