"""The Kirchhoff analogy: the discrete spherical pendulum (Def 3.3, Thm 3.10)."""

from __future__ import annotations

import numpy as np

import ddgjax as dg
from ddgjax.verify import check
from energies import elastica, pendulum
from solvers import solve

from ._shared import space_elastica, thm_3_8_spread

GROUP = "clamped elastica"  # share the solved elastica of _shared (one compilation per size)


def _shot_error(n: int, scale: float) -> float:
    problem, sol = space_elastica(n, "edge")
    T = np.asarray(sol.x)
    gravity = scale * np.asarray(elastica.pendulum_gravity(sol, problem))
    return float(np.max(np.abs(np.asarray(pendulum.shoot(T[0], T[1], gravity, n)) - T)))


@check("Thm 3.10", "iterating the pendulum's Lagrangian map with gravity (h²/2)λ from T_0, T_1 reproduces the elastica",
       quantity="max_k |T_k(shot) − T_k(elastica)|", at_most=1e-9, quick=dict(n=32), full=dict(n=128))
def pendulum_shooting_reproduces_elastica(ctx, n):
    return _shot_error(n, 1.0)


@check("Thm 3.10", "negative control: shooting with 1.1 times that gravity does not",
       quantity="max_k |T_k(shot) − T_k(elastica)|", at_least=1e-4, quick=dict(n=32), full=dict(n=128))
def pendulum_wrong_gravity_fails(ctx, n):
    return _shot_error(n, 1.1)


@check("Thm 3.10, Def 3.3", "a critical point of the pendulum action satisfies Thm 3.8 with a = gravity (unit edges), "
       "and the Lagrangian map from T_0, T_1 reproduces it",
       quantity="max_k |b_k − b_1| + max_k |T_k(shot) − T_k|", at_most=1e-9, quick=dict(n=32), full=dict(n=128))
def pendulum_trajectory_is_elastica(ctx, n):
    a = np.array([0.02, -0.05, 0.01]) * (25 / n) ** 2
    sol = solve(pendulum.action(n, a=a, T_first=[1.0, 0.2, 0.0], T_last=[-0.2, 1.0, 0.4]))
    T = np.asarray(sol.x)
    gamma = np.asarray(dg.curves.from_tangents(T))
    shot = np.asarray(pendulum.shoot(T[0], T[1], a, n))
    return thm_3_8_spread(T, gamma, a) + float(np.max(np.abs(shot - T)))
