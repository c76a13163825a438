"""Reproductions of the reference's figures that need the catalogue (`energies`), and their drawings."""

from __future__ import annotations

import numpy as np

from ddgjax.mesh.builtin import tall_dome
from ddgjax.plot import save_figure
from ddgjax.plot._figure import pyplot
from energies.area import harmonic_iteration

__all__ = ["draw_fig_7_26", "draw_surface", "fig_7_26"]


def fig_7_26(seed: int = 0, budget: int = 30, **dome):
    """Fig 7.26 on `mesh.builtin.tall_dome(seed, **dome)`: `(V, F, boundary, cotan, narrow)` with
    `cotan` and `narrow` the `(V, F, info)` of `energies.area.harmonic_iteration` without flips
    (Fig 6.5, which ends a run whose iterate degenerates) and with flips (Fig 7.23), `budget`
    iterations each."""
    V, F, boundary = tall_dome(seed, **dome)
    cotan = harmonic_iteration(V, F, boundary, flip=False, tol=1e-9, max_iter=budget)
    narrow = harmonic_iteration(V, F, boundary, flip=True, tol=1e-9, max_iter=budget)
    return V, F, boundary, cotan, narrow


def draw_surface(ax, X, G, title: str, *, linewidth: float = 0.4, fontsize: float = 9, height: float = 0.5) -> None:
    """The simplicial surface with positions X and faces G on the 3-D axes `ax`, faces that repeat
    a vertex (a gluing's Δ-complex faces seen as a mesh) left out; z drawn at `height` of x and y."""
    G = np.asarray(G)
    G = G[(G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 2] != G[:, 0])]
    ax.plot_trisurf(X[:, 0], X[:, 1], X[:, 2], triangles=G, color="lightsteelblue", edgecolor="k", linewidth=linewidth)
    ax.set_title(title, fontsize=fontsize)
    ax.set_box_aspect((1, 1, height))
    ax.set_axis_off()


def draw_fig_7_26(path, V, F, cotan, narrow):
    """Three surfaces (the start, the last Fig 6.5 iterate, the Fig 7.23 result) above the two
    residual histories; saved to `path` (PNG)."""
    plt = pyplot()
    fig = plt.figure(figsize=(12.0, 7.5))
    panels = ((V, F, "start (skinny triangles)"), (cotan[0], F, f"Fig 6.5 after {cotan[2]['iterations']} steps"),
              (narrow[0], narrow[1], f"Fig 7.23 after {narrow[2]['iterations']} steps"))
    for k, (X, G, title) in enumerate(panels):
        draw_surface(fig.add_subplot(2, 3, k + 1, projection="3d"), X, G, title, linewidth=0.2, fontsize=10, height=0.6)
    ax = fig.add_subplot(2, 1, 2)
    for (_, _, info), label in ((cotan, "Fig 6.5 (cotan Laplacian of the surface)"),
                                (narrow, "Fig 7.23 (flips + Laplace–Beltrami)")):
        ax.semilogy(np.maximum(info["history"], 1e-300), "o-", ms=3, label=label)
    ax.set_xlabel("iteration")
    ax.set_ylabel("max |Δf| at free vertices")
    ax.legend(fontsize=9)
    fig.suptitle("Fig 7.26: a start unsuited to the minimal surface")
    return save_figure(fig, path, dpi=100)
