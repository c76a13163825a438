"""The Clifford torus as the Willmore torus of revolution (`energies.willmore.torus_of_revolution`;
Willmore 1965, Langer–Singer 1984, Marques–Neves 2014).  Among tori, W = ∫H² dA ≥ 2π², with
equality for the Clifford torus, the torus of revolution of a circle of radius r about ρ = R with
R/r = √2.  Declared as the Helfrich energy of an equilateral profile polygon revolved into
m = 2n meridians and solved from R/r = 2.5, the discrete minimiser has R/r → √2 and W → 2π² at
order 2 in 1/n; it is a minimum (`solvers.stability`).  Drawn: the torus coloured by its mean
curvature, and the profiles from the start to the solution.

    python examples/clifford_torus.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax.plot import save_figure
from ddgjax.plot.surface import surface
from energies import willmore
from solvers import solve, stability


def ratio_of(P: np.ndarray) -> float:
    """R/r of a profile: the centroid's distance to the axis over the mean distance to the centroid."""
    centre = P.mean(axis=0)
    return float(centre[0] / np.mean(np.linalg.norm(P - centre, axis=1)))


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    results = {}
    for n in (12, 16, 24) if tiny else (12, 16, 24, 32, 48):
        problem = willmore.torus_of_revolution(2 * n, n, ratio=2.5)
        sol = solve(problem)
        P = np.asarray(sol.x)
        results[n] = (problem, sol, P)
        print(f"n = {n:3d}, m = {2 * n:3d}: {int(sol.steps)} Newton steps, residual {float(sol.residual):.1e}, "
              f"W/2π² = {float(sol.energy) / (2 * np.pi**2):.8f}, R/r = {ratio_of(P):.8f} (√2 = {np.sqrt(2):.8f})")
    table = dg.limits.convergence(lambda n: abs(float(results[n][1].energy) / (2 * np.pi**2) - 1), sorted(results),
                                  label="|W/2π² − 1| (n profile points)")
    print(table.to_markdown())
    n = max(results)
    problem, sol, P = results[n]
    print(f"stability index at n = {n}: {stability(problem, sol).index} (a minimum)")

    V, F = dg.mesh.torus(2 * n, n)
    V = np.asarray(willmore.revolve(P, 2 * n))
    H, _ = willmore.mean_curvature(V, F)
    torus = surface(V, F, out / "clifford_torus.png", color_by=H[F].mean(axis=1), label="mean curvature H",
                    title=f"W/2π² = {float(sol.energy) / (2 * np.pi**2):.5f}, R/r = {ratio_of(P):.5f}")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 4))
    for P_, style, label in ((np.asarray(problem.x0), "--", "start, R/r = 2.5"), (P, "-o", f"solution, n = {n}")):
        closed = np.vstack([P_, P_[:1]])
        ax.plot(closed[:, 0], closed[:, 1], style, ms=3, label=label)
    ax.axvline(0.0, color="0.6", lw=0.8)
    ax.set(xlabel="ρ (distance to the axis)", ylabel="z", aspect="equal", title="profiles of the torus of revolution")
    ax.legend(fontsize=8)
    return [torus, save_figure(fig, out / "clifford_profiles.png"), table.plot(out / "clifford_convergence.png",
                                                                           title="Willmore tori of revolution → 2π²")]


if __name__ == "__main__":
    run(main, __doc__)
