"""Smoothed-aggregation algebraic multigrid for the Krylov back end: the hierarchy is made on the
host once per sparsity pattern, the cycle runs in JAX inside `jit`.

**Hierarchy** (Vaněk, Mandel & Brezina 1996, *Algebraic multigrid by smoothed aggregation for
second and fourth order elliptic problems*).  The unknowns are grouped by the row of `x` they
belong to (a vertex: `w` = 3 coordinates), so the Hessian `H` is a matrix of w×w blocks; a
row with some entries fixed is padded with decoupled unit unknowns.  On each level ℓ, with
`A_ℓ` a block matrix:

- *aggregation*: the block graph of `A_ℓ`'s pattern is cut into aggregates (a root and its
  neighbours; `pyamg.aggregation.standard_aggregation` on the pattern of ones, so that it
  depends on the pattern only);
- *tentative prolongator*: `T` restricts the near-null space `B_ℓ` to each aggregate,
  orthonormalised there (`pyamg`'s `fit_candidates`: `B_ℓ = T B_ℓ₊₁`).  On the finest level
  `B₀` holds the translations (a constant per component) and the infinitesimal rotations of
  the rows of `x` (`e_k × x_i` for w = 3, `(−x_i², x_i¹)` for w = 2): the rigid motions, which
  a Hessian of an energy invariant under Euclidean motions annihilates up to boundary terms;
- *smoothed prolongator*: `P = (I − ω |D|⁺A_ℓ) T`, `ω = 4/(3 ρ(|D|⁺A_ℓ))`, `|D|` the
  absolute value of the block diagonal (below);
- *Galerkin operator*: `A_ℓ₊₁ = Pᵀ A_ℓ P`.

Aggregates and `T` depend on the pattern (and on the rows of `x0`, for the rotations) and are
made once per pattern (`_cache.derived`); everything that depends on the Hessian (`P`, the
Galerkin operators, the smoothers) is recomputed inside `jit` at every Newton step, by block
sparse products whose index maps (which pair of blocks goes to which result block) are
computed here once, symbolically: `A T` (one term per block of A), `Y = A P` and `Pᵀ Y`.

**Cycle.**  On each level ν = 2 block-Jacobi sweeps `x ← x + ω |D|⁻¹ (b − A x)` before and
after the coarse correction, with `|D|` the absolute value of each diagonal block (its
eigenvalues made positive) and `ω = 1/ρ̃`, ρ̃ a power-iteration estimate of `ρ(|D|⁻¹A)`; on the
coarsest level the pseudo-inverse of `|A_L|` (dense, by `eigh`).  The coarse correction on the
intermediate levels is the AMLI cycle of Axelsson & Vassilevski (1989): the fixed polynomial
`p(B A) B` of degree 2 in the coarse cycle B with `1 − t p(t) = (1 − t/θ)²`, θ = (1 + α)/2,
the best such polynomial that stays in [0, 1] on the spectrum [α, 1] of a coarse cycle, so
that the recursion keeps every level's spectrum in (0, 1].  A V-cycle's iteration count grows
with the number of levels on the area Hessian, whose near-kernel (the tangential motions,
stiff in no direction) the rigid motions do not span; the polynomial restores the two-level
method's convergence, which does not depend on the mesh size.

Every part is symmetric, and positive definite for *every* symmetric `A`, definite or not:
the symmetrised smoother `ω |D|^{-½} f(Â) |D|^{-½}`, `f(λ) = (1 − (1 − ωλ)^{2ν})/λ`, is positive
for every eigenvalue `λ < 2/ω` of `Â = |D|^{-½}A|D|^{-½}` (negative ones included); the
coarse correction is a congruence of a positive definite coarse cycle; and
`p(t) = (1 − (1 − t/θ)²)/t > 0` for every `t < 2θ = 1 + α`, t ≠ 0, negative t included.  So
the cycle is a valid preconditioner for MINRES (Paige & Saunders 1975) on an indefinite
Hessian too.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ._cache import derived

MAX_COARSE = 300  # unknowns of the coarsest level (a dense eigendecomposition per Newton step)
MAX_LEVELS = 10
SWEEPS = 2  # block-Jacobi sweeps before and after the coarse correction
POWER_STEPS = 15  # power iterations for ρ(|D|⁻¹A)
AMLI_ALPHA = 0.1  # the coarse polynomial's lower spectral bound α (module docstring)
PINV_CUT = 1e-12  # eigenvalues below this, relative to the block's largest, are dropped (pseudo-inverse)


@dataclass(frozen=True, eq=False)
class Hierarchy:
    """The static part of an aggregation hierarchy: per level ℓ the number of block rows
    `sizes[ℓ]` and the block size `blocks[ℓ]`; `arrays` holds its index maps and the blocks of
    the tentative prolongators (host NumPy; `device_arrays` copies them to the device once)."""

    width: int
    sizes: tuple
    blocks: tuple
    products: tuple  # blocks of Y = A_ℓ P_ℓ per level
    arrays: dict

    @property
    def levels(self) -> int:
        return len(self.sizes)


# --------------------------------------------------------------------------------------------
# host: structure


def galerkin_terms(a_rows, a_cols, p_rows, p_cols, n_coarse: int):
    """Symbolic `Pᵀ A P` for block COO patterns: the index maps of its two products.

    `Y = A P`: term t adds `A[a[t]] P[p[t]]` to `Y[y[t]]`; `Z = Pᵀ Y`: term s adds
    `P[p2[s]]ᵀ Y[y2[s]]` to `Z[z[s]]`.  Returns the maps and the COO pattern of Y and Z,
    each sorted by (row, column).
    """
    n_rows = int(max(a_rows.max(), p_rows.max())) + 1
    p_order = np.argsort(p_rows, kind="stable")
    p_ptr = np.concatenate([[0], np.cumsum(np.bincount(p_rows, minlength=n_rows))])
    count = p_ptr[a_cols + 1] - p_ptr[a_cols]
    a = np.repeat(np.arange(a_rows.size), count)
    offset = np.arange(a.size) - np.repeat(np.cumsum(count) - count, count)
    p = p_order[p_ptr[a_cols[a]] + offset]
    y_keys, y = np.unique(a_rows[a].astype(np.int64) * n_coarse + p_cols[p], return_inverse=True)
    y_rows, y_cols = y_keys // n_coarse, y_keys % n_coarse

    y_ptr = np.concatenate([[0], np.cumsum(np.bincount(y_rows, minlength=n_rows))])  # Y is sorted by row
    count = y_ptr[p_rows + 1] - y_ptr[p_rows]
    p2 = np.repeat(np.arange(p_rows.size), count)
    offset = np.arange(p2.size) - np.repeat(np.cumsum(count) - count, count)
    y2 = y_ptr[p_rows[p2]] + offset
    z_keys, z = np.unique(p_cols[p2].astype(np.int64) * n_coarse + y_cols[y2], return_inverse=True)
    return {"a": a, "p": p, "y": y, "p2": p2, "y2": y2, "z": z}, (y_rows, y_cols), (z_keys // n_coarse, z_keys % n_coarse)


def _segment_sum(values: np.ndarray, segments: np.ndarray, n: int) -> np.ndarray:
    """`out[s] = Σ_{t: segments[t] = s} values[t]` for blocks `values` (t, r, c), by bincount."""
    size = int(np.prod(values.shape[1:]))
    flat = (segments[:, None].astype(np.int64) * size + np.arange(size)).ravel()
    return np.bincount(flat, weights=values.ravel(), minlength=n * size).reshape((n,) + values.shape[1:])


def galerkin_values(maps, n_y: int, n_z: int, A, P):
    """`Pᵀ A P` on the host (NumPy) by the maps of `galerkin_terms`: the reference of `galerkin`."""
    Y = _segment_sum(np.einsum("tab,tbc->tac", A[maps["a"]], P[maps["p"]]), maps["y"], n_y)
    return _segment_sum(np.einsum("tba,tbc->tac", P[maps["p2"]], Y[maps["y2"]]), maps["z"], n_z)


def prolongator_pattern(a_rows, a_cols, aggregate: np.ndarray, n_agg: int):
    """The block pattern of `P = (I − ω D⁻¹A) T` (block (i, J) where i or a neighbour j of i
    lies in aggregate J; `aggregate[j]` = −1 for an unaggregated row), sorted by (row, column),
    and for each block of A the index of the P block its product with T adds to."""
    keep = aggregate[a_cols] >= 0
    keys = a_rows.astype(np.int64) * n_agg + np.where(keep, aggregate[a_cols], 0)
    unique, at = np.unique(keys[keep], return_inverse=True)
    target = np.zeros(a_rows.size, np.int64)
    target[keep] = at
    return unique // n_agg, unique % n_agg, target


def pad_value(diagonal):
    """The diagonal entry of a padded (fixed) unknown: the mean |diagonal entry| of the free ones,
    `diagonal` the diagonals of the fine diagonal blocks before padding (zeros at the pads)."""
    xp = jnp if isinstance(diagonal, jax.Array) else np
    return xp.sum(xp.abs(diagonal)) / xp.maximum(xp.sum(diagonal != 0), 1)


def near_null_space(coords: np.ndarray | None, n_blocks: int, width: int) -> np.ndarray:
    """The rigid motions of the rows of x: translations, and for w = 2 or 3 the infinitesimal
    rotations of the coordinates `coords` (n_blocks × w, centred), as columns."""
    B = [np.tile(np.eye(width), (n_blocks, 1))]
    if coords is not None and width in (2, 3):
        y = coords - coords.mean(0)
        if width == 3:
            B.append(np.stack([np.cross(e, y).ravel() for e in np.eye(3)], 1))
        else:
            B.append(np.stack([-y[:, 1], y[:, 0]], 1).reshape(-1, 1))
    return np.concatenate(B, 1)


def build_hierarchy(free: np.ndarray, width: int, h_rows, h_cols, coords=None) -> Hierarchy:
    """The aggregation hierarchy of a Hessian with COO pattern `(h_rows, h_cols)` over the free
    unknowns at flat positions `free` of an array with rows of `width` entries; `coords`: the
    rows of x, for the rotations in the near-null space (None: translations only)."""
    from pyamg.aggregation.aggregate import standard_aggregation
    from pyamg.aggregation.tentative import fit_candidates
    import scipy.sparse as sp

    w = width
    block_rows, block = np.unique(free // w, return_inverse=True)
    comp = free % w
    nb = block_rows.size
    # the fine level: blocks of H (and the diagonal blocks, always present)
    br, bc = block[h_rows], block[h_cols]
    keys, at = np.unique(np.concatenate([br * nb + bc, np.arange(nb) * (nb + 1)]), return_inverse=True)
    a_rows, a_cols = keys // nb, keys % nb
    fine_target = (at[: br.size] * w + comp[h_rows]) * w + comp[h_cols]
    diag = np.searchsorted(keys, np.arange(nb) * (nb + 1))
    has = np.zeros((nb, w), bool)
    has[block, comp] = True
    pad_block, pad_comp = np.nonzero(~has)
    arrays = {"fine_target": fine_target, "fine_pad": (diag[pad_block] * w + pad_comp) * w + pad_comp,
              "fine_dofs": block * w + comp}  # the padded position of each free unknown
    B = near_null_space(None if coords is None else coords[block_rows], nb, w)

    sizes, blocks, products = [nb], [w], []
    level = 0
    while sizes[-1] * blocks[-1] > MAX_COARSE and level + 1 < MAX_LEVELS:
        n_rows = sizes[-1]
        graph = sp.csr_matrix((np.ones(a_rows.size), (a_rows, a_cols)), shape=(n_rows, n_rows))
        agg = standard_aggregation(graph)[0].tocsr()
        n_agg = agg.shape[1]
        if n_agg >= n_rows or n_agg == 0:
            break
        arrays.update({f"a{level}_rows": a_rows, f"a{level}_cols": a_cols, f"a{level}_diag": diag})
        T, B = fit_candidates(agg, B)  # T: one (block, candidates) block per aggregated row
        aggregate = np.full(n_rows, -1, np.int64)
        rows = np.repeat(np.arange(n_rows), np.diff(agg.indptr))
        aggregate[rows] = agg.indices
        T = T.tobsr(blocksize=(w if level == 0 else blocks[-1], B.shape[1]))
        t_values = np.zeros((n_rows,) + T.blocksize)
        t_values[np.repeat(np.arange(n_rows), np.diff(T.indptr))] = T.data
        p_rows, p_cols, t_target = prolongator_pattern(a_rows, a_cols, aggregate, n_agg)
        t_self = np.searchsorted(p_rows * n_agg + p_cols, np.arange(n_rows) * n_agg + np.maximum(aggregate, 0))
        maps, (y_rows, _), (a_rows, a_cols) = galerkin_terms(a_rows, a_cols, p_rows, p_cols, n_agg)
        arrays.update({f"p{level}_rows": p_rows, f"p{level}_cols": p_cols, f"t{level}_values": t_values,
                       f"t{level}_target": t_target, f"t{level}_self": t_self})
        arrays.update({f"g{level}_{k}": v for k, v in maps.items()})
        products.append(y_rows.size)
        diag = np.searchsorted(a_rows * n_agg + a_cols, np.arange(n_agg) * (n_agg + 1))
        sizes.append(n_agg)
        blocks.append(B.shape[1])
        level += 1
    arrays.update({f"a{level}_rows": a_rows, f"a{level}_cols": a_cols, f"a{level}_diag": diag})
    return Hierarchy(w, tuple(sizes), tuple(blocks), tuple(products), arrays)


def device_arrays(hierarchy: Hierarchy) -> dict:
    """The hierarchy's arrays on the device (int32 indices, float64 tentative prolongators), made once."""

    def make():
        with jax.ensure_compile_time_eval():
            return {
                f"amg_{k}": jnp.asarray(v) if v.dtype.kind == "f" else jnp.asarray(v.astype(np.int32))
                for k, v in hierarchy.arrays.items()
            }

    return derived(hierarchy, "device", make)


# --------------------------------------------------------------------------------------------
# device: values per Newton step, and the cycle


def block_matvec(values, rows, cols, x, n_rows: int):
    """`y_i = Σ_j A_ij x_j` for a block COO matrix; x is (blocks, block size)."""
    return jax.ops.segment_sum(jnp.einsum("tab,tb->ta", values, x[cols]), rows, num_segments=n_rows)


def abs_pinv_blocks(blocks):
    """`|D|⁺ = V |Λ|⁺ Vᵀ` of each symmetric block `D = V Λ Vᵀ` (eigenvalues below `PINV_CUT`
    times the block's largest dropped): symmetric positive semidefinite, definite where D is
    nonsingular."""
    lam, V = jnp.linalg.eigh(0.5 * (blocks + jnp.swapaxes(blocks, -1, -2)))
    big = jnp.max(jnp.abs(lam), axis=-1, keepdims=True)
    keep = jnp.abs(lam) > PINV_CUT * big
    inv = jnp.where(keep, 1.0 / jnp.where(keep, jnp.abs(lam), 1.0), 0.0)
    return jnp.einsum("...ij,...j,...kj->...ik", V, inv, V)


def spectral_radius(apply, n_rows: int, block: int, dtype):
    """`ρ(M)` estimated by `POWER_STEPS` power iterations from a fixed pseudo-random start."""
    x = jax.random.normal(jax.random.key(0), (n_rows, block), dtype)

    def step(_, x):
        y = apply(x)
        return y / jnp.maximum(jnp.linalg.norm(y), jnp.finfo(dtype).tiny)

    x = jax.lax.fori_loop(0, POWER_STEPS, step, x / jnp.linalg.norm(x))
    return jnp.linalg.norm(apply(x))


@dataclass(frozen=True)
class Levels:
    """One Newton step's hierarchy values: the block operators `A_ℓ`, the prolongators `P_ℓ`,
    `|D_ℓ|⁺`, the sweep weights `ω_ℓ`, and the pseudo-inverse of `|A_L|` on the coarsest level."""

    A: tuple
    P: tuple
    dinv: tuple
    omega: tuple
    coarse: object


def smoothed_prolongator(h: Hierarchy, ix: dict, level: int, A, dinv, omega):
    """`P = T − ω |D|⁺ (A T)` on the pattern of `prolongator_pattern`; `A T` has one term per
    block of A (T has one block per row)."""
    T = ix[f"amg_t{level}_values"]
    n_p = ix[f"amg_p{level}_rows"].shape[0]
    AT = jax.ops.segment_sum(jnp.einsum("tab,tbc->tac", A, T[ix[f"amg_a{level}_cols"]]), ix[f"amg_t{level}_target"],
                             num_segments=n_p)
    P = jax.ops.segment_sum(T, ix[f"amg_t{level}_self"], num_segments=n_p)
    return P - omega * jnp.einsum("nab,nbc->nac", dinv[ix[f"amg_p{level}_rows"]], AT)


def galerkin(h: Hierarchy, ix: dict, level: int, A, P):
    """`A_ℓ₊₁ = Pᵀ A_ℓ P` by the symbolic maps of `galerkin_terms`: `Y = A P`, then `Pᵀ Y`."""
    g = {k: ix[f"amg_g{level}_{k}"] for k in ("a", "p", "y", "p2", "y2", "z")}
    Y = jax.ops.segment_sum(jnp.einsum("tab,tbc->tac", A[g["a"]], P[g["p"]]), g["y"], num_segments=h.products[level])
    n_z = ix[f"amg_a{level + 1}_rows"].shape[0]
    return jax.ops.segment_sum(jnp.einsum("tba,tbc->tac", P[g["p2"]], Y[g["y2"]]), g["z"], num_segments=n_z)


def smoother(h: Hierarchy, ix: dict, level: int, A):
    """`(|D|⁺, ρ̃)`: the pseudo-inverse of the absolute diagonal blocks and the power-iteration
    estimate of `ρ(|D|⁺A)`."""
    rows, cols = ix[f"amg_a{level}_rows"], ix[f"amg_a{level}_cols"]
    dinv = abs_pinv_blocks(A[ix[f"amg_a{level}_diag"]])
    n_rows = h.sizes[level]

    def apply(x):
        return jnp.einsum("nab,nb->na", dinv, block_matvec(A, rows, cols, x, n_rows))

    return dinv, spectral_radius(apply, n_rows, h.blocks[level], A.dtype)


def setup(h: Hierarchy, ix: dict, h_values, mu) -> Levels:
    """The levels for the Hessian entries `h_values` (in the order of the pattern's `h_at`) plus
    `μ I`: per level the smoother, the smoothed prolongator and the Galerkin product; the
    pseudo-inverse of the coarsest operator."""
    w = h.width
    dtype = h_values.dtype
    nnz = ix["amg_a0_rows"].shape[0]  # blocks of the fine level
    A = jnp.zeros((nnz * w * w,), dtype).at[ix["amg_fine_target"]].add(h_values)
    A = A.at[ix["amg_fine_pad"]].set(pad_value(jnp.diagonal(A.reshape(nnz, w, w)[ix["amg_a0_diag"]], axis1=1, axis2=2)))
    A = A.reshape(nnz, w, w).at[ix["amg_a0_diag"]].add(mu * jnp.eye(w, dtype=dtype))
    As, dinvs, omegas, Ps = [A], [], [], []
    tiny = jnp.finfo(dtype).tiny
    for level in range(h.levels - 1):
        dinv, rho = smoother(h, ix, level, As[-1])
        P = smoothed_prolongator(h, ix, level, As[-1], dinv, 4.0 / (3.0 * jnp.maximum(rho, tiny)))
        dinvs.append(dinv)
        omegas.append(1.0 / jnp.maximum(rho, tiny))
        Ps.append(P)
        As.append(galerkin(h, ix, level, As[-1], P))
    L = h.levels - 1
    r = h.blocks[L]
    rows, cols = ix[f"amg_a{L}_rows"], ix[f"amg_a{L}_cols"]
    size = h.sizes[L] * r
    dense_rows = (rows[:, None, None] * r + jnp.arange(r)[None, :, None]) + jnp.zeros((1, 1, r), rows.dtype)
    dense_cols = (cols[:, None, None] * r + jnp.arange(r)[None, None, :]) + jnp.zeros((1, r, 1), cols.dtype)
    dense = jnp.zeros((size, size), dtype).at[dense_rows, dense_cols].add(As[L])
    return Levels(tuple(As), tuple(Ps), tuple(dinvs), tuple(omegas), abs_pinv_blocks(dense))


def cycle(h: Hierarchy, ix: dict, lv: Levels, b, level: int = 0):
    """One symmetric cycle `B_ℓ b` on level ℓ (module docstring); b is (blocks, block size)."""
    L = h.levels - 1
    if level == L:
        shape = b.shape
        return (lv.coarse @ b.ravel()).reshape(shape)
    A, dinv, omega = lv.A[level], lv.dinv[level], lv.omega[level]
    rows, cols = ix[f"amg_a{level}_rows"], ix[f"amg_a{level}_cols"]
    p_rows, p_cols, P = ix[f"amg_p{level}_rows"], ix[f"amg_p{level}_cols"], lv.P[level]
    n_rows, n_coarse = h.sizes[level], h.sizes[level + 1]

    def matvec(x):
        return block_matvec(A, rows, cols, x, n_rows)

    def sweep(_, x):
        return x + omega * jnp.einsum("nab,nb->na", dinv, b - matvec(x))

    x = jax.lax.fori_loop(0, SWEEPS, sweep, jnp.zeros_like(b))
    r = b - matvec(x)
    rc = jax.ops.segment_sum(jnp.einsum("tba,tb->ta", P, r[p_rows]), p_cols, num_segments=n_coarse)
    xc = coarse_correction(h, ix, lv, rc, level + 1)
    x = x + jax.ops.segment_sum(jnp.einsum("tab,tb->ta", P, xc[p_cols]), p_rows, num_segments=n_rows)
    return jax.lax.fori_loop(0, SWEEPS, sweep, x)


def coarse_correction(h: Hierarchy, ix: dict, lv: Levels, r, level: int):
    """`A_ℓ⁻¹ r` approximated: exactly (pseudo-inverse) on the coarsest level, else by the AMLI
    polynomial of degree 2, `p(B A) B r` with `1 − t p(t) = (1 − t/θ)²`, θ = (1 + α)/2: two
    Richardson steps `x ← x + B(r − A x)/θ` with the cycle B of that level."""
    if level == h.levels - 1:
        return cycle(h, ix, lv, r, level)
    A, rows, cols = lv.A[level], ix[f"amg_a{level}_rows"], ix[f"amg_a{level}_cols"]
    theta = (1.0 + AMLI_ALPHA) / 2.0

    def step(_, x):
        return x + cycle(h, ix, lv, r - block_matvec(A, rows, cols, x, h.sizes[level]), level) / theta

    return jax.lax.fori_loop(0, 2, step, jnp.zeros_like(r))


def precondition(h: Hierarchy, ix: dict, lv: Levels, r):
    """`B r` for a vector r over the free unknowns: padded to the blocks, one cycle, restricted."""
    dofs = ix["amg_fine_dofs"]
    padded = jnp.zeros((h.sizes[0] * h.width,), r.dtype).at[dofs].set(r)
    return cycle(h, ix, lv, padded.reshape(h.sizes[0], h.width)).ravel()[dofs]


__all__ = ["Hierarchy", "build_hierarchy", "device_arrays", "setup", "precondition", "galerkin_terms"]
