"""Discrete elastica: bad input.  The statements (Def 3.2, Thm 3.8, Cor 3.9, Remark 3.7, the smooth
limits) are `ddgjax verify` checks (`sec3_elastica`, run by `test_verify_checks.py`)."""

import numpy as np
import pytest

from ddgjax.errors import InvalidInputError, NonFiniteError
from energies import elastica


def test_bad_input():
    with pytest.raises(elastica.InfeasibleChordError, match="not shorter than the length"):
        elastica.clamped(10, length=1.0, chord=[1.2, 0, 0], t_start=[1, 0, 0], t_end=[1, 0, 0])
    T = np.tile([1.0, 0.0, 0.0], (10, 1))
    T[4, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"index \(4, 1\)"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0], x0=T)
    with pytest.raises(InvalidInputError, match="clamp"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0], clamp="free")
    with pytest.raises(InvalidInputError, match="t_start"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 0, 0], t_end=[0, -1, 0])


def test_euler_column_is_straight_and_critical_for_every_load():
    """`elastica.loaded`: the straight column T_k = d solves the KKT system at any load, with unit
    multipliers P h/2 (P h d = 2λ_k d) and no lateral force; the chord is free (its length along
    d is the load's conjugate), so a buckled start under a load above 4π² does not come back to
    the straight column (negative control: the straight column is not the only critical point)."""
    import jax.numpy as jnp

    from solvers import stability, solve

    d = np.array([0.0, 0.6, 0.8])
    problem = elastica.loaded(12, load=25.0, direction=d, clamp="edge")
    sol = solve(problem)
    h = 1.0 / 12
    assert float(sol.residual) <= 1e-12 and np.max(np.abs(np.asarray(sol.x) - d)) <= 1e-14
    np.testing.assert_allclose(np.asarray(sol.multipliers["unit"]), 25.0 * h / 2, rtol=1e-12)
    assert np.max(np.abs(np.asarray(sol.multipliers["lateral"]))) <= 1e-12
    column = elastica.loaded(12, load=60.0)
    theta = np.sin(2 * np.pi * (np.arange(12) + 0.5) / 12)
    start = np.stack([np.cos(theta), np.sin(theta), np.zeros(12)], axis=1)
    straight = solve(column)
    assert stability(column, straight).index == 2
    buckled = solve(column.with_x0(jnp.asarray(start)))
    assert bool(buckled.converged) and np.max(np.abs(np.asarray(buckled.x)[:, 1])) > 0.1
    assert float(buckled.energy) < float(straight.energy) - 1.0


def test_euler_column_bad_input():
    with pytest.raises(InvalidInputError, match="direction"):
        elastica.loaded(10, direction=[0, 0, 0])
    with pytest.raises(InvalidInputError, match="load"):
        elastica.loaded(10, load=float("nan"))
    with pytest.raises(InvalidInputError, match="clamp"):
        elastica.loaded(10, clamp="free")
    with pytest.raises(InvalidInputError, match="n"):
        elastica.loaded(2)
