"""Soap bubbles: area with a volume constraint (Laplace–Young, Alexandrov's theorem).

`energies.area.with_volume`: the area of a triangle mesh with its enclosed volume prescribed, the
named constraint "volume", whose multiplier p is the pressure.  At a critical point ∇A = p ∇vol,
and by Thm 6.7 ∇A is the cotan Laplacian of the surface, the discrete mean curvature normal: the
surface has constant mean curvature κ1 + κ2 = p, the Laplace–Young law of a soap film.  The
checks solve bubbles (a perturbed icosphere with the volume 4π/3 of the unit sphere: p → 2) and
liquid bridges (the film between two coaxial unit circles at z = ±H: with the cylinder's volume
p → 1; with more volume it bulges into a Delaunay surface of revolution whose pressure comes
from the smooth profile by shooting, `liquid_bridge_pressure`).

Double bubbles (`energies.area.with_volumes`, several chambers; the films meet three at an edge):
from the sampled standard double bubble of two equal chambers (`ddgjax.mesh.builtin.double_bubble`,
caps of radius r = 1, flat wall), the solved pressures converge to Laplace–Young's 2/r; with
unequal volumes the caps and the wall become spheres of radii r_A, r_B, r_W (fitted) with
1/r_W = 1/r_B − 1/r_A, the standard double bubble of Hutchings, Morgan, Ritoré & Ros (2002).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve

import ddgjax as dg
from ddgjax.verify import check
from energies import area
from solvers import solve

SPHERE_VOLUME = 4.0 * np.pi / 3.0  # the unit ball: p = 2/r = 2
BRIDGE_H = 0.5  # the bridges span the unit circles at z = ±H
BULGE = 1.3  # the bulging bridge holds 1.3 × the cylinder's volume


def sphere_start(level: int):
    """`(V, F)`: `dg.mesh.icosphere(level)` with its radius perturbed by 2 % of the Legendre
    polynomial P2(z) (a smooth, non-round start of the volume ≈ 4π/3)."""
    V, F = dg.mesh.icosphere(level)
    return V * (1.0 + 0.02 * (1.5 * V[:, 2:] ** 2 - 0.5)), F


def bridge_start(n: int, H: float = BRIDGE_H, volume: float | None = None):
    """`(V, F)`: `dg.mesh.builtin.cylinder(n, H=H)` (3n vertices per circle, n + 1 circles) with
    its faces reversed so that the normals point out of the enclosed volume; with `volume`, its
    interior circles scaled to the parabolic profile r(z) = r0 − (r0 − 1) z²/H² of that volume
    (`_parabola_waist`), a start Newton converges from in ~10 steps where the cylinder is too far
    for a bulging bridge on fine meshes (n = 24, 1.3 × the volume: not in 100 steps)."""
    V, F = dg.mesh.builtin.cylinder(n, H=H)
    if volume is not None:
        r0 = _parabola_waist(H, volume)
        scale = r0 - (r0 - 1.0) * V[:, 2] ** 2 / H**2
        scale[dg.mesh.boundary_vertices(F)] = 1.0
        V = np.column_stack([V[:, :2] * scale[:, None], V[:, 2]])
    return V, np.ascontiguousarray(F[:, ::-1])


def _parabola_waist(H: float, volume: float, R: float = 1.0) -> float:
    """The waist r0 ≥ R of the profile r(z) = r0 − a z², a = (r0 − R)/H², through the circles of
    radius R at z = ±H whose solid of revolution has the given volume."""
    def excess(r0):
        a = (r0 - R) / H**2
        return np.pi * (2 * r0**2 * H - 4 * r0 * a * H**3 / 3 + 2 * a**2 * H**5 / 5) - volume

    return brentq(excess, R, 10.0 * R)


def _solved(V, F, volume: float) -> dict:
    from solvers import solve

    sol = solve(area.with_volume(V, F, volume), tol=1e-12)
    x = np.asarray(sol.x)
    distance = np.linalg.norm(x - x.mean(axis=0), axis=1)
    return {"pressure": float(sol.multipliers["volume"][0]), "residual": float(sol.residual),
            "volume_error": abs(area.enclosed_volume(x, F) - volume), "steps": int(sol.steps),
            "roundness": float(distance.max() - distance.min()), "x": x}


@lru_cache(maxsize=None)
def bubble(level: int, volume: float = SPHERE_VOLUME) -> dict:
    """The solved bubble from `sphere_start(level)` with the given volume (cached)."""
    return _solved(*sphere_start(level), volume)


@lru_cache(maxsize=None)
def bridge(n: int, factor: float = 1.0, H: float = BRIDGE_H) -> dict:
    """The solved liquid bridge from `bridge_start(n, H)` holding `factor` × the cylinder's volume
    2πH (cached)."""
    volume = factor * 2.0 * np.pi * H
    return _solved(*bridge_start(n, H, volume), volume)


def liquid_bridge_pressure(H: float, volume: float, R: float = 1.0) -> float:
    """The pressure p = κ1 + κ2 of the smooth liquid bridge of revolution r(z), |z| ≤ H, spanning
    the circles of radius R at z = ±H and enclosing `volume`, on the branch of a convex bulge
    (volume > 2πR²H; p = 1/R for the cylinder's volume).  With the outward normal,
    κ1 + κ2 = 1/(r√(1 + r'²)) − r''/(1 + r'²)^{3/2} = p: shooting from the waist r(0) = r0,
    r'(0) = 0 for (r0, p) with r(H) = R and π∫ r² dz = volume, from the parabola's guess
    (`_parabola_waist`, and p from its curvatures at the waist)."""
    def ends(w):
        r0, p = w

        def rhs(z, y):
            q = 1.0 + y[1] ** 2
            return [y[1], q / y[0] - p * q**1.5, np.pi * y[0] ** 2]

        r, _, half = solve_ivp(rhs, (0.0, H), [r0, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
        return [r - R, 2.0 * half - volume]

    r0 = _parabola_waist(H, volume, R)
    (r0, p), info, _, _ = fsolve(ends, [r0, 1.0 / r0 + 2.0 * (r0 - R) / H**2], full_output=True, xtol=1e-13)
    if np.max(np.abs(info["fvec"])) > 1e-10:
        raise RuntimeError(f"liquid_bridge_pressure: shooting did not converge ({info['fvec']})")
    return float(p)


def _order(ctx, errors: dict, name: str, label: str) -> float:
    table = ctx.convergence(dg.limits.convergence(errors.get, sorted(errors), label=label), name)
    return float(table.orders[-1])


@check("Laplace–Young; Thm 6.7", "a soap bubble of volume 4π/3 (a perturbed icosphere) has the pressure of the unit "
       "sphere, p·r = κ1 + κ2 = 2: the multiplier of the volume converges to 2/r at order 2 in the edge length",
       quantity="observed order of |p·r − 2| between the two finest icosphere levels", target=2.0, within=0.1,
       quick=dict(levels=(0, 1, 2)), full=dict(levels=(0, 1, 2, 3, 4)))
def bubble_pressure_order(ctx, levels):
    errors = {2**level: abs(bubble(level)["pressure"] - 2.0) for level in levels}
    return _order(ctx, errors, "bubble_pressure", "|p·r − 2| (h ∝ 1/n, n = 2^level)")


@check("Laplace–Young; Thm 6.7", "the bubble is a critical point of the area with the volume constraint: the KKT "
       "residual |∇A − p ∇vol| and the volume error vanish to round-off",
       quantity="max over levels of the KKT residual and |vol − 4π/3|", at_most=1e-11,
       quick=dict(levels=(0, 1, 2)), full=dict(levels=(0, 1, 2, 3, 4)))
def bubble_kkt_residual(ctx, levels):
    return max(max(bubble(level)["residual"], bubble(level)["volume_error"]) for level in levels)


@check("Alexandrov's theorem", "a closed embedded surface of constant mean curvature is a round sphere: the "
       "discrete bubble's spread of distances to its centroid goes to zero under refinement",
       quantity="observed order of max − min |v − c| between the two finest levels (≈ 1.5–1.7 measured)",
       at_least=1.0, quick=dict(levels=(1, 2, 3)), full=dict(levels=(1, 2, 3, 4)))
def bubble_is_round(ctx, levels):
    errors = {2**level: bubble(level)["roundness"] for level in levels}
    return _order(ctx, errors, "bubble_roundness", "max − min |v − c|")


@check("Laplace–Young", "a liquid bridge between the unit circles at z = ±1/2 holding the cylinder's volume π is "
       "the cylinder, κ1 + κ2 = 1: the pressure converges to 1 at order 2",
       quantity="observed order of |p − 1| between the two finest meshes", target=2.0, within=0.1,
       quick=dict(ns=(3, 4, 6)), full=dict(ns=(3, 6, 12, 24)))
def bridge_pressure_order(ctx, ns):
    errors = {n: abs(bridge(n)["pressure"] - 1.0) for n in ns}
    return _order(ctx, errors, "bridge_pressure", "|p − 1| (cylinder)")


@check("Laplace–Young (Delaunay surfaces)", "a liquid bridge holding 1.3 × the cylinder's volume bulges; its pressure "
       "converges at order 2 to that of the smooth bridge of revolution with κ1 + κ2 = p (shooting)",
       quantity="observed order of |p − p_smooth| between the two finest meshes", target=2.0, within=0.15,
       quick=dict(ns=(3, 4, 6)), full=dict(ns=(3, 6, 12, 24)))
def bulging_bridge_order(ctx, ns):
    p = liquid_bridge_pressure(BRIDGE_H, BULGE * 2.0 * np.pi * BRIDGE_H)
    errors = {n: abs(bridge(n, BULGE)["pressure"] - p) for n in ns}
    return _order(ctx, errors, "bulging_bridge_pressure", f"|p − p_smooth|, p_smooth = {p:.10f}")


@check("Laplace–Young", "negative control: the bubble holding the volume of the sphere of radius 2 is not the unit "
       "sphere, its pressure is 2/2 = 1 and p·1 misses 2",
       quantity="|p·1 − 2| for the volume 8 · 4π/3 (level 1)", at_least=0.5, quick=dict(level=1))
def wrong_volume_misses_unit_pressure(ctx, level):
    return abs(bubble(level, 8.0 * SPHERE_VOLUME)["pressure"] - 2.0)


# --- double bubbles: two chambers, three films along a junction -----------------------------------

DOUBLE_VOLUME = 9.0 * np.pi / 8.0  # each chamber of the standard double bubble with caps of radius 1
UNEQUAL = (1.2, 0.8)  # the unequal chambers, in units of DOUBLE_VOLUME


@lru_cache(maxsize=None)
def double_bubble_solution(m: int, shares: tuple = (1.0, 1.0)):
    """`(solution, F, chambers)`: `area.with_volumes` on `double_bubble(m, m // 4, round(m / 6))`
    with the volumes `shares` × 9π/8, solved from the equal-volume standard double bubble."""
    V, F, C = dg.mesh.builtin.double_bubble(m, m // 4, max(2, round(m / 6)))
    return solve(area.with_volumes(V, F, C, DOUBLE_VOLUME * np.asarray(shares))), F, C


def sphere_radius(P: np.ndarray) -> float:
    """The radius of the least-squares sphere through the points P (algebraic fit:
    |x|² = 2c·x + r² − |c|², linear in (c, r² − |c|²))."""
    A = np.column_stack([2.0 * P, np.ones(len(P))])
    coef = np.linalg.lstsq(A, (P**2).sum(axis=1), rcond=None)[0]
    return float(np.sqrt(coef[3] + coef[:3] @ coef[:3]))


def sheet_radii(m: int) -> tuple[float, float, float]:
    """`(r_A, r_B, r_W)`: the fitted radii of the two caps and the wall of the unequal double bubble."""
    sol, F, C = double_bubble_solution(m, UNEQUAL)
    X = np.asarray(sol.x)
    sheets = (C[:, 1] == 0, C[:, 0] == 0, (C[:, 0] != 0) & (C[:, 1] != 0))
    return tuple(sphere_radius(X[np.unique(F[mask])]) for mask in sheets)


def pressure_error(m: int) -> float:
    """max_c |p_c r/2 − 1| of the equal double bubble (r = 1)."""
    sol = double_bubble_solution(m)[0]
    return float(np.max(np.abs(np.asarray(sol.multipliers["volumes"]) / 2.0 - 1.0)))


@check("Laplace–Young; Plateau", "a double bubble of two equal chambers of volume 9π/8 (started from the sampled "
       "standard double bubble): both pressures converge to that of its caps of radius 1, p = 2/r = 2, at order 2",
       quantity="fitted order of max_c |p_c/2 − 1|", target=2.0, within=0.2, quick=dict(ns=(12, 16, 24)),
       full=dict(ns=(12, 16, 24, 48)))
def double_bubble_pressure_order(ctx, ns):
    table = ctx.convergence(dg.limits.convergence(pressure_error, list(ns)), "double_bubble_pressure_order",
                            title="double bubble: max |p/2 − 1| against the ring size m")
    return float(table.fitted_order)


@check("Laplace–Young; Euler's homogeneous function theorem", "at a critical double bubble 2A = 3 Σ_c p_c vol_c "
       "(the area is homogeneous of degree 2 and the volumes of degree 3 in the positions, so scaling is a direction "
       "of the KKT system), to the KKT tolerance, and every solve converged",
       quantity="max over m and both volume pairs of |2A − 3 Σ p_c vol_c| / A", at_most=1e-9,
       quick=dict(ns=(12,)), full=dict(ns=(12, 16, 24, 32)))
def double_bubble_scaling_identity(ctx, ns):
    worst = 0.0
    for m in ns:
        for shares in ((1.0, 1.0), UNEQUAL):
            sol = double_bubble_solution(m, shares)[0]
            if not bool(sol.converged):
                return float("inf")
            A, p = float(sol.energy), np.asarray(sol.multipliers["volumes"])
            worst = max(worst, abs(2.0 * A - 3.0 * float(p @ (DOUBLE_VOLUME * np.asarray(shares)))) / A)
    return worst


@check("Hutchings, Morgan, Ritoré & Ros 2002", "the double bubble of chambers 1.2 and 0.8 × 9π/8 is the standard one: "
       "its caps and its wall approach spheres (fitted radii r_A, r_B, r_W) with 1/r_W = 1/r_B − 1/r_A",
       quantity="fitted order of |1/r_W − 1/r_B + 1/r_A| (≈ 2.4 measured, pre-asymptotic)", at_least=1.5,
       quick=dict(ns=(12, 16, 24)), full=dict(ns=(12, 16, 24, 32)))
def double_bubble_standard_radii(ctx, ns):
    def defect(m):
        r_a, r_b, r_w = sheet_radii(m)
        return abs(1.0 / r_w - 1.0 / r_b + 1.0 / r_a)

    table = ctx.convergence(dg.limits.convergence(defect, list(ns)), "double_bubble_standard_radii",
                            title="unequal double bubble: |1/r_W − 1/r_B + 1/r_A| against m")
    return float(table.fitted_order)


@check("Laplace–Young", "the unequal double bubble's pressures converge to its caps' 2/r_A and 2/r_B (fitted radii) "
       "at order 2", quantity="fitted order of max(|p_A r_A/2 − 1|, |p_B r_B/2 − 1|)", target=2.0, within=0.2,
       quick=dict(ns=(12, 16, 24)), full=dict(ns=(12, 16, 24, 32)))
def double_bubble_unequal_pressures(ctx, ns):
    def error(m):
        r_a, r_b, _ = sheet_radii(m)
        p = np.asarray(double_bubble_solution(m, UNEQUAL)[0].multipliers["volumes"])
        return max(abs(p[0] * r_a / 2.0 - 1.0), abs(p[1] * r_b / 2.0 - 1.0))

    table = ctx.convergence(dg.limits.convergence(error, list(ns)), "double_bubble_unequal_pressures",
                            title="unequal double bubble: |p r/2 − 1| against m")
    return float(table.fitted_order)


@check("Laplace–Young", "negative control: the equal double bubble's pressure is not that of one sphere holding both "
       "chambers (radius (27/16)^(1/3))", quantity="|p/p_sphere − 1|", at_least=0.1, quick=dict(m=24), full=dict(m=48))
def double_bubble_not_one_sphere(ctx, m):
    p = float(double_bubble_solution(m)[0].multipliers["volumes"][0])
    return abs(p / (2.0 / (3.0 * 2.0 * DOUBLE_VOLUME / (4.0 * np.pi)) ** (1.0 / 3.0)) - 1.0)
