"""The catenoid's fold (Sec 6.4; Keller's pseudo-arclength continuation, `solvers.continuation`):
the simplicial catenoid (Thm 6.7) spanned by the unit circles at z = ±H, followed in the
half-distance H from H = 0.45 on the stable catenoid through the fold and back to H = 0.45 on the
unstable one.  Smooth comparison: the catenoids r = c cosh(z/c) with c cosh(H/c) = 1, of area
π c (2H + c sinh(2H/c)); with t = H/c they are c = 1/cosh t, H = t/cosh t, the stable one
(Morse index 0, larger neck) for t < t*, the unstable one (index 1) for t > t*, t* tanh t* = 1,
meeting at the fold H* = t*/cosh t* ≈ 0.6627.

    python examples/catenoid_fold.py [--out DIR] [--tiny]
"""

from __future__ import annotations

import numpy as np
from _common import output_dir, run
from scipy.optimize import brentq

import ddgjax as dg
from ddgjax.plot import save_figure
from ddgjax.verify.checks.ext_continuation import H_START, catenoid_branch, fold_half_distance, neck_radius


def smooth_catenoids(H_min: float, samples: int = 200) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(H, area, neck c)` along both smooth catenoids with H ≥ H_min, in the order of t = H/c
    (the stable one first, through the fold, then the unstable one)."""
    t_fold = brentq(lambda t: t * np.tanh(t) - 1.0, 0.5, 2.0)
    half_distance = lambda t: t / np.cosh(t) - H_min
    t = np.linspace(brentq(half_distance, 1e-6, t_fold), brentq(half_distance, t_fold, 10.0), samples)
    c = 1.0 / np.cosh(t)
    H = t * c
    return H, np.pi * c * (2 * H + c * np.sinh(2 * H / c)), c


def fold_diagram(branch, n: int, path):
    """Area and neck radius against H: the branch's stable points (index 0) and unstable points
    (index 1) in two styles, joined at the refined fold, over the smooth catenoids."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fold = branch.folds[0]
    neck = neck_radius(branch, n)
    fold_neck = neck_radius(branch._replace(x=np.asarray(fold.x)[None]), n)[0]
    stable, unstable = branch.index == 0, branch.index == 1
    H_smooth, area_smooth, c_smooth = smooth_catenoids(H_START - 0.02)
    H_star = fold_half_distance()
    t_star = brentq(lambda t: t * np.tanh(t) - 1.0, 0.5, 2.0)
    c_star = 1.0 / np.cosh(t_star)
    area_star = np.pi * c_star * (2 * H_star + c_star * np.sinh(2 * H_star / c_star))

    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.8))
    for ax, values, at_fold, smooth, smooth_fold, name in (
            (axes[0], branch.energy, fold.energy, area_smooth, area_star, "area"),
            (axes[1], neck, fold_neck, c_smooth, c_star, "neck radius")):
        ax.plot(H_smooth, smooth, "-", color="0.6", lw=1, label="smooth catenoids")
        ax.plot(np.append(branch.p[stable], fold.p), np.append(values[stable], at_fold), "o-", color="tab:blue",
                ms=4, label="index 0 (stable)")
        ax.plot(np.insert(branch.p[unstable], 0, fold.p), np.insert(values[unstable], 0, at_fold), "s--",
                color="tab:red", ms=4, mfc="none", label="index 1 (unstable)")
        ax.plot([fold.p], [at_fold], "k*", ms=11, label=f"fold H = {fold.p:.4f}")
        ax.plot([H_star], [smooth_fold], "kx", ms=8, label=f"smooth fold H* = {H_star:.4f}")
        ax.set_xlabel("half-distance H")
        ax.set_ylabel(name)
        ax.legend(fontsize=7)
    axes[0].set_title(f"catenoid fold, cylinder({n})")
    return save_figure(fig, path, dpi=120)


def main(out=None, tiny: bool = False):
    out = output_dir(out)
    H_star = fold_half_distance()
    print(f"smooth fold: H* = {H_star:.10f} (2H* = {2 * H_star:.6f})")
    ns = (6,) if tiny else (6, 8, 12, 16)
    rows = ["| n | points | fold H | H* | error % | index along the branch |", "|---:|---:|---:|---:|---:|:---|"]
    for n in ns:
        branch = catenoid_branch(n)
        fold = branch.folds[0]
        print(f"n = {n:2d}: {len(branch.p)} points, {branch.stopped}, fold at H = {fold.p:.8f} "
              f"(refined: {fold.refined}), area there {fold.energy:.8f}, index changes {len(branch.index_changes)}")
        rows.append(f"| {n} | {len(branch.p)} | {fold.p:.6f} | {H_star:.6f} | {100 * (fold.p / H_star - 1):+.3f} | "
                    f"{''.join(map(str, branch.index))} |")
    print("\n".join(rows))
    if len(ns) > 1:
        errors = {n: abs(catenoid_branch(n).folds[0].p - H_star) for n in ns}
        print(dg.limits.convergence(errors.get, list(ns), label="|H_fold − H*|").to_markdown())
    return [fold_diagram(branch, n, out / "catenoid_fold.png")]


if __name__ == "__main__":
    run(main, __doc__)
