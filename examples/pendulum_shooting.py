"""The Kirchhoff analogy (Thm 3.10): the tangents of a discrete elastica are a trajectory of the
discrete spherical pendulum with gravity (h²/2)λ; shooting from T_0, T_1 with the Lagrangian
map reproduces the elastica, a slightly wrong gravity does not.

    python examples/pendulum_shooting.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from energies import elastica, pendulum
from solvers import solve


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    n = 16 if tiny else 60
    problem = elastica.clamped(n, chord=[0.5, 0.3, 0.2], t_start=[0.0, 1.0, 0.3], t_end=[0.2, -1.0, 0.5])
    sol = solve(problem)
    T, gravity = np.asarray(sol.x), np.asarray(elastica.pendulum_gravity(sol, problem))
    curves = []
    for scale in (1.0, 1.05):
        shot = np.asarray(pendulum.shoot(T[0], T[1], scale * gravity, n))
        print(f"gravity × {scale}: max |T_shot − T_elastica| = {np.max(np.abs(shot - T)):.2e}")
        curves.append(np.asarray(dg.curves.from_tangents(shot, edge_length=1.0 / n)))
    curves.insert(0, np.asarray(elastica.curve(sol.x, problem)))
    return dg.plot.curves(curves, labels=["elastica", "shot, gravity (h²/2)λ", "shot, 1.05 × gravity"],
                          path=out / "pendulum_shooting.png")


if __name__ == "__main__":
    run(main, __doc__)
