"""Newton–Krylov: the KKT system solved by preconditioned Krylov methods, inside `jit`.

`method="krylov"`.  Nothing is factorised, so the whole solver stays inside `jit` on any backend
(GPUs and TPUs have no sparse LU that `jit`, `vmap` and `grad` go through); the linear algebra
is matrix–vector products and a few vector reductions per iteration.

**The tangent-space solve** (every problem that is not a chain, below).  For `K d = b` with `K = [[H, −Jᵀ], [−J, 0]]` (`_kkt.py`), i.e.

    H d₁ − Jᵀ d₂ = b₁,     −J d₁ = b₂,

write `d₁ = dₙ + dₜ` with the normal part `dₙ = −M⁻¹Jᵀ S⁻¹ b₂` (so `J dₙ = −b₂`) and the
tangential part `dₜ ∈ ker J`, `S = J M⁻¹ Jᵀ`.  Then `dₜ` solves the reduced system
`Zᵀ H Z ξ = Zᵀ (b₁ − H dₙ)` on `ker J = range Z`, by MINRES (Paige & Saunders 1975: the reduced
Hessian is indefinite at a saddle point such as Euler's figure eight, so CG would not do)
preconditioned by the projection

    P r = M⁻¹ (r − Jᵀ S⁻¹ J M⁻¹ r),

the constraint preconditioner of Gould, Hribar & Nocedal (2001): symmetric, positive
semidefinite, with range `ker J`, so every Krylov iterate stays in the tangent space and the
residual is measured only in tangent directions.  Finally `d₂ = S⁻¹ J M⁻¹ (H d₁ − b₁)` (the
residual `H d₁ − b₁` lies in `range Jᵀ` at convergence).  Solves with `S` (m × m, symmetric
positive definite when the constraints are independent) are by CG with Jacobi preconditioning:
for the catalogue's constraints (unit vectors, one per cell, plus a few global sums such as a
chord) `S` is diagonal plus a low-rank border and CG converges in a few iterations.  Without
constraints the method is MINRES preconditioned by `M⁻¹`.  Unpreconditioned Krylov methods on
the full, indefinite KKT matrix do not converge at these sizes (`SOLVER-NOTES.md`).

**Chains.**  For a problem on a curve (every stencil on a few consecutive rows of x: elastica,
rods, the pendulum's action) the KKT matrix is block tridiagonal apart from the rows of global
sums (a chord), and `_banded` solves the block-tridiagonal part exactly by block elimination
(two `lax.scan`s).  The solve is then GMRES on the whole KKT matrix preconditioned by it: the
preconditioned matrix is the identity plus a perturbation of rank at most twice the number of
global constraints, so GMRES needs a handful of iterations at every n (10⁵ elastica edges:
2 s per Newton step on the CPU, where the Jacobi-preconditioned MINRES needs about n
iterations).

**Operators.**  For a problem declared local (`dg.local_sum`) the products use the assembled
sparse blocks of `K` (the same values as `method="sparse"`) and `M = |diag H|` (Jacobi);
otherwise `K v` is a forward-over-reverse product of the Lagrangian (`jax.linearize`) and
`M = I`.

**Multigrid.**  `Krylov(preconditioner="amg")`, for an unconstrained problem declared local
(a mesh): MINRES preconditioned by a smoothed-aggregation multigrid cycle of the Hessian
(`_amg.py`: the aggregates made once per pattern on the host with pyamg; the prolongators,
coarse operators and smoothers recomputed from the Hessian at every Newton step and the cycle
applied inside `jit`) in place of the Jacobi metric; its iteration count stays nearly constant as the mesh is refined, where the Jacobi
one grows with the condition number.

**Accuracy.**  Each solve runs to the relative tolerance `rtol` (1e-12) in the preconditioned
norm; near a solution Newton then converges as with a direct solve, to the same point.  The
Levenberg–Marquardt fallback of `_newton.py` solves `(K² + ν I) d = −K R` by CG.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.sparse.linalg import cg, gmres

from ddgjax._checks import is_concrete
from ddgjax.errors import InvalidInputError

from . import _amg as amg
from . import _banded as banded
from ._banded import Chain, chain_arrays, chain_structure
from ._cache import derived
from ._kkt import KKT
from ._linear import LinearSolver, regularisation
from ._sparse import PatternKey, SparsePattern, cached_pattern, index_arrays, kkt_values

RTOL = 1e-12
CHAIN_RESTART, CHAIN_CYCLES = 10, 2  # GMRES with the block-tridiagonal preconditioner (border rank ≤ 2·3 for a chord)
JACOBI_FLOOR = 1e-12  # |diag H| below this (relative to its largest entry) is raised to it
PRECONDITIONERS = ("jacobi", "amg")


def minres(A: Callable, b, precondition: Callable, *, rtol: float, maxiter: int, atol=0.0, lift: Callable | None = None):
    """Preconditioned MINRES (Paige & Saunders 1975) for `A x = b`, A symmetric, x₀ = 0.

    `precondition` applies a symmetric positive (semi)definite `P ≈ A⁻¹`; the iteration minimises
    the `P`-norm of the residual over the Krylov space of `P A` and stops when it is `rtol` times
    that of `b` (or `atol`).  Returns `(x, iterations, relative residual)`.  One `lax.while_loop`.

    `lift`, for a projection-type `P` with `P·lift·P = P` (`lift = M` for the constraint
    preconditioner), replaces each residual vector `r` by `lift(P r)`, which differs from it by
    an element of the kernel of P and so leaves the iteration unchanged in exact arithmetic,
    but keeps the residual vectors free of the large normal components that P would otherwise
    cancel in round-off (the "residual update" of Gould, Hribar & Nocedal 2001).
    """
    lift = (lambda y, r: r) if lift is None else (lambda y, r, f=lift: f(y))
    y = precondition(b)
    b = lift(y, b)
    beta1 = jnp.sqrt(jnp.maximum(jnp.dot(b, y), 0.0))
    zero = jnp.zeros_like(b)
    tiny = jnp.finfo(b.dtype).tiny
    # (x, r1, r2, y, w, w2, beta, oldb, dbar, epsln, phibar, cs, sn, it)
    start = (zero, b, b, y, zero, zero, beta1, jnp.zeros_like(beta1), jnp.zeros_like(beta1),
             jnp.zeros_like(beta1), beta1, -jnp.ones_like(beta1), jnp.zeros_like(beta1), 0)

    def cond(s):
        beta, phibar, it = s[6], s[10], s[13]
        return (it < maxiter) & (phibar > jnp.maximum(rtol * beta1, atol)) & (beta > tiny)

    def body(s):
        x, r1, r2, y, w, w2, beta, oldb, dbar, epsln, phibar, cs, sn, it = s
        v = y / beta  # the Lanczos vector
        y = A(v)
        y = jnp.where(it > 0, y - (beta / jnp.where(oldb > 0, oldb, 1.0)) * r1, y)
        alfa = jnp.dot(v, y)
        y = y - (alfa / beta) * r2
        r1, r2 = r2, y
        y = precondition(r2)
        r2 = lift(y, r2)
        oldb, beta = beta, jnp.sqrt(jnp.maximum(jnp.dot(r2, y), 0.0))
        # the previous plane rotation applied to the new column of the tridiagonal matrix
        oldeps = epsln
        delta = cs * dbar + sn * alfa
        gbar = sn * dbar - cs * alfa
        epsln = sn * beta
        dbar = -cs * beta
        # the next rotation
        gamma = jnp.maximum(jnp.hypot(gbar, beta), tiny)
        cs, sn = gbar / gamma, beta / gamma
        phi = cs * phibar
        phibar = sn * phibar
        w1, w2 = w2, w
        w = (v - oldeps * w1 - delta * w2) / gamma
        return (x + phi * w, r1, r2, y, w, w2, beta, oldb, dbar, epsln, phibar, cs, sn, it + 1)

    out = jax.lax.while_loop(cond, body, start)
    return out[0], out[13], out[10] / jnp.maximum(beta1, tiny)


@dataclass(frozen=True)
class Linearisation:
    """The KKT matrix at `w` as products: `hvp = H·`, `jvp = J·`, `vjp = Jᵀ·`, `kvp = K·`,
    with `diag_h` (the diagonal of H, or None) and `jacobi_s(minv)` (the diagonal of
    `J diag(minv) Jᵀ`, or None) for the preconditioners, and `scale` (largest entry of K)."""

    n: int
    m: int
    hvp: Callable
    jvp: Callable
    vjp: Callable
    kvp: Callable
    diag_h: object
    jacobi_s: Callable | None
    scale: object
    values: object = None  # the coalesced sparse values of K (local problems)


@dataclass(frozen=True)
class Factored:
    """A `Linearisation` with the regularisation μ and the Jacobi preconditioner `M⁻¹`."""

    K: Linearisation
    mu: object
    minv: object
    sinv: object  # the Jacobi preconditioner of S, or None
    chain: object = None  # the block-tridiagonal factors (`_banded.factor`), or None
    amg: object = None  # the multigrid levels at this step (`_amg.setup`), or None


def _sparse_linearisation(pattern: SparsePattern, index: dict, kkt: KKT, w, identity_hessian: bool) -> Linearisation:
    n, m = pattern.n, pattern.m
    values = kkt_values(pattern, index, kkt, w, identity_hessian)
    h_at, j_at, diag_at = index["h_at"], index["j_at"], index["diagonal"][:n]
    rows, cols = index["rows"], index["cols"]
    h_vals, j_vals = values[h_at], values[j_at]  # K's entries in H, and in its −J block
    h_rows, h_cols = rows[h_at], cols[h_at]
    j_rows, j_cols = rows[j_at] - n, cols[j_at]

    def hvp(v):
        return jax.ops.segment_sum(h_vals * v[h_cols], h_rows, num_segments=n)

    def jvp(v):
        return -jax.ops.segment_sum(j_vals * v[j_cols], j_rows, num_segments=m)

    def vjp(y):
        return -jax.ops.segment_sum(j_vals * y[j_rows], j_cols, num_segments=n)

    def kvp(z):
        return jnp.concatenate([hvp(z[:n]) + vjp(-z[n:]), -jvp(z[:n])])

    def jacobi_s(minv):
        return jax.ops.segment_sum(j_vals**2 * minv[j_cols], j_rows, num_segments=m)

    return Linearisation(n, m, hvp, jvp, vjp, kvp, values[diag_at], jacobi_s, jnp.max(jnp.abs(values)), values)


def _autodiff_linearisation(kkt: KKT, w, identity_hessian: bool) -> Linearisation:
    n, m = kkt.spec.n, kkt.spec.m
    u, _ = kkt.split(w)
    g_u, jvp = jax.linearize(kkt.g, u)
    transpose = jax.linear_transpose(jvp, u)

    def vjp(y):
        return transpose(y)[0]

    if identity_hessian:
        def hvp(v):
            return v
    else:
        _, full = jax.linearize(kkt.residual, w)

        def hvp(v):
            return full(jnp.concatenate([v, jnp.zeros((m,), v.dtype)]))[:n]

    def kvp(z):
        return jnp.concatenate([hvp(z[:n]) - vjp(z[n:]), -jvp(z[:n])])

    return Linearisation(n, m, hvp, jvp, vjp, kvp, None, None, jnp.asarray(1.0, w.dtype))


@jax.tree_util.register_pytree_node_class
class Krylov(LinearSolver):
    """Matrix-free KKT solves (module docstring): GMRES with the block-tridiagonal preconditioner
    on chains, MINRES on the constraints' tangent space otherwise, each to the relative
    tolerance `rtol` in at most `maxiter` iterations (default 2N + 50).  `preconditioner="amg"`
    replaces the Jacobi metric by a multigrid cycle (module docstring; unconstrained problems
    declared local).  A pytree: the pattern's index arrays (if the problem is local) are its
    leaves, and the multigrid hierarchy's."""

    def __init__(self, pattern: SparsePattern | None = None, rtol: float = RTOL, maxiter: int | None = None,
                 index: dict | None = None, chain: Chain | None = None, preconditioner: str = "jacobi",
                 hierarchy: amg.Hierarchy | None = None):
        if preconditioner not in PRECONDITIONERS:
            raise InvalidInputError(f"preconditioner must be one of {PRECONDITIONERS}, got {preconditioner!r}")
        self.pattern = pattern
        self.rtol = float(rtol)
        self.maxiter = maxiter
        self.chain = chain
        self.preconditioner = preconditioner
        self.hierarchy = hierarchy
        if index is None and pattern is not None:
            index = dict(index_arrays(pattern), **({} if chain is None else chain_arrays(chain)),
                         **({} if hierarchy is None else amg.device_arrays(hierarchy)))
        self.index = index

    def bind(self, problem, spec) -> Krylov:
        """Assembled products for a problem declared local, with the block-tridiagonal
        preconditioner if it is a chain (or the multigrid one if asked); autodiff products
        otherwise; itself if already bound to the problem's pattern (its index arrays may then
        be arguments of a traced function: `solve_batch` passes them so)."""
        if spec.is_local and self.pattern is not None and self.pattern is cached_pattern(spec, problem.x0, problem.params):
            return self
        if self.preconditioner == "amg":
            return self._bind_amg(problem, spec)
        if not spec.is_local:
            return type(self)(None, self.rtol, self.maxiter)
        pattern = cached_pattern(spec, problem.x0, problem.params)
        shape = spec.layout.shapes[0]
        width = shape[1] if len(shape) == 2 else 1
        # made once per pattern: jit's cache compares it by identity
        chain = derived(pattern, "chain", lambda: chain_structure(pattern, spec.layout.free, width))
        return type(self)(pattern, self.rtol, self.maxiter, chain=chain)

    def _bind_amg(self, problem, spec) -> Krylov:
        """The multigrid hierarchy of the Hessian's pattern, made once per pattern (with the
        rotations of x0's rows in its near-null space when x0 is concrete)."""
        if not spec.is_local:
            raise InvalidInputError(
                "Krylov(preconditioner='amg') assembles the Hessian: it needs an energy declared with "
                "dg.local_sum over a single array of unknowns"
            )
        if spec.m:
            raise InvalidInputError(
                f"Krylov(preconditioner='amg') solves unconstrained problems; this one has {spec.m} constraints "
                "(use Krylov() for the tangent-space MINRES with the Jacobi metric)"
            )
        pattern = cached_pattern(spec, problem.x0, problem.params)
        hierarchy = derived(pattern, "amg", lambda: _hierarchy(pattern, spec, problem))
        return type(self)(pattern, self.rtol, self.maxiter, preconditioner="amg", hierarchy=hierarchy)

    def __repr__(self):
        extra = "" if self.preconditioner == "jacobi" else f", preconditioner={self.preconditioner!r}"
        return f"Krylov(rtol={self.rtol:g}, maxiter={self.maxiter}{extra})"

    def tree_flatten(self):
        names = () if self.index is None else tuple(sorted(self.index))
        key = None if self.pattern is None else PatternKey(self.pattern)
        # the chain and the hierarchy are found on the pattern (`of`), so that the static part
        # compares by the pattern's structure only and problems declared alike share one
        # compiled solver
        aux = (key, self.rtol, self.maxiter, names, self.chain is not None, self.preconditioner)
        return tuple(self.index[k] for k in names), aux

    @classmethod
    def tree_unflatten(cls, aux, children):
        key, rtol, maxiter, names, has_chain, preconditioner = aux
        if key is None:
            return cls(None, rtol, maxiter, preconditioner=preconditioner)
        chain = derived(key.pattern, "chain") if has_chain else None
        hierarchy = derived(key.pattern, "amg") if preconditioner == "amg" else None
        return cls(key.pattern, rtol, maxiter, dict(zip(names, children)), chain, preconditioner, hierarchy)

    def matrix(self, kkt: KKT, w, identity_hessian=False) -> Linearisation:
        if self.pattern is not None:
            return _sparse_linearisation(self.pattern, self.index, kkt, w, identity_hessian)
        return _autodiff_linearisation(kkt, w, identity_hessian)

    def factor_matrix(self, kkt: KKT, K: Linearisation, mu_rel) -> Factored:
        mu = mu_rel * jnp.maximum(K.scale, 1.0)
        if self.chain is not None:  # the block-tridiagonal preconditioner replaces the Jacobi one
            return Factored(K, mu, None, None, banded.factor(self.chain, self.index, K.values, mu))
        if K.diag_h is None:
            minv = jnp.ones((K.n,), dtype=K.scale.dtype)
        else:
            d = jnp.abs(K.diag_h + mu)
            minv = 1.0 / jnp.maximum(d, JACOBI_FLOOR * jnp.maximum(jnp.max(d), 1.0))
        sinv = None
        if K.m and K.jacobi_s is not None:
            s = K.jacobi_s(minv)
            sinv = 1.0 / jnp.where(s > 0, s, 1.0)
        levels = None
        if self.hierarchy is not None:
            levels = amg.setup(self.hierarchy, self.index, K.values[self.index["h_at"]], mu)
        return Factored(K, mu, minv, sinv, amg=levels)

    def _schur_solve(self, fac: Factored, r):
        """`S⁻¹ r`, `S = J M⁻¹ Jᵀ`, by Jacobi-preconditioned CG."""
        K, minv = fac.K, fac.minv

        def S(y):
            return K.jvp(minv * K.vjp(y))

        precondition = None if fac.sinv is None else (lambda y: fac.sinv * y)
        y, _ = cg(S, r, tol=self.rtol * 1e-2, atol=0.0, maxiter=K.m + 20, M=precondition)
        return y

    def _project(self, fac: Factored, r):
        """`P r = M⁻¹ (r − Jᵀ S⁻¹ J M⁻¹ r)`: the constraint preconditioner, range `ker J`."""
        K, minv = fac.K, fac.minv
        if not K.m:
            return minv * r
        return minv * (r - K.vjp(self._schur_solve(fac, K.jvp(minv * r))))

    def apply(self, fac: Factored, b):
        return self.apply_counted(fac, b)[0]

    def apply_counted(self, fac: Factored, b):
        """`(d, iterations)`: the solve of `apply` and its number of MINRES iterations (−1 for
        the chain's GMRES)."""
        if fac.chain is not None:
            return self._apply_chain(fac, b), -1
        K, minv = fac.K, fac.minv
        n, m = K.n, K.m
        b1, b2 = b[:n], b[n:]
        maxiter = self.maxiter if self.maxiter is not None else 2 * n + 50

        def H(v):
            return K.hvp(v) + fac.mu * v

        d_n = -minv * K.vjp(self._schur_solve(fac, b2)) if m else jnp.zeros_like(b1)
        rhs = b1 - H(d_n)
        scale = jnp.sqrt(jnp.dot(rhs, minv * rhs))
        # the right-hand side less its part in range Jᵀ (which only changes d₂): MINRES's residual
        # vectors then carry no large normal component that P would have to cancel in round-off
        if m:
            rhs = rhs - K.vjp(self._schur_solve(fac, K.jvp(minv * rhs)))  # = M P rhs
        if fac.amg is not None:  # m = 0; the tolerance is relative to the cycle's norm of rhs
            precondition, atol = (lambda r: amg.precondition(self.hierarchy, self.index, fac.amg, r)), 0.0
        else:
            precondition, atol = (lambda r: self._project(fac, r)), self.rtol * scale
        d_t, iterations, _ = minres(
            H, rhs, precondition, rtol=self.rtol, atol=atol, maxiter=maxiter,
            lift=(lambda y: y / minv) if m else None,
        )
        d1 = d_n + d_t
        if not m:
            return d1, iterations
        d2 = self._schur_solve(fac, K.jvp(minv * (H(d1) - b1)))
        return jnp.concatenate([d1, d2]), iterations

    def _apply_chain(self, fac: Factored, b):
        """GMRES on `(K + μS) d = b` preconditioned by the block-tridiagonal solve (`_banded`)."""
        K = fac.K
        shift = regularisation(K.n, K.m, fac.mu)  # μS, as the direct back ends add it

        def A(v):
            return K.kvp(v) + shift * v

        def precondition(r):
            return banded.solve(self.chain, self.index, fac.chain, r)

        restart = min(CHAIN_RESTART, b.shape[0])
        d, _ = gmres(A, b, M=precondition, tol=self.rtol, atol=0.0, restart=restart, maxiter=CHAIN_CYCLES)
        return d

    def matvec(self, K: Linearisation, v):
        return K.kvp(v)

    def lm_solve_matrix(self, K: Linearisation, nu, R):
        """`−(K² + ν I)⁻¹ K R` by CG (K is symmetric)."""
        size = R.shape[0]

        def normal(v):
            return K.kvp(K.kvp(v)) + nu * v

        d, _ = cg(normal, -K.kvp(R), tol=self.rtol, atol=0.0, maxiter=2 * size + 50)
        return d


def _hierarchy(pattern: SparsePattern, spec, problem) -> amg.Hierarchy:
    """`_amg.build_hierarchy` for the Hessian block of the pattern, with the rows of x at x0 for
    the rotations when they are concrete."""
    h_at, _ = pattern.blocks()
    shape = spec.layout.shapes[0]
    width = shape[1] if len(shape) == 2 else 1
    coords = np.asarray(spec.layout.ravel(problem.x0)).reshape(-1, width) if is_concrete(problem.x0) else None
    return amg.build_hierarchy(np.asarray(spec.layout.free, np.int64), width, pattern.rows[h_at].astype(np.int64),
                               pattern.cols[h_at].astype(np.int64), coords)


__all__ = ["Krylov", "minres"]
