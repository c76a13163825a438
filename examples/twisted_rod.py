"""Discrete elastic rods (Def 3.6, 3.7): clamped rods whose end frame is twisted further and
further about its tangent; the twist angles stay constant along each rod (Lemma 3.12) and the
centreline leaves the plane.

    python examples/twisted_rod.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax import quaternion as qt
from energies import rod
from solvers import solve

E2, E3 = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    n = 12 if tiny else 60
    start, end = qt.from_axis_angle(E3, np.pi / 2), qt.from_axis_angle(E3, -np.pi / 2)  # tangents e2, −e2
    centrelines, Phi = [], None
    for twist in (0.0, 1.5, 3.0):
        frame_end = qt.mul(qt.from_axis_angle(-E2, twist), end)  # turn the end frame about its tangent −e2
        sol = solve(rod.clamped(n, alpha=0.7, chord=[0.6, 0, 0], frame_start=start, frame_end=frame_end, x0=Phi))
        Phi = np.asarray(sol.x)
        theta = np.asarray(rod.twist_angles(sol.x))
        print(f"end twist {twist}: θ_k = {theta[0]:.6f} (spread {np.ptp(theta):.1e}), energy {float(sol.energy):.5f}")
        centrelines.append(np.asarray(dg.curves.from_tangents(rod.tangents(sol.x), edge_length=1.0 / n)))
    return dg.plot.curves(centrelines, labels=["twist 0", "twist 1.5", "twist 3"], path=out / "twisted_rod.png")


if __name__ == "__main__":
    run(main, __doc__)
