"""Soap bubbles and liquid bridges: the area with a prescribed enclosed volume
(`energies.area.with_volume`), whose multiplier is the pressure p = κ1 + κ2 of the Laplace–Young
law (Thm 6.7: the area gradient is the mean curvature normal).  A bubble of volume 4π/3 from a
perturbed icosphere has p → 2 (the unit sphere) at order 2; films between the unit circles at
z = ±1/2 holding more and more volume bulge from the cylinder (p = 1) into Delaunay surfaces of
revolution, compared with the smooth pressure by shooting.

    python examples/soap_bubble.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax.plot import save_figure
from ddgjax.plot.surface import surface
from ddgjax.verify.checks.ext_bubbles import (
    BRIDGE_H,
    SPHERE_VOLUME,
    bridge_start,
    liquid_bridge_pressure,
    sphere_start,
)
from energies import area
from solvers import solve


def bubbles(levels) -> tuple[dict, np.ndarray, np.ndarray]:
    """Solve the bubble of volume 4π/3 at each icosphere level: ({level: p}, V, F) of the finest."""
    pressures = {}
    for level in levels:
        V, F = sphere_start(level)
        sol = solve(area.with_volume(V, F, SPHERE_VOLUME), tol=1e-12)
        pressures[level] = float(sol.multipliers["volume"][0])
        print(f"bubble, level {level}: nv = {len(V):4d}, {int(sol.steps)} Newton steps, KKT residual "
              f"{float(sol.residual):.1e}, p = {pressures[level]:.10f}, |p·r − 2| = {abs(pressures[level] - 2):.2e}")
    return pressures, np.asarray(sol.x), F


def bridges(n: int, factors) -> list[tuple[float, float, float, np.ndarray]]:
    """The liquid bridges of `factors` × the cylinder's volume on the mesh `bridge_start(n)`, one
    declaration re-solved with other volumes (`with_params`), each started from the last:
    [(volume, p, p_smooth, V)]."""
    V, F = bridge_start(n)
    problem = area.with_volume(V, F, 2 * np.pi * BRIDGE_H)
    out = []
    for factor in factors:
        volume = factor * 2 * np.pi * BRIDGE_H
        sol = solve(problem.with_params({"volume": volume}), tol=1e-12)
        problem = problem.with_x0(sol.x)
        p, smooth = float(sol.multipliers["volume"][0]), liquid_bridge_pressure(BRIDGE_H, volume)
        print(f"bridge, n = {n}, volume {factor:.2f} × 2πH: p = {p:.8f}, smooth {smooth:.8f}, |p − p_smooth| = "
              f"{abs(p - smooth):.2e}")
        out.append((volume, p, smooth, np.asarray(sol.x)))
    return out


def profiles(solved, path):
    """Each bridge's vertices as (distance to the axis, z), labelled with its pressure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4.5, 3.5))
    for volume, p, smooth, V in solved:
        ax.plot(np.linalg.norm(V[:, :2], axis=1), V[:, 2], ".", ms=3,
                label=f"vol {volume:.3f}: p = {p:.4f} (smooth {smooth:.4f})")
    ax.set_xlabel("distance to the axis r")
    ax.set_ylabel("z")
    ax.set_title("liquid bridges (Laplace–Young)")
    ax.legend(fontsize=7)
    return save_figure(fig, path, dpi=120)


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    pressures, V, F = bubbles((1, 2) if tiny else (1, 2, 3, 4))
    table = dg.limits.convergence(lambda n: abs(pressures[int(np.log2(n))] - 2.0), [2**k for k in pressures],
                                  label="|p·r − 2| (n = 2^level)")
    print(table.to_markdown())
    solved = bridges(4 if tiny else 12, (1.0, 1.3) if tiny else (1.0, 1.1, 1.2, 1.3))
    return [surface(V, F, out / "soap_bubble.png", color_by="mean_curvature", label="mean curvature H(e)",
                    title=f"bubble of volume 4π/3: p = {pressures[max(pressures)]:.6f}"),
            profiles(solved, out / "liquid_bridges.png")]


if __name__ == "__main__":
    run(main, __doc__)
