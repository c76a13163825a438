"""A double bubble: two chambers of prescribed volumes sharing a wall (`energies.area.with_volumes`,
the named constraint "volumes", whose multipliers are the chambers' pressures).  From the sampled
standard double bubble of two equal chambers (`dg.mesh.double_bubble`: caps of radius 1, a flat
wall) the solver moves to chambers of 1.2 and 0.8 × 9π/8: the caps and the wall become spheres
with 1/r_W = 1/r_B − 1/r_A (Hutchings, Morgan, Ritoré & Ros 2002) and the pressures 2/r
(Laplace–Young); the checks are `ddgjax verify --only double_bubble`.

    python examples/double_bubble.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax.plot.surface import surface
from ddgjax.verify.checks.ext_bubbles import DOUBLE_VOLUME, UNEQUAL, sphere_radius
from energies import area
from solvers import solve


def double_bubble(m: int, shares) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`(x, F, chambers, pressures)` of the double bubble with the volumes `shares` × 9π/8."""
    V, F, C = dg.mesh.double_bubble(m, m // 4, max(2, round(m / 6)))
    sol = solve(area.with_volumes(V, F, C, DOUBLE_VOLUME * np.asarray(shares)))
    p = np.asarray(sol.multipliers["volumes"])
    print(f"m = {m}, volumes {shares[0]:.1f} and {shares[1]:.1f} × 9π/8: {int(sol.steps)} Newton steps"
          f"{f' after {int(sol.first_order_steps)} L-BFGS steps' if int(sol.first_order_steps) else ''}, KKT residual "
          f"{float(sol.residual):.1e}, area {float(sol.energy):.8f}, pressures {p[0]:.8f}, {p[1]:.8f}")
    return np.asarray(sol.x), F, C, p


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    for m in (12, 16) if tiny else (12, 16, 24, 32):
        double_bubble(m, (1.0, 1.0))
        X, F, C, p = double_bubble(m, UNEQUAL)
        sheets = {"cap A": C[:, 1] == 0, "cap B": C[:, 0] == 0, "wall": (C[:, 0] != 0) & (C[:, 1] != 0)}
        r_a, r_b, r_w = (sphere_radius(X[np.unique(F[mask])]) for mask in sheets.values())
        print(f"    fitted radii r_A = {r_a:.6f}, r_B = {r_b:.6f}, r_W = {r_w:.6f}: 1/r_W − (1/r_B − 1/r_A) = "
              f"{1 / r_w - 1 / r_b + 1 / r_a:.2e}; p_A r_A/2 = {p[0] * r_a / 2:.6f}, p_B r_B/2 = {p[1] * r_b / 2:.6f}")
    sheet = np.where(C[:, 1] == 0, 1.0, np.where(C[:, 0] == 0, -1.0, 0.0))
    return surface(X, F, out / "double_bubble.png", color_by=sheet, label="cap A (+1), wall (0), cap B (−1)",
                   title=f"double bubble {UNEQUAL[0]} : {UNEQUAL[1]}, p = {p[0]:.3f}, {p[1]:.3f}")


if __name__ == "__main__":
    run(main, __doc__)
