"""Clamped discrete elastica (Def 3.2, Thm 3.8) at decreasing chord, and Euler's figure-eight, a
closed elastica (Remark 3.2, 3.7), found from the exact one's tangents.

    python examples/elastica_family.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax.smooth import elastica as exact
from energies import elastica
from solvers import solve


def family(n: int, out):
    curves, T = [], None
    for chord in (0.8, 0.6, 0.4, 0.2):  # continuation: each solution starts the next
        problem = elastica.clamped(n, chord=[chord, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0], x0=T)
        sol = solve(problem)
        T = np.asarray(sol.x)
        print(f"chord {chord}: energy {float(sol.energy):9.5f}, load λ = {np.asarray(elastica.load(sol)).round(4)}")
        curves.append(np.asarray(elastica.curve(sol.x, problem))[:, :2])
    return dg.plot.curves(curves, labels=["0.8", "0.6", "0.4", "0.2"], path=out / "elastica_family.png")


def figure_eight(n: int, out):
    eight = exact.figure_eight(lam=exact.figure_eight(lam=1.0).period)  # rescaled to length 1
    start = eight.tangent((np.arange(n) + 0.5) / n)
    problem = elastica.closed(n, x0=start)
    sol = solve(problem)
    print(f"figure-eight, n = {n}: energy {float(sol.energy):.6f}, exact ½∫κ² = {0.5 * eight.bending_energy():.6f}")
    gamma = np.asarray(elastica.curve(sol.x, problem))
    return dg.plot.curve(gamma[:, :2], path=out / "figure_eight.png", color="k")


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    return [family(16 if tiny else 100, out), figure_eight(24 if tiny else 96, out)]


if __name__ == "__main__":
    run(main, __doc__)
