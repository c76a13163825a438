"""Solved problems shared by several check modules, cached so that each problem structure is
compiled and solved once per `ddgjax verify` run (JIT compilation dominates the quick run)."""

from __future__ import annotations

import functools

import numpy as np

from ddgjax.smooth import elastica as exact

# A clamped space elastica with a genuinely three-dimensional load (Thm 3.8, Thm 3.10, Cor 3.9).
SPACE_CHORD, SPACE_START, SPACE_END = (0.5, 0.3, 0.2), (0.0, 1.0, 0.3), (0.2, -1.0, 0.5)
COARSEST = 32  # the default start of `elastica.clamped` converges up to about here


@functools.cache
def space_elastica(n: int, clamp: str = "edge"):
    """`(problem, solution)` of the clamped space elastica with n edges."""
    from energies import elastica
    from solvers import solve

    # Newton needs a start near the solution: the vertex clamp starts from the edge-clamped
    # solution, a fine edge-clamped one from a coarser one resampled (continuation in n)
    if clamp == "vertex":
        x0 = space_elastica(n, "edge")[1].x
    else:
        x0 = None if n <= COARSEST else elastica.resample(space_elastica(max(COARSEST, n // 2))[1].x, n)
    problem = elastica.clamped(n, chord=SPACE_CHORD, t_start=SPACE_START, t_end=SPACE_END, clamp=clamp, x0=x0)
    return problem, solve(problem)


@functools.cache
def planar_elastica(n: int, chord: float):
    """`(problem, solution)` of the planar elastica from (0, 1, 0) to (0, −1, 0), chord (c, 0, 0)."""
    from energies import elastica
    from solvers import solve

    problem = elastica.clamped(n, chord=[chord, 0.0, 0.0], t_start=[0.0, 1.0, 0.0], t_end=[0.0, -1.0, 0.0])
    return problem, solve(problem)


def smooth_clamped_elastica() -> exact.PlanarElastica:
    """The inflectional elastica whose boundary data the smooth-limit checks clamp."""
    return exact.inflectional(0.8, lam=4.0, u0=0.3, length=1.0)


def edge_midpoint_tangents(curve, n: int) -> np.ndarray:
    """Unit tangents of the smooth elastica `curve` (planar or in space: its `tangent(s)` and
    `length`) at the n edge midpoints of a uniform partition of [0, L]: a start for Newton
    within O(h²) of the discrete elastica."""
    return curve.tangent((np.arange(n) + 0.5) * curve.length / n)


def vertex_field(T) -> np.ndarray:
    """`W_k = T_k × T_{k−1} / (1 + <T_k, T_{k−1}>)` at the interior vertices: the Heisenberg
    velocity of Prop 2.2 and the left side of Thm 3.8."""
    T = np.asarray(T)
    return np.cross(T[1:], T[:-1]) / (1 + np.sum(T[1:] * T[:-1], axis=1))[:, None]


def thm_3_8_spread(T, gamma, a) -> float:
    """`max_k |b_k − b_1|` with `b_k = W_k − a × γ_k` at the interior vertices (Thm 3.8: b is
    one constant vector)."""
    b = vertex_field(T) - np.cross(np.asarray(a), np.asarray(gamma)[1:-1])
    return float(np.max(np.abs(b - b[0])))


def euclidean_motion_fit(points, velocities, extra=None) -> tuple[float, np.ndarray]:
    """`(residual, (a, b[, c]))`: the least-squares fit of `v_k ≈ a × p_k + b [+ c e_k]` and its
    residual `max_k |v_k − (a × p_k + b [+ c e_k])|`: how far a velocity field is from an
    infinitesimal Euclidean motion (Cor 3.7), optionally plus a multiple c of another field
    `extra` (Def 3.7)."""
    points, velocities = np.asarray(points), np.asarray(velocities)
    rows = np.cross(points[:, None, :], np.eye(3)[None]).transpose(0, 2, 1)  # [p]× e_j = p × e_j
    blocks = [-rows, np.broadcast_to(np.eye(3), rows.shape)]
    if extra is not None:
        blocks.append(-np.asarray(extra)[:, :, None])
    A = np.concatenate(blocks, axis=2).reshape(-1, sum(b.shape[2] for b in blocks))
    solution = np.linalg.lstsq(A, velocities.ravel(), rcond=None)[0]
    return float(np.max(np.abs(A @ solution - velocities.ravel()))), solution


def euclidean_motion_residual(points, velocities, extra=None) -> float:
    """The residual of `euclidean_motion_fit`."""
    return euclidean_motion_fit(points, velocities, extra)[0]


def unit_rows(X) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    return X / np.linalg.norm(X, axis=-1, keepdims=True)


def max_abs(a, b=0.0) -> float:
    """max |a − b| over the entries, in NumPy: the checks reduce concrete arrays, where each
    `jax.numpy` operation on a shape not seen before would compile a program of its own."""
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)), initial=0.0))
