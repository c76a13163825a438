"""Polyhedral curvature (Sec 5: Gauss–Bonnet, mean curvature, Steiner)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import mesh
from ddgjax.mesh.builtin import _voxel_boundary  # no public polycube builder
from ddgjax.verify import check

from .sec4_topology import BUILTIN


@check("Thm 5.6, Remark 5.4", "Gauss–Bonnet: Σ K(p) over interior vertices + Σ φ(p) over boundary vertices = 2πχ",
       quantity="max |Σ K − 2πχ| over the built-in meshes", at_most=1e-12, quick=dict())
def gauss_bonnet_builtin(ctx):
    worst = 0.0
    for name in BUILTIN:
        V, F = getattr(mesh, name)()
        worst = max(worst, abs(float(np.sum(np.asarray(mesh.angle_defect(V, F)))) - 2 * np.pi * mesh.euler_characteristic(F)))
    for name in ("icosphere", "torus"):
        dg.plot.surface.surface(*getattr(mesh, name)(), path=ctx.figure(f"angle_defect_{name}.png"),
                                title=f"angle defect K(p), {name}")
    return worst


@check("Thm 5.6", "Σ K is topological: its gradient with respect to the vertex positions vanishes (torus)",
       quantity="max |∂(Σ K)/∂V|", at_most=1e-12, quick=dict(m=12, n=6), full=dict(m=48, n=24))
def gauss_bonnet_gradient(ctx, m, n):
    V, F = mesh.torus(m, n)
    return float(jnp.max(jnp.abs(jax.jit(jax.grad(lambda X: jnp.sum(mesh.angle_defect(X, F))))(jnp.asarray(V)))))


@check("Example 5.1", "the cube (squares, and triangulated): K(p) = π/2 at every vertex, θ(e) = π/2 at the edges of the "
       "squares and H(S) = 3π", quantity="max of |K − π/2|, |θ − π/2| and |H − 3π| / 3π over both cubes",
       at_most=1e-15, quick=dict())
def cube_curvatures(ctx):
    worst = 0.0
    for triangulated in (False, True):
        V, F = mesh.cube(triangulated)
        worst = max(worst, float(np.max(np.abs(np.asarray(mesh.angle_defect(V, F)) - np.pi / 2))),
                    abs(float(mesh.total_mean_curvature(V, F)) - 3 * np.pi) / (3 * np.pi))
    V, F = mesh.cube()
    return max(worst, float(np.max(np.abs(np.asarray(mesh.dihedral_angles(V, F)) - np.pi / 2))))


def _triangle_area(V, F) -> float:
    """Σ_f ½ |(b − a) × (c − a)| in numpy (no library code)."""
    a, b, c = (V[F[:, i]] for i in range(3))
    return 0.5 * float(np.sum(np.linalg.norm(np.cross(b - a, c - a), axis=1)))


def _box_distance(X, lo, hi):
    """Euclidean distance from the rows of X to the box [lo, hi]."""
    return np.linalg.norm(np.maximum(np.maximum(np.asarray(lo) - X, X - np.asarray(hi)), 0.0), axis=1)


def _offset_area(boxes, centre, rho: float, level: int) -> float:
    """Area of the level set {d(·, P) = ρ} of P = ∪ boxes (each containing `centre`), triangulated by
    moving the vertices u of icosphere(level) to centre + r(u) u with d(centre + r u, P) = ρ.  P_ρ is
    star-shaped about the centre (a union of convex sets containing it), so r(u) is found by bisection
    of the non-decreasing d along the ray; the inscribed surface converges like h²."""
    U, F = mesh.icosphere(level)
    lo, hi = np.zeros(len(U)), np.full(len(U), rho + sum(np.linalg.norm(np.subtract(*b)) for b in boxes))
    for _ in range(60):
        r = 0.5 * (lo + hi)
        d = np.min([_box_distance(centre + r[:, None] * U, *b) for b in boxes], axis=0)
        lo, hi = np.where(d < rho, r, lo), np.where(d < rho, hi, r)
    return _triangle_area(centre + (0.5 * (lo + hi))[:, None] * U, F)


def _extrapolated_offset_area(ctx, boxes, centre, rho, levels, compare=None, name=None) -> float:
    """Richardson extrapolation (order 2) of `_offset_area` over the last two `levels`; with `compare`
    and `name`, records the convergence table of |area − compare|."""
    areas = {2**k: _offset_area(boxes, centre, rho, k) for k in levels}
    if name is not None:
        table = dg.limits.convergence(lambda n: abs(areas[n] - compare), sorted(areas), label="error of A(S_ρ)")
        ctx.convergence(table, name)
    coarse, fine = areas[2 ** levels[-2]], areas[2 ** levels[-1]]
    return fine + (fine - coarse) / 3


CUBE = [((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))]
STEINER_RHOS = (0.1, 0.5, 2.0)


def _steiner_cube_errors(ctx, levels, scale_H=1.0):
    """Relative errors of A + 2 (scale_H · H) ρ + 4πρ² (library A, H) against the sampled ∂P_ρ."""
    V, F = mesh.cube()
    A, H = float(mesh.surface_area(V, F)), float(mesh.total_mean_curvature(V, F))
    errors = []
    for rho in STEINER_RHOS:
        formula = A + 2 * scale_H * H * rho + 4 * np.pi * rho**2
        name = "convergence_steiner_cube" if rho == 0.5 and ctx is not None and scale_H == 1.0 else None
        sampled = _extrapolated_offset_area(ctx, CUBE, np.full(3, 0.5), rho, levels, formula, name)
        errors.append(abs(sampled - formula) / formula)
    return errors


@check("Thm 5.7", "Steiner's formula A(S_ρ) = A + 2H(S)ρ + 4πρ² on the cube: H(S) of Def 5.3 against the area of "
       "∂P_ρ sampled from the distance function (inscribed triangulations, Richardson-extrapolated)",
       quantity="max relative error over ρ ∈ {0.1, 0.5, 2}", at_most=2e-4, quick=dict(levels=(3, 4, 5)),
       full=dict(levels=(3, 4, 5, 6)))
def steiner_cube(ctx, levels):
    return max(_steiner_cube_errors(ctx, levels))


@check("Thm 5.7", "negative control: the same sampling rejects H(S) off by 1 % in Steiner's formula on the cube",
       quantity="min relative error over ρ ∈ {0.1, 0.5, 2} with 1.01 H(S) (≥ the tolerance of steiner_cube)",
       at_least=2e-4, quick=dict(levels=(4, 5)), full=dict(levels=(4, 5, 6)))
def steiner_cube_detects_wrong_mean_curvature(ctx, levels):
    return min(_steiner_cube_errors(None, levels, scale_H=1.01))


# Rem 5.5 on the L-shaped prism [0, 2]×[0, 1]² ∪ [0, 1]×[0, 2]×[0, 1]: one concave edge (θ = −π/2).
L_PRISM = [((0.0, 0.0, 0.0), (2.0, 1.0, 1.0)), ((0.0, 0.0, 0.0), (1.0, 2.0, 1.0))]
L_CENTRE = np.full(3, 0.5)


def _l_prism():
    """The boundary of L_PRISM in unit squares, triangulated (16 vertices).  Only numpy runs on it:
    a library call would compile for its shapes."""
    occupied = np.ones((2, 2, 1), dtype=bool)
    occupied[1, 1, 0] = False
    return _voxel_boundary(occupied)


def _dented_cube(t: float = 0.5):
    """The triangulated unit cube with the corner (1, 1, 1) pushed in to (t, t, t): three concave
    edges (θ = −π/3 at t = ½) and a saddle vertex, with the shapes of `mesh.cube(True)` (compiled
    by `cube_curvatures`)."""
    V, F = mesh.cube(triangulated=True)
    return np.where(np.all(V == 1.0, axis=1, keepdims=True), t, V), F


def _solid_angle(a, b, c):
    """Signed area of the spherical triangle abc (Van Oosterom–Strackee), positive counter-clockwise
    seen from outside the sphere."""
    return 2 * np.arctan2(np.dot(a, np.cross(b, c)), 1 + np.dot(a, b) + np.dot(b, c) + np.dot(c, a))


def _gauss_image_pieces(V, F):
    """`(Σ_e l(e) θ(e), Σ_p Ω(p))` from the face normals alone: θ(e) the angle between the normals
    of the faces at e, negative where the far corner of one face lies outside the other's plane
    (a concave edge); Ω(p) the signed area of the spherical polygon of the normals around p (Sec
    5.2.1: the Gauss image of the vertex star).  With them the signed parallel surface of Remark 5.5
    (Fig 5.7) has area A + ρ Σ l θ + ρ² Σ Ω: faces shifted, cylinders and spherical pieces, negative
    where concave."""
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    across, around = {}, {}
    for f, (i, j, k) in enumerate(F):
        for u, v, w in ((i, j, k), (j, k, i), (k, i, j)):
            across[(u, v)] = (f, w)
            around[(u, v)] = (f, w)  # around vertex u: after the face (u, v, w) comes the one at (u, w)
    edge_term = 0.0
    for (u, v), (f, w) in across.items():
        if u < v:
            g, x = across[(v, u)]
            theta = np.arccos(np.clip(N[f] @ N[g], -1.0, 1.0))
            edge_term += np.linalg.norm(V[v] - V[u]) * (theta if (V[x] - V[u]) @ N[f] < 0 else -theta)
    vertex_term = 0.0
    for p in np.unique(F):
        start = next(v for (u, v) in around if u == p)
        normals, v = [], start
        while True:
            f, v = around[(p, v)]
            normals.append(N[f])
            if v == start:
                break
        vertex_term += sum(_solid_angle(normals[0], a, b) for a, b in zip(normals[1:], normals[2:]))
    return edge_term, vertex_term


def _signed_steiner_area(V, F, rho: float) -> float:
    """A + ρ Σ l θ + ρ² Σ Ω of Remark 5.5 from the face normals (`_gauss_image_pieces`), in numpy."""
    edge_term, vertex_term = _gauss_image_pieces(V, F)
    return _triangle_area(V, F) + rho * edge_term + rho**2 * vertex_term


@check("Remark 5.5", "Steiner's formula A(S_ρ) = A + 2H(S)ρ + K(S)ρ² for the signed parallel surface (Fig 5.7) of "
       "non-convex polyhedra: cylinders ρlθ and spherical pieces ρ²Ω counted from the face normals give `steiner_area` "
       "on the cube with a corner pushed in, and A = 14, H = 5π, K = 4π on the L-shaped prism",
       quantity="max relative difference over ρ ∈ {0.1, 0.5, 2} (to `steiner_area` on the dented cube, to "
       "14 + 10πρ + 4πρ² on the L-shaped prism)", at_most=1e-13, quick=dict())
def steiner_nonconvex_signed(ctx):
    dented, prism = _dented_cube(), _l_prism()
    pairs = [(_signed_steiner_area(*dented, rho), float(mesh.steiner_area(*dented, rho))) for rho in STEINER_RHOS]
    pairs += [(_signed_steiner_area(*prism, rho), 14 + 10 * np.pi * rho + 4 * np.pi * rho**2) for rho in STEINER_RHOS]
    return max(abs(pieces - reference) / reference for pieces, reference in pairs)


@check("Remark 5.5", "negative control: the boundary of the true parallel body of the L-shaped prism is not the signed "
       "surface: at the concave edge the shifted faces are cut back by 2ρl, not (π/2)ρl, and the cylinders at its ends by "
       "ρ² each, so A(∂P_ρ) = A + 2Hρ + Kρ² − (2 − π/2)ρ − (4 − π)ρ²",
       quantity="(A + 2Hρ + Kρ² − A(∂P_ρ) sampled) / ((2 − π/2)ρ + (4 − π)ρ²) farthest from 1, ρ ∈ {0.2, 0.5}",
       target=1.0, within=0.15, quick=dict(levels=(4, 5)), full=dict(levels=(5, 6)))
def steiner_nonconvex_true_body_differs(ctx, levels):
    V, F = _l_prism()
    ratios = [(_signed_steiner_area(V, F, rho) - _extrapolated_offset_area(ctx, L_PRISM, L_CENTRE, rho, levels))
              / ((2 - np.pi / 2) * rho + (4 - np.pi) * rho**2) for rho in (0.2, 0.5)]
    return max(ratios, key=lambda r: abs(r - 1.0))


def _ellipsoid(level: int, axes=(1.0, 0.8, 0.6)):
    """The icosphere(level) stretched to the ellipsoid with semi-axes `axes` (vertices on it)."""
    V, F = mesh.icosphere(level)
    return V * np.asarray(axes), F


def _smooth_ellipsoid(rho: float, axes=(1.0, 0.8, 0.6), n: int = 96):
    """`(A(S_ρ), A, ∫H dA, ∫K dA)` of the ellipsoid by Gauss–Legendre (θ) × trapezoid (φ) quadrature:
    A(S_ρ) from the area element |∂_θ y × ∂_φ y| of the normal shift y = x + ρN, N = ∇q/|∇q|
    (q = Σ x_i²/a_i²), and the classical H = (Σ a_i² − |x|²) / (2 (abc)² s^{3/2}), K = 1/((abc)² s²),
    s = Σ x_i²/a_i⁴ (outward normal: H > 0)."""
    a = np.asarray(axes)
    t, wt = np.polynomial.legendre.leggauss(n)
    theta, phi = np.pi * (t + 1) / 2, 2 * np.pi * np.arange(2 * n) / (2 * n)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    w = (np.pi / 2 * wt)[:, None] * (np.pi / n)
    x = a * np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    x_t = a * np.stack([np.cos(T) * np.cos(P), np.cos(T) * np.sin(P), -np.sin(T)], -1)
    x_p = a * np.stack([-np.sin(T) * np.sin(P), np.sin(T) * np.cos(P), 0 * T], -1)
    g = x / a**2
    N = g / np.linalg.norm(g, axis=-1, keepdims=True)

    def shifted(dx):  # ∂(x + ρN) from ∂x, with ∂N = (∂g − N⟨N, ∂g⟩)/|g|
        dg_ = dx / a**2
        return dx + rho * (dg_ - N * np.sum(N * dg_, -1, keepdims=True)) / np.linalg.norm(g, axis=-1, keepdims=True)

    area = lambda u, v: float(np.sum(w * np.linalg.norm(np.cross(u, v), axis=-1)))  # noqa: E731
    dA = w * np.linalg.norm(np.cross(x_t, x_p), axis=-1)
    s = np.sum(x**2 / a**4, -1)
    H = (np.sum(a**2) - np.sum(x**2, -1)) / (2 * np.prod(a) ** 2 * s**1.5)
    K = 1 / (np.prod(a) ** 2 * s**2)
    return area(shifted(x_t), shifted(x_p)), float(dA.sum()), float(np.sum(H * dA)), float(np.sum(K * dA))


@check("Thm 5.3", "Steiner's formula for the smooth ellipsoid: A(S_ρ) = A + 2ρ∫H dA + ρ²∫K dA with the outward normal "
       "(the reference's A − 2Hρ + Kρ² is the same formula with κ < 0 on convex surfaces, Sec 5.1)",
       quantity="max |A(S_ρ) − A − 2ρ∫H − ρ²∫K| / A(S_ρ) over ρ ∈ {0.1, 0.5, 2}, plus |∫K − 4π|", at_most=1e-12,
       quick=dict())
def steiner_smooth_ellipsoid(ctx):
    worst = 0.0
    for rho in STEINER_RHOS:
        shifted, A, H, K = _smooth_ellipsoid(rho)
        worst = max(worst, abs(shifted - A - 2 * rho * H - rho**2 * K) / shifted, abs(K - 4 * np.pi))
    return worst


@check("Def 5.3, Sec 5.3", "the total mean curvature of the icosphere tends to ∫H dA = 4π, order 2 in the edge length",
       quantity="observed order between successive levels farthest from 2 (n = 2^level)", target=2.0, within=0.1,
       quick=dict(levels=(2, 3, 4)), full=dict(levels=(1, 2, 3, 4, 5)))
def total_mean_curvature_limit(ctx, levels):
    errors = {2**k: abs(float(mesh.total_mean_curvature(*mesh.icosphere(k))) - 4 * np.pi) for k in levels}
    table = dg.limits.convergence(errors.get, sorted(errors), label="error of H(S)")
    orders = ctx.convergence(table, "convergence_total_mean_curvature").orders
    return float(max(orders, key=lambda p: abs(p - 2.0)))


# After `total_mean_curvature_limit`: the ellipsoids have the shapes of its icospheres, so
# H(S) here reuses that check's compilations (same levels at both sizes).
@check("Thm 5.3, Thm 5.7, Def 5.3", "the polyhedral Steiner area A + 2H(S)ρ + 4πρ² of ellipsoids inscribed at icosphere "
       "levels tends to the smooth A(S_ρ) (ρ = 0.3), order 2 in the edge length; H(S) tends to ∫H dA",
       quantity="observed order between successive levels farthest from 2 (of |A_ρ − A(S_ρ)| and |H(S) − ∫H dA|)",
       target=2.0, within=0.2, quick=dict(levels=(2, 3, 4)), full=dict(levels=(1, 2, 3, 4, 5)))
def steiner_smooth_limit(ctx, levels):
    rho = 0.3
    shifted, _, H, _ = _smooth_ellipsoid(rho)
    meshes = {2**k: _ellipsoid(k) for k in levels}
    H_S = {n: float(mesh.total_mean_curvature(*VF)) for n, VF in meshes.items()}
    steiner = dg.limits.convergence(lambda n: abs(_triangle_area(*meshes[n]) + 2 * H_S[n] * rho + 4 * np.pi * rho**2
                                                  - shifted), sorted(meshes), label="error of A + 2H(S)ρ + 4πρ²")
    mean = dg.limits.convergence(lambda n: abs(H_S[n] - H), sorted(meshes), label="error of H(S)")
    orders = [*ctx.convergence(steiner, "convergence_steiner_ellipsoid").orders,
              *ctx.convergence(mean, "convergence_mean_curvature_ellipsoid").orders]
    return float(max(orders, key=lambda p: abs(p - 2.0)))
