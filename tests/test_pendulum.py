"""The discrete spherical pendulum and the Kirchhoff analogy (Def 3.3, Thm 3.10)."""

import numpy as np

import ddgjax as dg
from energies import elastica, pendulum
from solvers import solve


def test_thm_3_10_shooting_reproduces_an_elastica():
    """Elastica → pendulum: iterate the Lagrangian map from T_0, T_1 with gravity (h²/2)λ."""
    n = 30
    problem = elastica.clamped(n, chord=[0.5, 0.3, 0.2], t_start=[0.0, 1.0, 0.3], t_end=[0.2, -1.0, 0.5])
    sol = solve(problem)
    T = np.asarray(sol.x)
    a = elastica.pendulum_gravity(sol, problem)
    shot = np.asarray(pendulum.shoot(T[0], T[1], a, n))
    assert np.max(np.abs(shot - T)) <= 1e-9
    # the wrong gravity does not reproduce it
    assert np.max(np.abs(np.asarray(pendulum.shoot(T[0], T[1], 1.1 * a, n)) - T)) > 1e-4


def test_thm_3_10_pendulum_trajectory_is_an_elastica():
    """Pendulum → elastica: a critical point of the action satisfies Thm 3.8 with a = gravity
    (unit edges), and is reproduced by the Lagrangian map."""
    n, a = 25, np.array([0.02, -0.05, 0.01])
    problem = pendulum.action(n, a=a, T_first=[1.0, 0.2, 0.0], T_last=[-0.2, 1.0, 0.4])
    sol = solve(problem)
    assert float(sol.residual) <= 1e-10
    T = np.asarray(sol.x)
    gamma = np.asarray(dg.curves.from_tangents(T))
    W = np.cross(T[1:], T[:-1]) / (1 + np.sum(T[1:] * T[:-1], axis=1))[:, None]
    b = W - np.cross(a, gamma[1:-1])
    assert np.max(np.abs(b - b[0])) <= 1e-10
    assert np.max(np.abs(np.asarray(pendulum.shoot(T[0], T[1], a, n)) - T)) <= 1e-9
