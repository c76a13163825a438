"""Euclidean invariance and scaling of *solved* catalogue objects (hypothesis properties).

The discrete elastica (Def 3.2) is built from lengths and angles only, so for a rotation R and a
scale s > 0 the clamped elastica with chord R·s·c, length s·L and end tangents R·t is the solved
one rotated: `T ↦ R T`; its energy `(2/h) Σ log(1 + tan²(φ_k/2))` scales as 1/s (h = sL/n), so
by `∇E = Jᵀλ` with J ∝ h the chord load rotates and scales as `λ_chord ↦ R λ_chord / s²` and the
tensions as `λ_unit ↦ λ_unit / s`.  The simplicial area (Thm 6.7) of a rotated and scaled
minimal surface is `s²` times the area, its solution the moved one.

One declaration per object: the examples only change parameters and the fixed entries of x0,
so the compiled solver is shared; the rotation comes from a hypothesis-drawn seed.
Negative control: the property fails for a reflected start that is not a rotation of the data.
"""

import functools

import jax.numpy as jnp
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import ddgjax as dg
from energies import area, elastica
from solvers import solve

CHORD, T_START, T_END = np.array([0.5, 0.2, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
N = 16


def rotation(seed: int) -> np.ndarray:
    """A uniformly random rotation of R³ (QR of a Gaussian matrix, det +1)."""
    Q, R = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


def solved_elastica(R: np.ndarray, s: float):
    return solve(elastica.clamped(N, length=s, chord=s * R @ CHORD, t_start=R @ T_START, t_end=R @ T_END))


@functools.cache
def base():
    """The solved elastica with the data unmoved (solved on first use, not at collection)."""
    return solved_elastica(np.eye(3), 1.0)


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**31), log_s=st.floats(-3.0, 3.0))
def test_solved_elastica_is_rotation_and_scale_covariant(seed, log_s):
    R, s = rotation(seed), 10.0**log_s
    BASE = base()
    sol = solved_elastica(R, s)
    assert float(sol.residual) <= 1e-10
    np.testing.assert_allclose(np.asarray(sol.x), np.asarray(BASE.x) @ R.T, atol=1e-9)
    np.testing.assert_allclose(float(sol.energy) * s, float(BASE.energy), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(sol.multipliers["chord"]) * s**2, R @ np.asarray(BASE.multipliers["chord"]),
                               rtol=1e-8, atol=1e-8 * np.abs(BASE.multipliers["chord"]).max())
    np.testing.assert_allclose(np.asarray(sol.multipliers["unit"]) * s, np.asarray(BASE.multipliers["unit"]),
                               rtol=1e-8, atol=1e-8 * np.abs(BASE.multipliers["unit"]).max())


def test_negative_control_a_reflection_of_the_chord_alone_changes_the_solution():
    """Mirroring only the chord (not the end tangents) is not a symmetry: the check can fail."""
    M, BASE = np.diag([1.0, -1.0, 1.0]), base()
    sol = solve(elastica.clamped(N, chord=M @ CHORD, t_start=T_START, t_end=T_END))
    assert np.max(np.abs(np.asarray(sol.x) - np.asarray(BASE.x) @ M.T)) > 1e-3


V0, F, B = dg.mesh.saddle_grid(8, noise=0.0)


@functools.cache
def area_base():
    """The solved minimal surface with its boundary unmoved."""
    return solve(area.simplicial(V0, F, B))


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 2**31), log_s=st.floats(-2.0, 2.0), shift=st.floats(-10.0, 10.0))
def test_solved_minimal_surface_moves_with_its_boundary(seed, log_s, shift):
    R, s = rotation(seed), 10.0**log_s
    moved, AREA = s * V0 @ R.T + shift, area_base()
    sol = solve(area.simplicial(moved, F, B))
    assert float(sol.residual) <= 1e-10 * max(1.0, s)
    np.testing.assert_allclose(np.asarray(sol.x), s * np.asarray(AREA.x) @ R.T + shift,
                               atol=1e-9 * s * (1 + abs(shift) / s))
    np.testing.assert_allclose(float(sol.energy), s**2 * float(AREA.energy), rtol=1e-10)
    assert float(jnp.max(jnp.abs(jnp.asarray(AREA.x)))) > 0  # a genuine surface
