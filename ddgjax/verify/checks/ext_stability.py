"""Stability: the Morse index of constrained critical points (Sec 3.1 Lagrange multipliers; second-order condition).

`solvers.stability`: the Hessian of the Lagrangian L = E − λ·g on the free entries and the
constraints' tangent space, the zero modes of Euclidean motions removed.  A critical point is a
strict local minimum iff it is positive definite; the number of negative eigenvalues is the
Morse index.  Objects: the two catenoids between the unit circles at z = ±½ (Sec 6.4; the one
with the larger neck is stable, the other has index 1) and the closed elastica (the regular
polygon, a minimum; Euler's figure-eight, a saddle, Remark 3.7), and soap bubbles (a single
bubble and the standard double bubble: minima, index 0, with the six Euclidean zero modes).
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.optimize import brentq

import ddgjax as dg
from ddgjax.verify import check
from energies import area, elastica
from solvers import solve, stability

from .sec3_elastica import figure_eight


def catenoid_parameter(stable: bool) -> float:
    """The root c of c·cosh(½/c) = 1: c ≈ 0.848 (stable) or c ≈ 0.235 (unstable)."""
    f = lambda c: c * np.cosh(0.5 / c) - 1.0
    return brentq(f, 0.5, 1.0) if stable else brentq(f, 0.1, 0.4)


@functools.cache
def catenoid(n: int, stable: bool):
    """`(problem, solution)`: the simplicial catenoid on `cylinder(n)` (boundary circles fixed),
    found by Newton from the smooth catenoid r = c cosh(z/c) sampled on the cylinder's mesh."""
    V, F = dg.mesh.builtin.cylinder(n)
    c = catenoid_parameter(stable)
    r, z = np.linalg.norm(V[:, :2], axis=1), V[:, 2]
    start = V.copy()
    start[:, :2] *= (c * np.cosh(z / c) / r)[:, None]
    problem = area.simplicial(start, F)
    return problem, solve(problem)


def _catenoid_index(n: int, stable: bool, method: str = "auto") -> float:
    problem, sol = catenoid(n, stable)
    result = stability(problem, sol, k=2, method=method)
    if result.zero_modes != 0:  # the fixed circles break every Euclidean motion
        raise AssertionError(f"{result.zero_modes} zero modes found on a catenoid with fixed boundary")
    return float(result.index)


@check("Sec 3.1, 6.4", "the catenoid with the larger neck (c ≈ 0.848, c·cosh(½/c) = 1) is stable: the Hessian of "
       "the area on the interior vertices is positive definite", quantity="Morse index", target=0.0, within=0.0,
       quick=dict(n=6), full=dict(n=24))
def catenoid_stable_index(ctx, n):
    return _catenoid_index(n, True)


@check("Sec 3.1, 6.4", "the catenoid with the smaller neck (c ≈ 0.235) is unstable with one negative direction "
       "(the neck's radius): Morse index 1, no spurious tangential modes", quantity="Morse index", target=1.0,
       within=0.0, quick=dict(n=6), full=dict(n=24))
def catenoid_unstable_index(ctx, n):
    return _catenoid_index(n, False)


@check("Sec 3.1, 6.4", "the unstable catenoid on a mesh of ~10⁴ free unknowns (34 rings): Morse index 1 by the "
       "sparse path (Sylvester inertia of the bordered KKT matrix, shift-invert Lanczos)", quantity="Morse index",
       target=1.0, within=0.0, quick=dict(n=34), full_only=True)
def catenoid_unstable_index_sparse(ctx, n):
    return _catenoid_index(n, False, method="sparse")


def _regular_polygon(n: int):
    angles = 2 * np.pi * (np.arange(n) + 0.5) / n
    problem = elastica.closed(n, x0=np.stack([np.cos(angles), np.sin(angles), 0 * angles], 1))
    return problem, solve(problem)


@check("Sec 3.1, Remark 3.7", "the regular n-gon is a stable closed elastica: index 0, with exactly the three "
       "rotations of R³ as zero modes (translations do not act on tangents)",
       quantity="index + |zero modes − 3|", target=0.0, within=0.0, quick=dict(n=48), full=dict(n=192))
def closed_polygon_is_stable(ctx, n):
    result = stability(*_regular_polygon(n), k=2)
    return float(result.index + abs(result.zero_modes - 3))


@check("Sec 3.1, Remark 3.7", "negative control: with the zero-mode test switched off (zero_tol = 1e-300) the "
       "polygon's three rotations stay in the spectrum as eigenvalues at the round-off level",
       quantity="max |μ_1..3| / scale with no mode removed (−∞ unless 0 modes were removed)", at_most=1e-10,
       quick=dict(n=48))
def closed_polygon_rotations_are_null(ctx, n):
    result = stability(*_regular_polygon(n), k=4, zero_tol=1e-300)
    if result.zero_modes != 0:
        return float("inf")
    return float(np.max(np.abs(result.eigenvalues[:3])) / result.scale)


@check("Sec 3.1, Remark 3.7", "Euler's figure-eight is an unstable closed elastica: Morse index ≥ 1 (it is 1), the "
       "three rotations removed", quantity="Morse index (−1 unless 3 zero modes)", at_least=1.0,
       quick=dict(n=48), full=dict(n=96))
def figure_eight_index(ctx, n):
    problem, sol, _ = figure_eight(n)
    result = stability(problem, sol, k=3)
    return float(result.index) if result.zero_modes == 3 else -1.0


@functools.cache
def bubble(level: int):
    """`(problem, solution)`: the soap bubble of volume 4π/3 from the perturbed icosphere
    (`ext_bubbles.sphere_start`), solved."""
    from .ext_bubbles import SPHERE_VOLUME, sphere_start

    V, F = sphere_start(level)
    problem = area.with_volume(V, F, SPHERE_VOLUME)
    return problem, solve(problem)


@check("Sec 3.1; Laplace–Young", "the soap bubble (volume 4π/3, a perturbed icosphere solved) is a stable critical "
       "point: Morse index 0, with exactly six zero modes removed (the three translations and three rotations, "
       "which keep area and volume)", quantity="index + |zero modes − 6|", at_most=0.0, quick=dict(level=1),
       full=dict(level=2))
def bubble_is_stable(ctx, level):
    result = stability(*bubble(level), k=2)
    return float(result.index + abs(result.zero_modes - 6))


@check("Sec 3.1; Hutchings, Morgan, Ritoré & Ros 2002", "the standard double bubble of two equal chambers is a "
       "stable critical point of the area at fixed chamber volumes: Morse index 0, six zero modes (Euclidean motions)",
       quantity="index + |zero modes − 6|", at_most=0.0, quick=dict(m=12), full=dict(m=24))
def double_bubble_is_stable(ctx, m):
    V, F, C = dg.mesh.double_bubble(m, m // 4, max(2, round(m / 6)))
    problem = area.with_volumes(V, F, C, [9.0 * np.pi / 8.0] * 2)
    result = stability(problem, solve(problem), k=2)
    return float(result.index + abs(result.zero_modes - 6))
