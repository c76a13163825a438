"""Polyhedral curvature (Sec 5: Gauss–Bonnet, mean curvature, Steiner)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import mesh
from ddgjax.verify import check

from .sec4_topology import BUILTIN


@check("Thm 5.6, Remark 5.4", "Gauss–Bonnet: Σ K(p) over interior vertices + Σ φ(p) over boundary vertices = 2πχ",
       quantity="max |Σ K − 2πχ| over the built-in meshes", at_most=1e-12, quick=dict())
def gauss_bonnet_builtin(ctx):
    worst = 0.0
    for name in BUILTIN:
        V, F = getattr(mesh, name)()
        worst = max(worst, abs(float(jnp.sum(mesh.angle_defect(V, F))) - 2 * np.pi * mesh.euler_characteristic(F)))
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


@check("Thm 5.7", "Steiner's formula A(S_ρ) = A + 2Hρ + 4πρ² on the cube, against its pieces",
       quantity="max relative error over ρ ∈ {0.1, 0.5, 2}", at_most=1e-12, quick=dict())
def steiner_cube(ctx):
    V, F = mesh.cube()
    pieces = lambda rho: 6 + 12 * (np.pi / 2) * rho + 8 * (4 * np.pi * rho**2 / 8)  # noqa: E731
    return max(abs(float(mesh.steiner_area(V, F, rho)) - pieces(rho)) / pieces(rho) for rho in (0.1, 0.5, 2.0))


@check("Def 5.3, Sec 5.3", "the total mean curvature of the icosphere tends to ∫H dA = 4π, order 2 in the edge length",
       quantity="observed order between successive levels farthest from 2 (n = 2^level)", target=2.0, within=0.1,
       quick=dict(levels=(2, 3, 4)), full=dict(levels=(1, 2, 3, 4, 5)))
def total_mean_curvature_limit(ctx, levels):
    errors = {2**k: abs(float(mesh.total_mean_curvature(*mesh.icosphere(k))) - 4 * np.pi) for k in levels}
    table = dg.limits.convergence(errors.get, sorted(errors), label="error of H(S)")
    orders = ctx.convergence(table, "convergence_total_mean_curvature").orders
    return float(max(orders, key=lambda p: abs(p - 2.0)))
