"""Surfaces and graphs shared by the Sec 6 and Sec 7 checks and the surface examples
(`examples/catenoid.py`, `intrinsic_delaunay.py`, `narrow_minimal_surface.py`)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ddgjax import mesh


def random_graph(seed: int, n: int = 14, extra: int = 12):
    """`(edges, weights, rng)`: a connected graph on n vertices (a random tree plus `extra` random
    chords, loops dropped) with weights uniform in [0.1, 2]."""
    rng = np.random.default_rng(seed)
    parent = np.array([rng.integers(0, i) for i in range(1, n)])
    chords = rng.integers(0, n, size=(extra, 2))
    edges = np.vstack([np.stack([np.arange(1, n), parent], 1), chords[chords[:, 0] != chords[:, 1]]])
    return edges, rng.uniform(0.1, 2.0, len(edges)), rng


def unit_square(n: int):
    """`(V, F, boundary)`: the unit square in the plane z = 0 cut into n × n squares, each split
    into two right triangles (a Delaunay triangulation: every cotan weight is ≥ 0)."""
    s = np.linspace(0.0, 1.0, n + 1)
    x, y = np.repeat(s, n + 1), np.tile(s, n + 1)
    V = np.stack([x, y, np.zeros_like(x)], 1)
    F = mesh.triangulate(mesh.builtin.grid_quads(n + 1, n + 1, False, False))
    return V, F, np.flatnonzero((x == 0) | (x == 1) | (y == 0) | (y == 1))


def cylinder(n: int, R: float = 1.0, H: float = 0.5):
    """`(V, F)`: n + 1 circles of 3n vertices on the cylinder of radius R over |z| ≤ H, the start
    of Fig 6.5 for the catenoid spanned by its two boundary circles (edge length h ∝ 1/n)."""
    V, F = mesh.annulus(3 * n, n + 1, 1.0, 2.0)
    angle, s = np.arctan2(V[:, 1], V[:, 0]), np.linalg.norm(V[:, :2], axis=1) - 1.0
    return np.stack([R * np.cos(angle), R * np.sin(angle), H * (2.0 * s - 1.0)], 1), F


def catenoid_neck(R: float = 1.0, H: float = 0.5) -> float:
    """The neck radius c of the stable catenoid r(z) = c cosh(z/c) through the circles of radius R
    at z = ±H: the larger root of c cosh(H/c) = R (the smaller one is the unstable catenoid)."""
    fold = brentq(lambda c: np.tanh(H / c) - c / H, 1e-3 * H, H)  # c cosh(H/c) is least here
    return brentq(lambda c: c * np.cosh(H / c) - R, fold, R)


def neck_radius(V) -> float:
    """min over the vertices of the distance to the z-axis."""
    return float(np.min(np.linalg.norm(np.asarray(V)[:, :2], axis=1)))


def tall_dome(seed: int = 0, n_inner: int = 150, m: int = 32, stretch: float = 5.0, height: float = 3.0,
              wave: float = 0.0):
    """`(V, F, boundary)`: a start unsuited to its minimal surface (Fig 7.26).  Points in the unit
    disk (m on the circle, `n_inner` random inside), triangulated by the planar Delaunay
    triangulation of the points squeezed by `stretch` in y (long skinny triangles), lifted to the
    dome z = height (1 − r²) + wave r² cos 2φ over the boundary curve z = wave cos 2φ, which
    stays fixed (for wave = 0 the minimal surface is the flat m-gon)."""
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    t = 2 * np.pi * np.arange(m) / m
    r, a = np.sqrt(rng.uniform(0, 0.8, n_inner)), rng.uniform(0, 2 * np.pi, n_inner)
    P = np.vstack([np.stack([np.cos(t), np.sin(t)], 1), np.stack([r * np.cos(a), r * np.sin(a)], 1)])
    F = Delaunay(P * np.array([1.0, stretch])).simplices
    u, w = P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]
    clockwise = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0] < 0
    F[clockwise] = F[clockwise][:, [0, 2, 1]]
    rho2, phi = np.sum(P**2, axis=1), np.arctan2(P[:, 1], P[:, 0])
    return np.column_stack([P, height * (1 - rho2) + wave * rho2 * np.cos(2 * phi)]), F, np.arange(m)


def stretched_sphere(level: int = 2, stretch=(6.0, 1.0, 0.5), bumps: float = 0.0, seed: int = 0):
    """`(V, F)`: the icosphere stretched into a skinny ellipsoid (many non-Delaunay edges), its
    radii scaled by 1 + `bumps` · N(0, 1) (bumps > 0 breaks the symmetries that make quadrilaterals
    cocircular)."""
    V, F = mesh.icosphere(level)
    noise = 1.0 + bumps * np.random.default_rng(seed).standard_normal((len(V), 1))
    return V * np.asarray(stretch) * noise, F


def fig_7_26(seed: int = 0, budget: int = 30, **dome):
    """Fig 7.26 on `tall_dome(seed, **dome)`: `(V, F, boundary, cotan, narrow)` with `cotan` and
    `narrow` the `(V, F, info)` of `intrinsic.minimal.harmonic_iteration` without flips (Fig 6.5,
    which ends a run whose iterate degenerates) and with flips (Fig 7.23), `budget` iterations."""
    from ddgjax.intrinsic.minimal import harmonic_iteration

    V, F, boundary = tall_dome(seed, **dome)
    cotan = harmonic_iteration(V, F, boundary, flip=False, tol=1e-9, max_iter=budget)
    narrow = harmonic_iteration(V, F, boundary, flip=True, tol=1e-9, max_iter=budget)
    return V, F, boundary, cotan, narrow


def draw_fig_7_26(path, V, F, cotan, narrow):
    """Three surfaces (the start, the last Fig 6.5 iterate, the Fig 7.23 result) above the two
    residual histories; saved to `path` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12.0, 7.5))
    panels = ((V, F, "start (skinny triangles)"), (cotan[0], F, f"Fig 6.5 after {cotan[2]['iterations']} steps"),
              (narrow[0], narrow[1], f"Fig 7.23 after {narrow[2]['iterations']} steps"))
    for k, (X, G, title) in enumerate(panels):
        ax = fig.add_subplot(2, 3, k + 1, projection="3d")
        G = np.asarray(G)
        G = G[(G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 2] != G[:, 0])]
        ax.plot_trisurf(X[:, 0], X[:, 1], X[:, 2], triangles=G, color="lightsteelblue", edgecolor="k", linewidth=0.2)
        ax.set_title(title, fontsize=10)
        ax.set_box_aspect((1, 1, 0.6))
        ax.set_axis_off()
    ax = fig.add_subplot(2, 1, 2)
    for (_, _, info), label in ((cotan, "Fig 6.5 (cotan Laplacian of the surface)"),
                                (narrow, "Fig 7.23 (flips + Laplace–Beltrami)")):
        ax.semilogy(np.maximum(info["history"], 1e-300), "o-", ms=3, label=label)
    ax.set_xlabel("iteration")
    ax.set_ylabel("max |Δf| at free vertices")
    ax.legend(fontsize=9)
    fig.suptitle("Fig 7.26: a start unsuited to the minimal surface")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
