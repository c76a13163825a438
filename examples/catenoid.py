"""The catenoid as a simplicial minimal surface (Fig 6.5, Thm 6.7): the Pinkall–Polthier
iteration from a cylinder between two coaxial circles of radius R = 1 at z = ±H = ±0.5, compared
with the smooth catenoid r(z) = c cosh(z/c), c cosh(H/c) = R.  The neck radius converges O(h²).

    python examples/catenoid.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax.plot import laplace as plot_laplace
from ddgjax.plot import save_figure
from ddgjax.verify import references
from energies import area


def profile(V, c: float, path):
    """The vertices' distance to the axis against z, and the smooth catenoid c cosh(z/c)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    z = np.linspace(V[:, 2].min(), V[:, 2].max(), 200)
    fig, ax = plt.subplots(figsize=(4.5, 3.5))
    ax.plot(np.linalg.norm(V[:, :2], axis=1), V[:, 2], "k.", ms=3, label="simplicial catenoid")
    ax.plot(c * np.cosh(z / c), z, "-", color="tab:red", label="c cosh(z/c)")
    ax.set_xlabel("distance to the axis r")
    ax.set_ylabel("z")
    ax.legend(fontsize=8)
    return save_figure(fig, path, dpi=120)


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    c = references.catenoid_neck(R=1.0, H=0.5)
    print(f"smooth catenoid: neck radius c = {c:.10f}")
    errors = {}
    for n in (4, 8) if tiny else (6, 8, 12, 16, 24):
        # Fig 6.5 to an area-gradient residual well below the O(h²) discretisation error
        V, F, info = area.minimal_surface(*dg.mesh.builtin.cylinder(n), tol=0.05 / n**4, max_iter=4000)
        errors[n] = abs(references.neck_radius(V) - c)
        print(f"n = {n:2d}: {info['iterations']:4d} steps, area {info['area'][-1]:.6f}, neck {references.neck_radius(V):.8f}, "
              f"|neck − c| = {errors[n]:.2e}")
    table = dg.limits.convergence(errors.get, sorted(errors), label="neck radius error")
    print(table.to_markdown())
    return [plot_laplace.minimal_surface(V, F, out / "catenoid.png", history=info["history"],
                                         title=f"Fig 6.5: simplicial catenoid, n = {n}"),
            profile(V, c, out / "catenoid_profile.png")]


if __name__ == "__main__":
    run(main, __doc__)
