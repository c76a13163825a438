"""`stability`: the second-order test at a constrained critical point, and its Morse index.

At a solution `(x, λ)` of `∇E − Jᵀλ = 0, g = 0` (the Lagrange multipliers of Sec 3.1, "Basic fact
from the calculus of variations"; our λ is minus the reference's, `ddgjax.problem`) the quadratic
form that decides stability is the Hessian of the Lagrangian `L(x, λ) = E(x) − λ·g(x)` restricted
to the free entries and to the tangent space of the constraint set,

    H_red = Zᵀ ∇²_u L(u, λ) Z,    the columns of Z an orthonormal basis of {δu : J δu = 0},

with `u` the free entries of x and `J = Dg(x)` on them.  The second-order conditions (e.g.
Nocedal–Wright, Thm 12.5 and 12.6): a critical point with `H_red` positive definite is a strict
local minimum of E on {g = 0}; one with a negative eigenvalue is not a local minimum.  The number
of negative eigenvalues is the *Morse index* (the minimum has index 0; Euler's figure-eight, a
saddle, index ≥ 1).

**Symmetries.**  A Euclidean motion that maps the constraint set to itself and fixes the fixed
entries leaves E constant along its orbit, so its generator is a null vector of `H_red`
(exactly at an exact critical point).  Those directions are neither stable nor unstable; they are
removed.  For every leaf of x whose last axis has size 3 (2) the candidates are the infinitesimal
rotations `δX = ω × X` (the planar rotation) and translations `δX = e_a`; they are restricted to
the free entries, projected to the tangent space, and the subspace of their combinations `v` with

    |P ∇²L v| ≤ zero_tol · scale · |v|      (P the orthogonal projector onto ker J)

is the symmetry null space S, of dimension `zero_modes`.  A candidate that is no symmetry (a
translation of unit tangents, a rotation of a mesh with a fixed boundary) fails the test and is
dropped, so "translations only where they make sense" needs no flag.  Not every null direction
is a symmetry: the discrete figure-eight elastica lies in a one-parameter family of critical
points of equal energy (the phase of the sampling along the curve), whose tangent is a null
eigenvector that no Euclidean motion generates; it stays in the spectrum (eigenvalue ≈ 0, not
counted in the index).

The spectrum reported is that of `H_red` on `ker J ∩ S^⊥` (S is invariant under `H_red`, so
these are the remaining eigenvalues exactly), and

    index = #{eigenvalues < −tol · scale},   scale = ‖∇²_u L‖_∞ (the largest absolute row sum,
                                               a bound of every eigenvalue of H_red).

`tol = 1e-8` by default: far above the round-off of the Hessian (~1e-16 scale) and the effect
of a KKT residual ~1e-10, far below the negative eigenvalues of the examples (≳ 1e-4 scale).

**Paths.**  `method="dense"`: the Hessian and J by autodiff as dense matrices, Z by an SVD of
[J; Sᵀ], all eigenvalues by `eigh` (n ≲ 2,000 free unknowns).  `method="sparse"` (problems
declared local, `dg.local_sum`): the KKT matrix assembled from its cells as a scipy sparse
matrix; P applied by a sparse LU of `[[I, Jᵀ], [J, 0]]`; the k lowest eigenvalues by ARPACK
(`eigsh`) in shift-invert mode on the bordered system

    T b = [I 0] [[∇²L − σI, Cᵀ], [C, 0]]⁻¹ [b; 0],   C = [J; Sᵀ],

whose eigenvalues on `ker C` are `1/(μ − σ)` (0 on the normal space), with σ below the lowest
eigenvalue μ₁.  σ and the index come from the inertia of the bordered matrix (Sylvester; Gould
1985: its negative eigenvalues are #{μ < σ} + rank C) by Pardiso's `LDLᵀ` where MKL is
installed.  Sylvester's count also catches copies of a multiple eigenvalue that ARPACK (one
start vector) missed: they are then found with the found vectors deflated.  Without MKL the k + 4
eigenvalues nearest −tol·scale are computed (shift-invert there, `which="LM"`) and the index is
counted among them: exact unless a negative eigenvalue lies farther from 0 than k + 4 others
(then a lower bound).
"""

from __future__ import annotations

import functools

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg

from ddgjax._checks import check_finite, check_same_structure, is_concrete
from ddgjax.errors import InvalidInputError, ShapeError
from ddgjax.problem import Problem, flatten_multipliers

from ._dense import DenseLU
from ._exported import programs
from ._kkt import KKT, residual_weights, scaled_residual, spec_of
from ._solve import DENSE_MAX, Solution, linear_solver_of

__all__ = ["Stability", "stability"]

METHODS = ("auto", "dense", "sparse")
TOL = 1e-8  # eigenvalues below −TOL·scale count as negative
ZERO_TOL = 1e-8  # symmetry generators v with |P H v| ≤ ZERO_TOL·scale·|v| are zero modes
CRITICAL_TOL = 1e-6  # the scaled KKT residual at the solution must be below this
INDEPENDENT = 1e-8  # candidate generators with singular values below this (relative) are dependent


class Stability(NamedTuple):
    """The result of `stability`.

    - `index`: the Morse index, the number of eigenvalues of the reduced Hessian below
      `−tol·scale` with the symmetry zero modes excluded (0 at a strict local minimum).
    - `eigenvalues`: (k,) the lowest k eigenvalues of the reduced Hessian on the complement of the
      zero modes, ascending.
    - `vectors`: (n_free, k) their orthonormal eigenvectors as columns (`vectors[:, i]`), in the
      flat coordinates of the free entries (`spec.layout.free` order; `mode(i)` gives a pytree).
    - `zero_modes`: the dimension of the symmetry null space excluded.
    - `scale`: ‖∇²_u L‖_∞, the unit of `tol`.
    - `modes`: the k eigenvectors as pytrees like x (zero on fixed entries).
    """

    index: int
    eigenvalues: np.ndarray
    vectors: np.ndarray
    zero_modes: int
    scale: float
    modes: tuple

    def mode(self, i: int):
        """The i-th eigenvector as a pytree like x (zero on the fixed entries)."""
        return self.modes[i]


def stability(problem: Problem, solution: Solution, k: int = 6, *, method: str = "auto", tol: float = TOL,
              zero_tol: float = ZERO_TOL) -> Stability:
    """The lowest k eigenvalues and the Morse index of the Hessian of the Lagrangian
    `L = E − λ·g` at a critical point, on the free entries and the constraints' tangent space,
    with the zero modes of Euclidean symmetries excluded (module docstring).

    Second-order condition (Lagrange multipliers, Sec 3.1): a constrained critical point is a
    strict local minimum iff the reduced Hessian `Zᵀ ∇²L Z` (J Z = 0) is positive definite up to
    the symmetry directions; `index` = #{eigenvalues < −tol·scale} is its Morse index.

    **Arguments:** `problem`; `solution` its `Solution` (from `solve` or `minimize`); `k` how
    many of the lowest eigenvalues to return (capped at the dimension of the reduced space);
    `method` `"dense"`, `"sparse"` (problems declared local) or `"auto"` (dense up to 2,000 free
    unknowns and multipliers); `tol` and `zero_tol` relative to `scale` (module docstring).

    **Returns:** a `Stability`.

    **Raises:** `InvalidInputError` (k ≤ 0, unknown method, a solution whose shapes, fixed entries
    or multipliers are not this problem's, or which is not a critical point of it: scaled KKT
    residual above 1e-6), `NonFiniteError` / `ShapeError` (subclasses) for NaN or misshapen input.
    """
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k <= 0:
        raise InvalidInputError(f"k must be a positive integer (how many eigenvalues), got {k!r}")
    if method not in METHODS:
        raise InvalidInputError(f"method must be one of {METHODS}, got {method!r}")
    for value, name in ((tol, "tol"), (zero_tol, "zero_tol")):
        if not (np.isfinite(value) and value > 0):
            raise InvalidInputError(f"{name} must be finite and positive, got {value!r}")
    spec = spec_of(problem)
    if spec.n == 0:
        raise InvalidInputError("every entry of x is fixed: the reduced Hessian is empty")
    z, lam = _checked_point(problem, spec, solution)
    if method == "auto":
        method = "dense" if spec.n + spec.m <= DENSE_MAX or not spec.is_local else "sparse"
    if method == "sparse" and not spec.is_local:
        raise InvalidInputError("method='sparse' needs a problem declared local (dg.local_sum, dg.local_map)")
    u = z[spec.layout.free]
    H, J = _hessian_and_jacobian(problem, spec, z, np.concatenate([u, lam]), method)
    scale = max(float(abs(H).sum(axis=1).max()), np.finfo(float).tiny)
    generators = _symmetry_generators(spec.layout, z)[spec.layout.free]
    eig, vec, index, zero_modes = (_dense if method == "dense" else _sparse)(H, J, generators, k, scale, tol, zero_tol)
    modes = tuple(spec.layout.x_of(np.zeros(spec.layout.n_total), v) for v in np.asarray(vec).T)
    return Stability(int(index), eig, vec, int(zero_modes), scale, modes)


# --- input ------------------------------------------------------------------------------------


def _checked_point(problem: Problem, spec, solution) -> tuple[jax.Array, jax.Array]:
    """`(z, λ)`: the flattened solution and its flat multipliers, after checking that they are
    concrete, finite, shaped like this problem's, equal to x0 on the fixed entries and critical."""
    if not hasattr(solution, "x") or not hasattr(solution, "multipliers"):
        raise InvalidInputError(f"solution must be a Solution (with .x and .multipliers), got {type(solution).__name__}")
    if not is_concrete((solution.x, solution.multipliers)):
        raise InvalidInputError("stability needs concrete values: call it outside jit/vmap/grad")
    check_same_structure(problem.x0, solution.x, "solution.x", "problem.x0")
    check_finite(solution.x, "solution.x")
    try:
        lam = flatten_multipliers(problem, solution.multipliers)
    except ShapeError as error:
        raise ShapeError(f"solution.multipliers do not fit this problem's constraints: {error}") from None
    z = np.asarray(spec.layout.ravel(solution.x), dtype=float)
    z0 = np.asarray(spec.layout.ravel(problem.x0))
    fixed = np.setdiff1d(np.arange(spec.layout.n_total), spec.layout.free)
    moved = fixed[np.asarray(z[fixed] != z0[fixed])]
    if moved.size:
        raise InvalidInputError(
            f"solution.x differs from problem.x0 at fixed entry {int(moved[0])} (flat index): a solution of another problem?")
    R = _residual(spec, z, problem.params, np.concatenate([z[spec.layout.free], np.asarray(lam)]))
    residual = float(scaled_residual(R, residual_weights(problem, spec), spec.n))
    if not residual <= CRITICAL_TOL:
        raise InvalidInputError(
            f"solution is not a critical point of {problem.name or 'this problem'}: scaled KKT residual {residual:.3e} > "
            f"{CRITICAL_TOL:.0e} (a solution of another problem, or one that did not converge?)")
    return z, lam


@programs
def _residual(kkt_spec, z, params, w):
    return KKT(kkt_spec, z, params).residual(w)


@programs
def _kkt_matrix(kkt_spec, linear, z, params, w):
    return linear.matrix(KKT(kkt_spec, z, params), w)


def _hessian_and_jacobian(problem, spec, z, w, method: str):
    """`(H, J)`: ∇²_u L (n, n) and Dg (m, n) on the free entries, dense arrays or scipy CSR
    matrices, from the KKT matrix `[[∇²L, −Jᵀ], [−J, 0]]` the solver assembles."""
    import scipy.sparse as sp

    n = spec.n
    if method == "dense":
        K = np.asarray(_kkt_matrix(spec, DenseLU(), z, problem.params, w))
        H = 0.5 * (K[:n, :n] + K[:n, :n].T)
        return H, -K[n:, :n]
    linear = linear_solver_of(problem.with_x0(spec.layout.unravel(z)), spec, "sparse", None)
    values = np.asarray(_kkt_matrix(spec, linear, z, problem.params, w))
    pattern = linear.pattern
    K = sp.csr_matrix((values, (pattern.rows, pattern.cols)), shape=(n + spec.m, n + spec.m))
    H = K[:n, :n]
    return (0.5 * (H + H.T)).tocsr(), -K[n:, :n].tocsr()


# --- symmetries -------------------------------------------------------------------------------


def _symmetry_generators(layout, z) -> np.ndarray:
    """(n_total, c): the infinitesimal rotations and translations of every leaf of x whose last
    axis has size 2 or 3, each acting on that leaf alone (joint motions are their sums)."""
    z = np.asarray(z)
    columns, start = [], 0
    for shape in layout.shapes:
        size = int(np.prod(shape, dtype=int))
        if len(shape) >= 1 and shape[-1] in (2, 3) and size:
            X = z[start:start + size].reshape(-1, shape[-1])
            for motion in _motions(X):
                column = np.zeros(layout.n_total)
                column[start:start + size] = motion.ravel()
                columns.append(column)
        start += size
    return np.stack(columns, axis=1) if columns else np.zeros((layout.n_total, 0))


def _motions(X: np.ndarray) -> list[np.ndarray]:
    """Rotations ω × X (in the plane: (−y, x)) and translations e_a of the rows of X."""
    d = X.shape[1]
    translations = [np.broadcast_to(np.eye(d)[a], X.shape) for a in range(d)]
    if d == 2:
        return [np.stack([-X[:, 1], X[:, 0]], axis=1)] + translations
    return [np.cross(np.eye(3)[a], X) for a in range(3)] + translations


def _zero_modes(project, HP, G: np.ndarray, scale: float, zero_tol: float) -> np.ndarray:
    """(n, z) orthonormal: the combinations v of the projected generators with |P H v| ≤ zero_tol·scale·|v|.

    `project(V)` applies P to the columns of V, `HP(V)` applies P H."""
    if G.shape[1] == 0:
        return G
    W = project(G)
    U, s, _ = np.linalg.svd(W, full_matrices=False)
    if not s.size or s[0] == 0.0:
        return np.zeros((G.shape[0], 0))
    Q = U[:, s > INDEPENDENT * s[0]]
    Q = project(Q)  # back into ker J to round-off
    Q, _ = np.linalg.qr(Q)
    _, sigma, Vt = np.linalg.svd(HP(Q), full_matrices=False)
    sigma = np.concatenate([sigma, np.zeros(Q.shape[1] - sigma.size)])
    null = Vt[sigma <= zero_tol * scale].T
    return Q @ null


# --- dense path -------------------------------------------------------------------------------


def _null_basis(C: np.ndarray, n: int) -> np.ndarray:
    """(n, n − rank C) orthonormal basis of ker C by the SVD."""
    if C.shape[0] == 0:
        return np.eye(n)
    _, s, Vt = np.linalg.svd(C, full_matrices=True)
    rank = int(np.sum(s > max(C.shape) * np.finfo(float).eps * (s[0] if s.size else 0.0)))
    return Vt[rank:].T


def _dense(H, J, G, k, scale, tol, zero_tol):
    n = H.shape[0]
    Z = _null_basis(J, n)
    project = lambda V: Z @ (Z.T @ V)
    S = _zero_modes(project, lambda V: project(H @ V), G, scale, zero_tol)
    Zc = _null_basis(np.vstack([J, S.T]), n) if S.shape[1] else Z
    eig, y = scipy.linalg.eigh(Zc.T @ H @ Zc)
    index = int(np.sum(eig < -tol * scale))
    k = min(k, eig.size)
    return eig[:k], Zc @ y[:, :k], index, S.shape[1]


# --- sparse path ------------------------------------------------------------------------------


def _bordered(A, C, shift: float = 0.0):
    """`[[A − shift·I, Cᵀ], [C, 0]]` as CSC."""
    import scipy.sparse as sp

    m, n = C.shape
    top = A - shift * sp.identity(n) if shift else A
    return sp.bmat([[top, C.T], [C, sp.csr_matrix((m, m))]], format="csc") if m else sp.csc_matrix(top)


def _projector(J):
    """`project(V)`: the orthogonal projection of the columns of V onto ker J (a sparse LU of
    [[I, Jᵀ], [J, 0]])."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    m, n = J.shape
    if m == 0:
        return lambda V: np.asarray(V).reshape(n, -1)
    lu = spla.splu(_bordered(sp.identity(n, format="csr"), J))

    def project(V):
        V = np.asarray(V).reshape(n, -1)
        return lu.solve(np.vstack([V, np.zeros((m, V.shape[1]))]))[:n]

    return project


@functools.cache
def _pardiso_handle():
    """One symmetric-indefinite Pardiso handle per process, reused (freed by `_Inertia.close`)."""
    from ._direct import pardiso_solver

    return pardiso_solver(-2)


class _Inertia:
    """`count(σ)`: #{eigenvalues of A on ker C below σ}, by the inertia of the bordered matrix
    `[[A − σI, Cᵀ], [C, 0]]` (its negative eigenvalues are that count + rank C) from Pardiso's
    `LDLᵀ`, one handle for all shifts.  `available` is False without MKL."""

    def __init__(self, A, C):
        from ._direct import PARDISO_THREADS, pardiso_available

        self.A, self.C = A, C
        self.available = pardiso_available()
        if self.available:
            self.solver = _pardiso_handle()
            self.solver.libmkl.MKL_Set_Num_Threads(PARDISO_THREADS)

    def count(self, shift: float) -> int:
        import scipy.sparse as sp

        K = _bordered(self.A, self.C, shift).tocoo()
        keep = K.row <= K.col
        size = K.shape[0]
        diagonal = np.arange(size)  # a stored (possibly zero) diagonal entry in every row, as Pardiso wants
        upper = sp.csr_matrix((np.concatenate([K.data[keep], np.zeros(size)]),
                               (np.concatenate([K.row[keep], diagonal]), np.concatenate([K.col[keep], diagonal]))),
                              shape=K.shape)
        upper.sort_indices()
        self.solver.factorize(upper)
        return int(self.solver.iparm[22]) - self.C.shape[0]

    def close(self):
        if self.available:
            self.solver.free_memory(everything=True)


class _Spectrum:
    """Eigenpairs of H on ker C by shift-invert Lanczos (ARPACK), σ by σ, each found pair deflated
    from the later searches."""

    def __init__(self, H, C, project):
        self.H, self.C, self.project = H, C, project
        self.n = H.shape[0]
        self.eig, self.vec = np.zeros(0), np.zeros((self.n, 0))

    @property
    def room(self) -> int:
        """How many more eigenpairs ARPACK may look for (it needs k < dimension)."""
        return self.n - self.C.shape[0] - self.eig.size - 1

    def search(self, sigma: float, k: int, which: str = "LA") -> None:
        """Add k eigenpairs: those just above σ ("LA") or nearest σ ("LM"), from
        `T b = [I 0] [[H − σI, Cᵀ], [C, 0]]⁻¹ [b; 0]` (eigenvalues 1/(μ − σ) on ker C, 0 on the
        normal space) less Σ θ_i v_i v_iᵀ over the pairs found (Wielandt: they move to 0)."""
        import scipy.sparse.linalg as spla

        k = min(k, self.room)
        if k <= 0:
            return
        m = self.C.shape[0]
        lu = spla.splu(_bordered(self.H, self.C, sigma))
        V, theta_known = self.vec, 1.0 / (self.eig - sigma)

        def apply(b):
            b = np.ravel(b)
            return lu.solve(np.concatenate([b, np.zeros(m)]))[: self.n] - V @ (theta_known * (V.T @ b))

        operator = spla.LinearOperator((self.n, self.n), matvec=apply, dtype=float)
        v0 = self.project(np.random.default_rng(self.eig.size).standard_normal(self.n))[:, 0]
        theta, vec = spla.eigsh(operator, k=k, which=which, v0=v0, tol=1e-10)
        real = np.abs(theta) > 1e-12 * np.max(np.abs(theta))  # not the normal space, not a deflated pair
        vec = self.project(vec[:, real])  # exactly in ker J (ARPACK's vectors are, to its tolerance)
        self.eig = np.concatenate([self.eig, sigma + 1.0 / theta[real]])
        self.vec = np.concatenate([self.vec, vec / np.linalg.norm(vec, axis=0)], axis=1)
        order = np.argsort(self.eig)
        self.eig, self.vec = self.eig[order], self.vec[:, order]

    def lowest(self, inertia: _Inertia, sigma: float, want: int, scale: float, below: tuple | None = None) -> None:
        """Search from σ until the pairs found hold the `want` lowest eigenvalues (all those below
        σ found already);
        `below = (bound, count)`: there are exactly `count` eigenvalues in [σ, bound) (never ask
        for more: beyond them the spectrum is clustered as seen from σ, and ARPACK slow).

        ARPACK (one start vector) can miss copies of a multiple eigenvalue.  Sylvester's count
        below a cut in the first gap after the want-th eigenvalue found says whether it did; the
        missing ones are then sought again with the found ones deflated."""
        want -= int(np.sum(self.eig < sigma))  # those below σ are found already (a previous search)
        for _ in range(DEFLATIONS):
            have = int(np.sum(self.eig >= sigma))
            ask = max(want - have, 0) + EXTRA
            if below is not None:
                ask = min(ask, below[1] - int(np.sum((self.eig >= sigma) & (self.eig < below[0]))))
            self.search(sigma, ask)
            above = self.eig[self.eig >= sigma]
            if below is not None and int(np.sum(above < below[0])) >= min(below[1], want + EXTRA):
                if below[1] <= want + EXTRA or self._complete(inertia, above, want, sigma, scale):
                    return
                continue
            if self._complete(inertia, above, want, sigma, scale):
                return

    def _complete(self, inertia: _Inertia, above, want: int, sigma: float, scale: float) -> bool:
        """Whether no eigenvalue is missing below a cut in the first gap after the want-th found."""
        gap = np.flatnonzero(np.diff(above[want - 1:]) > CLUSTER * scale) if above.size > want else []
        if not len(gap) or self.room <= 0:
            return True
        cut_at = want + int(gap[0])  # above[:cut_at] lie below the cut
        return inertia.count(0.5 * (above[cut_at - 1] + above[cut_at])) == cut_at + int(np.sum(self.eig < sigma))


EXTRA = 4  # eigenpairs computed beyond those asked for: ARPACK may miss a copy of a multiple one
DEFLATIONS = 5
CLUSTER = 1e-9  # eigenvalues closer than this (× scale) count as copies of one (no cut between them)
PROBE_STEPS = 300  # Lanczos steps looking for a negative eigenvalue far from 0 (no inertia available)


def _sparse(H, J, G, k, scale, tol, zero_tol):
    import scipy.sparse as sp

    n = H.shape[0]
    project = _projector(J)
    S = _zero_modes(project, lambda V: project(H @ V), G, scale, zero_tol)
    C = sp.vstack([J, sp.csr_matrix(S.T)]).tocsr() if S.shape[1] else J
    k = min(k, n - C.shape[0] - 1)
    if k <= 0:
        raise InvalidInputError(f"the reduced space has dimension {n - C.shape[0]}: use method='dense'")
    threshold = -tol * scale
    spectrum = _Spectrum(H, C, lambda V: _deflated(project(V), S))
    inertia = _Inertia(H, C)
    try:
        if inertia.available:
            index = inertia.count(threshold)
            if index:  # the negative eigenvalues, from a shift just below the lowest
                spectrum.lowest(inertia, _below_lowest(inertia, scale, threshold), min(k, index), scale,
                                below=(threshold, index))
            if k > index:  # the rest, from a shift just below zero
                spectrum.lowest(inertia, threshold, k, scale)
        else:
            index = _without_inertia(spectrum, H, S, project, k, scale, threshold)
    finally:
        inertia.close()
    return spectrum.eig[:k], spectrum.vec[:, :k], index, S.shape[1]


def _deflated(V, S):
    """V projected further onto S^⊥ (S orthonormal columns in ker J)."""
    return V - S @ (S.T @ V) if S.shape[1] else V


def _below_lowest(inertia: _Inertia, scale: float, high: float) -> float:
    """A shift σ with count(σ) = 0 (below every eigenvalue) within ~10 % of the lowest one, by
    bisection from Gershgorin's bound −1.01·scale (nothing below it) and `high` (count > 0)."""
    low = -1.01 * scale
    for _ in range(60):
        if high - low < 0.1 * abs(low):
            break
        middle = 0.5 * (low + high)
        if inertia.count(middle) == 0:
            low = middle
        else:
            high = middle
    return low


def _without_inertia(spectrum: _Spectrum, H, S, project, k: int, scale: float, threshold: float) -> int:
    """Without an `LDLᵀ`: the k + 4 eigenvalues nearest −tol·scale, and a Lanczos probe of the
    lowest eigenvalue (`PROBE_STEPS` steps on the projected Hessian) for a negative one farther
    away; if it finds one, the k lowest from a shift below it.  The index is counted among the
    eigenvalues found (a lower bound when all of them are negative)."""
    spectrum.search(threshold, k + EXTRA, which="LM")
    lowest = _probe_lowest(H, S, project, scale)
    if lowest is not None and lowest < min(spectrum.eig[0], threshold):
        spectrum.eig, spectrum.vec = spectrum.eig[:0], spectrum.vec[:, :0]
        spectrum.search(lowest - 0.1 * abs(lowest), k + EXTRA)
    return int(np.sum(spectrum.eig < threshold))


def _probe_lowest(H, S, project, scale: float) -> float | None:
    """The lowest eigenvalue of H on ker J ∩ S^⊥ if Lanczos (`PROBE_STEPS` steps, the normal
    space shifted up by 2·scale) converges to it, else None."""
    import scipy.sparse.linalg as spla

    n = H.shape[0]

    def apply(v):
        p = _deflated(project(v), S)[:, 0]
        return _deflated(project(H @ p), S)[:, 0] + 2.0 * scale * (np.ravel(v) - p)

    operator = spla.LinearOperator((n, n), matvec=apply, dtype=float)
    v0 = _deflated(project(np.random.default_rng(0).standard_normal(n)), S)[:, 0]
    try:
        theta = spla.eigsh(operator, k=1, which="SA", v0=v0, tol=1e-3, maxiter=PROBE_STEPS, return_eigenvectors=False)
    except spla.ArpackNoConvergence:
        return None
    return float(theta[0])
