"""A red blood cell as a Helfrich vesicle (`energies.willmore.vesicle_of_revolution`; Canham 1970,
Helfrich 1973, Seifert–Berndl–Lipowsky 1991): the bending energy W = ∫H² dA of a closed surface
of revolution at fixed area and enclosed volume, with reduced volume v = Vol / (4π/3 (A/4π)^{3/2})
= 0.6.  From an oblate spheroid Newton finds the biconcave discocyte, thinner on the axis than at
its rim, a minimum (`solvers.stability`).  Drawn: the cell coloured by its mean curvature and
its cross-section (start and solution).

    python examples/red_blood_cell.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

from ddgjax.plot import save_figure
from ddgjax.plot.surface import surface
from energies import willmore
from solvers import solve, stability


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    m, n = (32, 16) if tiny else (96, 48)
    problem = willmore.vesicle_of_revolution(m, n, reduced_volume=0.6)
    sol = solve(problem)
    P = np.asarray(sol.x)
    index = stability(problem, sol).index
    mid = 0.5 * (P[0, 1] + P[-1, 1])
    on_axis, largest = P[0, 1] - P[-1, 1], 2 * (P[:, 1].max() - mid)
    print(f"m = {m}, n = {n}: {int(sol.steps)} Newton steps, residual {float(sol.residual):.1e}, "
          f"W/4π = {float(sol.energy) / (4 * np.pi):.6f}, stability index {index}; thickness on the axis "
          f"{on_axis:.4f}, largest {largest:.4f} (biconcave), diameter {2 * P[:, 0].max():.4f}")
    V, F = willmore.revolve_vesicle(P, m)
    H, _ = willmore.mean_curvature(V, F)
    cell = surface(V, F, out / "red_blood_cell.png", color_by=H[F].mean(axis=1), label="mean curvature H",
                   title=f"v = 0.6: W/4π = {float(sol.energy) / (4 * np.pi):.4f}")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3))
    for Q, style, label in ((np.asarray(problem.x0), "--", "start (oblate spheroid)"), (P, "-", "discocyte")):
        full = np.vstack([Q, (Q * [-1, 1])[::-1]])  # the profile and its mirror image across the axis
        ax.plot(full[:, 0], full[:, 1], style, label=label)
    ax.set(xlabel="ρ", ylabel="z", aspect="equal", title="cross-section through the axis")
    ax.legend(fontsize=8)
    return [cell, save_figure(fig, out / "red_blood_cell_section.png")]


if __name__ == "__main__":
    run(main, __doc__)
