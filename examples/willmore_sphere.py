"""The Willmore energy W = ∫H² dA of simplicial spheres (`energies.willmore`; Thm 6.7, Willmore's
theorem, Bobenko 2005).  With the mean curvature derived from the area, H_i = ⟨∇_i A, N_i⟩ / 2A_i
(`willmore.helfrich`), W of the icospheres tends to 4π (the round sphere's value) at order 2 in
the edge length, from below.  The mean curvature of a perturbed sphere is drawn on its faces,
and Bobenko's conformal energy Σ_e β_e − π|V| (`willmore.conformal`) is shown to be Möbius
invariant: unchanged by an inversion in a sphere, while ∫H² dA changes.

    python examples/willmore_sphere.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import jax
import numpy as np
from _common import output_dir, run

import ddgjax as dg
from ddgjax.plot.surface import surface
from ddgjax.verify.checks.ext_willmore import random_moebius
from energies import willmore


def energy(problem) -> float:
    """The problem's energy at its x0."""
    return float(jax.jit(problem.energy)(problem.x0, problem.params))


def icospheres(levels) -> dict:
    """{level: W} of `icosphere(level)`, printed with the error against 4π."""
    W = {}
    for level in levels:
        V, F = dg.mesh.icosphere(level)
        W[level] = energy(willmore.helfrich(V, F))
        print(f"icosphere({level}): nv = {len(V):5d}, W = {W[level]:.10f}, W − 4π = {W[level] - 4 * np.pi:+.3e}")
    return W


def perturbed_sphere(level: int) -> tuple[np.ndarray, np.ndarray]:
    """The icosphere with radius 0.7 + 0.8 z² + 0.1 x y (in the direction (x, y, z) of the unit
    sphere): a peanut whose waist is saddle-shaped (H < 0 there), so the colours show both signs."""
    V, F = dg.mesh.icosphere(level)
    V = np.asarray(V)
    x, y, z = V.T
    return V * (0.7 + 0.8 * z**2 + 0.1 * x * y)[:, None], np.asarray(F)


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    W = icospheres((1, 2, 3) if tiny else (1, 2, 3, 4, 5))
    table = dg.limits.convergence(lambda n: abs(W[int(np.log2(n))] - 4 * np.pi), [2**k for k in W],
                                  label="|W − 4π| (n = 2^level)")
    print(table.to_markdown())

    V, F = perturbed_sphere(2 if tiny else 4)
    H, A = willmore.mean_curvature(V, F)
    print(f"perturbed sphere: nv = {len(V)}, H from {H.min():.4f} to {H.max():.4f}, "
          f"∫H² dA = {np.sum(H**2 * A):.8f} ≥ 4π = {4 * np.pi:.8f}")

    X = random_moebius(V, np.random.default_rng(0))  # an inversion, a rotation, a scale and a translation
    before, after = energy(willmore.conformal(V, F)), energy(willmore.conformal(X, F))
    h_before, h_after = energy(willmore.helfrich(V, F)), energy(willmore.helfrich(X, F))
    print(f"Möbius invariance: conformal W = {before:.12f} before, {after:.12f} after a random inversion "
          f"(|ΔW|/W = {abs(after - before) / before:.1e}); the discrete ∫H² dA "
          f"= {h_before:.6f} before, {h_after:.6f} after (Möbius invariant only in the smooth limit)")

    # surface() colours faces: the vertex mean curvatures averaged over each face's three vertices
    return [surface(V, F, out / "willmore_sphere.png", color_by=H[F].mean(axis=1), label="mean curvature H",
                    title=f"perturbed sphere: ∫H² dA = {h_before:.4f}"),
            table.plot(out / "willmore_convergence.png", title="Willmore energy of icospheres → 4π")]


if __name__ == "__main__":
    run(main, __doc__)
