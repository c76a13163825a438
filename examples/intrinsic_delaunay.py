"""Intrinsic Delaunay triangulation of a skinny mesh by edge flips (Fig 7.13, Prop 7.9): an
icosphere stretched into a long ellipsoid has many edges whose opposite angles sum to more than
π; flipping them (Lemma 5.8) keeps the surface's metric and ends at a Delaunay triangulation
(Thm 7.12), lowering the harmonic index at every flip (Cor 7.19).  Its cotan weights are the
discrete Laplace–Beltrami operator (Def 7.8), all ≥ 0 (Prop 7.10).

    python examples/intrinsic_delaunay.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax import intrinsic, mesh
from ddgjax.plot import save_figure


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_edges(ax, tri, V, title: str):
    """The edges of `tri` on the upper half (z ≥ 0) seen from above, as chords between the vertex
    positions; non-Delaunay edges (Prop 7.9) thick and red."""
    from matplotlib.collections import LineCollection

    ok = intrinsic.delaunay_edges(tri)
    upper = np.all(V[tri.edges][:, :, 2] >= -1e-12, axis=1)
    segments = V[tri.edges][:, :, :2]
    for mask, color, width in ((ok & upper, "0.5", 0.4), (~ok & upper, "tab:red", 1.4)):
        ax.add_collection(LineCollection(segments[mask], colors=color, linewidths=width))
    ax.set_xlim(V[:, 0].min(), V[:, 0].max())
    ax.set_ylim(V[:, 1].min(), V[:, 1].max())
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(f"{title}: {int((~ok).sum())} non-Delaunay edges (upper half, from above)", fontsize=10)


def ellipsoid(level: int, path):
    V, F = mesh.builtin.stretched_sphere(level)
    start = intrinsic.from_mesh(V, F)
    result = intrinsic.flip_to_delaunay(start)
    h = result.harmonic_index
    nu_before, nu_after = intrinsic.cotan_weights(start), result.cotan_weights()
    print(f"stretched icosphere (level {level}): {start.n_faces} triangles, "
          f"{int((~intrinsic.delaunay_edges(start)).sum())} non-Delaunay edges")
    print(f"  {result.n_flips} flips in {result.n_rounds} rounds; harmonic index h(T) {h[0]:.2f} -> {h[-1]:.2f} "
          f"(decreases at every flip: {bool(np.all(np.diff(h) < 0))})")
    print(f"  min cotan weight {nu_before.min():+.3f} -> {nu_after.min():+.3e}; Delaunay: {intrinsic.is_delaunay(result)}")
    plt = _pyplot()
    fig = plt.figure(figsize=(11, 8))
    for k, (tri, title) in enumerate(((start, "start"), (result.triangulation, f"after {result.n_flips} flips"))):
        draw_edges(fig.add_subplot(3, 1, k + 1), tri, V, title)
    ax = fig.add_subplot(3, 1, 3)
    ax.plot(h, "-")
    ax.set_xlabel("flip")
    ax.set_ylabel("harmonic index h(T)")
    return save_figure(fig, path, dpi=110)


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    V, F, _ = mesh.builtin.tall_dome(0, n_inner=60 if tiny else 300, height=0.0)  # a flat disk with skinny triangles
    result = dg.plot.intrinsic.before_after(V, F, out / "intrinsic_delaunay_disk.png")
    print(f"flat disk: {result.n_flips} flips to the planar Delaunay triangulation")
    return [ellipsoid(2 if tiny else 3, out / "intrinsic_delaunay_ellipsoid.png"), out / "intrinsic_delaunay_disk.png"]


if __name__ == "__main__":
    run(main, __doc__)
