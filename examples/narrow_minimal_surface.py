"""Minimal surfaces in the narrow sense (Def 7.9, Fig 7.23, Fig 7.26): a tall dome over the unit
circle, triangulated with long skinny triangles unsuited to its minimal surface (the flat disk).
The cotan iteration of Fig 6.5 stalls (or breaks down on a degenerate iterate); Fig 7.23, which
flips to the intrinsic Delaunay triangulation and solves with the Laplace–Beltrami operator
before each step, converges in a few steps to a Delaunay surface with Δf = 0, every vertex in the
convex hull of its neighbours (Remark 7.10).

    python examples/narrow_minimal_surface.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

from ddgjax import intrinsic
from ddgjax.verify import figures


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    m = 16 if tiny else 32
    V, F, _, cotan, narrow = figures.fig_7_26(0, budget=30, n_inner=50 if tiny else 150, m=m)
    for name, (_, _, info) in (("Fig 6.5  (cotan Laplacian)", cotan), ("Fig 7.23 (Delaunay flips)", narrow)):
        state = "converged" if info["converged"] else "out of budget" if info["iterations"] == 30 else "broke down"
        print(f"{name}: {state:13s} after {info['iterations']:2d} steps, residual {info['residual']:.2e}, "
              f"{int(info['flips'].sum()):4d} flips, area {info['area'][-1]:.10f}")
    polygon = 0.5 * m * np.sin(2 * np.pi / m)
    tri = narrow[2]["triangulation"]
    print(f"the flat {m}-gon has area {polygon:.10f}; the result is Delaunay: {intrinsic.is_delaunay(tri)}, "
          f"min Laplace–Beltrami weight {intrinsic.cotan_weights(tri).min():+.2e}")
    return figures.draw_fig_7_26(out / "narrow_minimal_surface.png", V, F, cotan, narrow)


if __name__ == "__main__":
    run(main, __doc__)
