"""Block-tridiagonal KKT matrices of chain-local problems, and their solve inside `jit`.

A problem on a curve (elastica, rods, the pendulum's action) declares every density and every
`local_map` constraint on a few consecutive rows of x.  Numbered by rows — the unknowns of row
k, then the multipliers of the local constraints whose first row is k — its KKT matrix is then
block tridiagonal, apart from the rows and columns of the multipliers of global sums (a chord),
the *border*.  Grouping g consecutive rows per block (g = the largest stencil span) gives
blocks `D_k` on the diagonal and `U_k` above it (`U_kᵀ` below: K is symmetric).

Block Gaussian elimination (the block Thomas algorithm) solves such a system in O(N b³) with
two `lax.scan`s:

    S₀ = D₀,  S_k = D_k − U_{k−1}ᵀ S_{k−1}⁻¹ U_{k−1};
    forward  w_k = S_k⁻¹ (r_k − U_{k−1}ᵀ w_{k−1});
    backward x_k = w_k − S_k⁻¹ U_k x_{k+1}.

It runs on any backend (no sparse LU needed) and is `vmap`-able.  Without pivoting between
blocks it relies on every S_k being invertible, which holds for the nondegenerate critical
points of the catalogue (each S_k is itself a small KKT matrix); `_krylov.py` uses it as the
preconditioner of GMRES on the whole KKT matrix, which also accounts for the border, so an
inaccurate S_k costs iterations, not correctness.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ._sparse import SparsePattern

MAX_BLOCK = 16  # larger blocks (wide stencils, many constraints per row): use the other preconditioner


@dataclass(frozen=True, eq=False)
class Chain:
    """Where each KKT entry goes in the block-tridiagonal layout (NumPy, made once).

    - `n_blocks`, `size`: number and size b of the diagonal blocks;
    - `slot`: (n + m,) flat position `block · b + slot` of each KKT index, −1 on the border;
    - `d_at`, `d_pos` / `u_at`, `u_pos`: coalesced-value indices of K's entries in the diagonal
      blocks and in the blocks above them, and their flat positions in an (n_blocks, b, b) array;
    - `pad`: (n_blocks, b) slots that hold no unknown (a fixed entry, fewer constraints): 1 on
      their diagonal;
    - `sign`: (n_blocks, b) +1 for unknowns, −1 for multipliers (the regularisation μS).
    """

    n_blocks: int
    size: int
    slot: np.ndarray
    d_at: np.ndarray
    d_pos: np.ndarray
    u_at: np.ndarray
    u_pos: np.ndarray
    pad: np.ndarray
    sign: np.ndarray


def _constraint_rows(pattern: SparsePattern, m: int) -> np.ndarray:
    """(m,) the first row of x read by each constraint of a `local_map` term, −1 for global sums."""
    first = np.full(m, -1, dtype=np.int64)
    for tp in pattern.constraint_terms:
        if tp.term.reduce != "sum":
            first[tp.rows] = tp.term.stencil.min(axis=1)[:, None]
    return first


def chain_structure(pattern: SparsePattern, free_flat: np.ndarray, width: int) -> Chain | None:
    """The block-tridiagonal layout of the KKT matrix, or None if the problem is not a chain.

    `free_flat`: (n,) flat index into x of each free unknown; `width`: columns of x (d)."""
    n, m = pattern.n, pattern.m
    terms = pattern.energy_terms + pattern.constraint_terms
    span = max((int(np.max(tp.term.stencil.max(axis=1) - tp.term.stencil.min(axis=1))) for tp in terms
                if tp.term.stencil.size), default=0)
    group = max(span, 1)
    row = np.concatenate([free_flat // width, _constraint_rows(pattern, m)])
    border = row < 0
    block = np.where(border, -1, row // group)
    n_blocks = int(block.max()) + 1 if (~border).any() else 0
    within = np.where(np.arange(n + m) < n, (np.concatenate([free_flat, np.zeros(m, np.int64)]) % (group * width)), 0)
    # multipliers take the slots after the g·d unknown slots of their block, in index order
    cons = np.flatnonzero((np.arange(n + m) >= n) & ~border)
    order = np.argsort(block[cons], kind="stable")
    in_order = block[cons][order]
    rank = np.empty(cons.size, dtype=np.int64)
    rank[order] = np.arange(cons.size) - np.searchsorted(in_order, in_order, side="left")
    within[cons] = group * width + rank
    counts = np.bincount(block[cons], minlength=n_blocks) if cons.size else np.zeros(1, np.int64)
    size = group * width + (int(counts.max()) if n_blocks else 0)
    if n_blocks == 0 or size > MAX_BLOCK:
        return None
    rows, cols = pattern.rows.astype(np.int64), pattern.cols.astype(np.int64)
    inside = ~border[rows] & ~border[cols]
    bi, bj = block[rows], block[cols]
    if np.any(inside & (np.abs(bi - bj) > 1)):
        return None
    slot = np.where(border, -1, block * size + within)
    d = np.flatnonzero(inside & (bi == bj))
    u = np.flatnonzero(inside & (bj == bi + 1))
    used = np.zeros((n_blocks, size), bool)
    used.reshape(-1)[slot[~border]] = True
    sign = np.ones((n_blocks, size))
    sign.reshape(-1)[slot[n:][~border[n:]]] = -1.0
    return Chain(
        n_blocks=n_blocks, size=size, slot=slot,
        d_at=d.astype(np.int32), d_pos=(bi[d] * size * size + within[rows[d]] * size + within[cols[d]]).astype(np.int32),
        u_at=u.astype(np.int32), u_pos=(bi[u] * size * size + within[rows[u]] * size + within[cols[u]]).astype(np.int32),
        pad=~used, sign=sign,
    )


def chain_arrays(chain: Chain) -> dict:
    """The chain's index arrays (arguments of the compiled solver, like `_sparse.index_arrays`)."""
    names = ("slot", "d_at", "d_pos", "u_at", "u_pos")
    with jax.ensure_compile_time_eval():  # concrete even when made under a trace
        return {f"chain_{k}": jnp.asarray(np.asarray(getattr(chain, k), dtype=np.int32)) for k in names}


def factor(chain: Chain, index: dict, values, mu):
    """`(S⁻¹, S⁻¹U)`, each (n_blocks, b, b), of `K + μS` restricted to the chain (border dropped)."""
    N, b = chain.n_blocks, chain.size
    D = jnp.zeros((N * b * b,), values.dtype).at[index["chain_d_pos"]].add(values[index["chain_d_at"]]).reshape(N, b, b)
    U = jnp.zeros((N * b * b,), values.dtype).at[index["chain_u_pos"]].add(values[index["chain_u_at"]]).reshape(N, b, b)
    diagonal = jnp.asarray(chain.pad, values.dtype) + mu * jnp.asarray(chain.sign, values.dtype)
    D = D + diagonal[:, :, None] * jnp.eye(b, dtype=values.dtype)

    def eliminate(carry, blocks):
        s_inv_u_prev, u_prev = carry
        D_k, U_k = blocks
        S_inv = jnp.linalg.inv(D_k - u_prev.T @ s_inv_u_prev)
        return (S_inv @ U_k, U_k), (S_inv, S_inv @ U_k)

    zero = jnp.zeros((b, b), values.dtype)
    _, (S_inv, S_inv_U) = jax.lax.scan(eliminate, (zero, zero), (D, U))
    return S_inv, S_inv_U, U


def solve(chain: Chain, index: dict, factors, r):
    """Apply the block-tridiagonal inverse to the KKT vector r (identity on the border)."""
    S_inv, S_inv_U, U = factors
    N, b = chain.n_blocks, chain.size
    slot = index["chain_slot"]
    on_chain = slot >= 0
    rb = jnp.zeros((N * b,), r.dtype).at[jnp.where(on_chain, slot, N * b)].add(r, mode="drop").reshape(N, b)

    def forward(w_prev, blocks):
        S_inv_k, U_prev, r_k = blocks
        w = S_inv_k @ (r_k - U_prev.T @ w_prev)
        return w, w

    U_prev = jnp.concatenate([jnp.zeros((1, b, b), U.dtype), U[:-1]])
    _, w = jax.lax.scan(forward, jnp.zeros((b,), r.dtype), (S_inv, U_prev, rb))

    def backward(x_next, blocks):
        w_k, S_inv_U_k = blocks
        x = w_k - S_inv_U_k @ x_next
        return x, x

    _, x = jax.lax.scan(backward, jnp.zeros((b,), r.dtype), (w, S_inv_U), reverse=True)
    return jnp.where(on_chain, x.reshape(-1)[jnp.where(on_chain, slot, 0)], r)
