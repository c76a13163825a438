"""`continuation`: a branch of constrained critical points followed in a scalar parameter, and its folds.

A family of problems `problem_of(p)` (one declaration; `p` enters through `params` and/or the
fixed entries of `x0`) has the KKT system of Sec 3.1 ("Basic fact from the calculus of
variations: Lagrange multipliers"; `solvers/_kkt.py`) at every p,

    F(w, p) = (∇E − Jᵀλ, −g) = 0,     w = (u, λ)  (the free entries of x, the multipliers),

whose solutions form curves in (w, p)-space.  Natural continuation (solve at p, then at p + Δp)
breaks down at a *fold* (a turning point), where `F_w` is singular and the branch turns back in p:
the catenoid between two coaxial circles ceases to exist beyond a critical distance (Sec 6.4).
Keller's pseudo-arclength continuation (H. B. Keller, "Numerical solution of bifurcation and
nonlinear eigenvalue problems", in *Applications of Bifurcation Theory*, Academic Press 1977,
pp. 359–384) parametrises the branch by (an approximation of) its arclength s instead:

- *tangent*: the unit null vector t of the N × (N + 1) matrix `[F_w  F_p]` (rank N on a regular
  branch, folds included), oriented along the previous one: `[[F_w, F_p], [t_prevᵀ]] v = (0, 1)`,
  `t = v / |v|`;
- *predictor*: `y_pred = y_k + Δs t`, y = (w, p);
- *corrector*: Newton's method on the bordered system

      F(y) = 0,    tᵀ (y − y_pred) = 0,

  whose Jacobian `[[F_w, F_p], [tᵀ]]` stays non-singular through the fold;
- *step length*: Δs grows by 1.5 after an easy corrector (≤ 3 Newton steps), shrinks by 0.7
  after a hard one (≥ 6), is halved and the step retried when the corrector fails, jumps
  (correction > Δs / 2) or turns the tangent by more than 30°.

Norms and inner products on y are weighted, `|y|² = |w|² / N + p²` (N = n + m): a step Δs then
means comparable moves of the parameter and of the RMS unknown, whatever the mesh size.

`F_w` is the solver's KKT matrix `K = [[∇²L, −Jᵀ], [−J, 0]]`: for a problem declared local
(`dg.local_sum`) the sparse matrix assembled from its cells as `method="sparse"` assembles it, and
the bordered systems solved by sparse LU; otherwise `DenseLU.matrix` and dense LU (N ≲ 2,000).
`F_p = ∂F/∂(z0, params) · d(z0, params)/dp` is a forward-mode derivative of the solver's KKT
residual (`KKT.residual`), one compiled function per declaration for every p.  `d(z0, params)/dp` is taken by `jax.jvp` through `problem_of` when
it traces (`params = {"H": p}`, `jnp` arithmetic), else by central differences (`problem_of`
building meshes in NumPy; the tangent is then accurate to ~1e-10, the points still to `tol`).

**Folds.**  A fold lies where the tangent's p-component `dp/ds` changes sign between two
consecutive points; it is refined to `|dp/ds| ≤ 1e-10` by the Illinois (regula-falsi) method on
the predictor distance σ ∈ [0, Δs] from the earlier point (each trial a corrector and a tangent).
At a generic fold one eigenvalue of the reduced Hessian crosses zero: the Morse index
(`solvers.stability`, the second-order condition of Sec 3.1) changes by one there.

**Bifurcations.**  Where the index changes between two consecutive points and `dp/ds` keeps its
sign, an eigenvalue of the reduced Hessian crosses zero while the branch goes on: a simple
bifurcation point (pitchfork or transcritical; e.g. Euler buckling of a straight rod under an
end load), where a second branch of critical points crosses this one in the direction of the
critical eigenvector.  The pseudo-arclength steps pass over it (the bordered Jacobian is
singular only at the point itself); it is refined by the same Illinois iteration on σ, now on the
crossing eigenvalue (the j-th lowest, j the smaller index of the two points) until it is
`≤ BIFURCATION_TOL` times the eigenvalues' scale (`Stability.scale`), and reported with its
eigenvector (`Bifurcation.mode`), the direction of the other branch.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ddgjax.errors import ConvergenceError, InvalidInputError
from ddgjax.problem import Problem, flatten_multipliers

from ._dense import DenseLU
from ._exported import programs
from ._kkt import KKT, residual_weights, scaled_residual, spec_of
from ._solve import Solution, linear_solver_of, solve
from ._stability import stability

__all__ = ["Bifurcation", "Branch", "Fold", "IndexChange", "continuation"]

GROW, SHRINK = 1.5, 0.7  # step-length factors after an easy (≤ EASY steps) or a hard (≥ HARD) corrector
EASY, HARD = 3, 6
MAX_TURN = np.cos(np.pi / 6)  # successive tangents must agree to 30°
MAX_CORRECTION = 0.5  # the corrector may move at most this fraction of Δs from the predictor
FOLD_TOL = 1e-10  # |dp/ds| at a refined fold
FOLD_ITERATIONS = 60
BIFURCATION_TOL = 1e-10  # |crossing eigenvalue| / Stability.scale at a refined bifurcation
FD_STEP = 1e-5  # central differences of (z0, params) in p, relative to max(1, |p|)


class Fold(NamedTuple):
    """A turning point of the branch: `dp/ds = 0`, p extremal along the branch.

    - `p`, `x`, `multipliers`, `energy`, `residual`: the critical point at the fold.
    - `s`: its pseudo-arclength along the branch; `dp_ds`: the tangent's p-component there (≈ 0).
    - `after`: the fold lies between points `after` and `after + 1` of the branch.
    - `refined`: False when the refinement failed (the point is then the nearer of the two).
    """

    p: float
    x: object
    multipliers: object
    energy: float
    residual: float
    s: float
    dp_ds: float
    after: int
    refined: bool


class IndexChange(NamedTuple):
    """The Morse index changes from `before` (at point `after`) to `after_index` (at `after + 1`)."""

    after: int
    before: int
    after_index: int
    p: float


class Bifurcation(NamedTuple):
    """A simple bifurcation point of the branch (module docstring): the Morse index changes from
    `before` (point `after`) to `after_index` (point `after + 1`) with no fold between them.

    - `p`, `x`, `multipliers`, `energy`, `residual`: the critical point where the crossing
      eigenvalue vanishes; `s`: its pseudo-arclength.
    - `eigenvalue`: the crossing eigenvalue of the reduced Hessian there (≈ 0); `mode`: its
      eigenvector as a pytree like x (zero on fixed entries): the direction of the other branch.
    - `refined`: False when the refinement failed (the point is then the nearer of the two).
    """

    p: float
    x: object
    multipliers: object
    energy: float
    residual: float
    s: float
    eigenvalue: float
    mode: object
    after: int
    before: int
    after_index: int
    refined: bool


class Branch(NamedTuple):
    """The result of `continuation`: K points along the branch, in order of arclength.

    - `p` (K,): the parameter; `x`: a pytree like x0 with a leading axis K; `multipliers`: (K, m)
      (for named constraints a pytree of (K, ...) leaves); `energy`, `residual` (K,) (the scaled
      KKT residual max-norm, ≤ `tol`).
    - `index` (K,): the Morse index at each point (`solvers.stability`), −1 where not computed.
    - `s` (K,): pseudo-arclength (weighted norm, module docstring); `dp_ds` (K,): the unit
      tangent's p-component (its sign says whether the branch moves towards p1).
    - `steps` (K,): Newton steps of each corrector (of `solve` for the first point).
    - `folds`: the turning points found (`Fold`); `index_changes`: `IndexChange`s between points;
      `bifurcations`: the index changes that no fold explains (`Bifurcation`, refined).
    - `stopped`: why the continuation ended: `"reached p1"`, `"returned to p0"`, `"max_points"`
      or `"step too small at p = …"`.
    """

    p: np.ndarray
    x: object
    multipliers: object
    energy: np.ndarray
    residual: np.ndarray
    index: np.ndarray
    s: np.ndarray
    dp_ds: np.ndarray
    steps: np.ndarray
    folds: tuple
    index_changes: tuple
    stopped: str
    bifurcations: tuple = ()

    def solution(self, i: int) -> Solution:
        """Point i as a `Solution` of `problem_of(p[i])` (e.g. for `solvers.stability`)."""
        take = lambda tree: jax.tree_util.tree_map(lambda leaf: leaf[i], tree)
        return _solution(take(self.x), take(self.multipliers), self.energy[i], self.residual[i], int(self.steps[i]))


def _solution(x, multipliers, energy, residual, steps) -> Solution:
    return Solution(x, multipliers, jnp.asarray(energy), jnp.asarray(residual), jnp.asarray(steps),
                    jnp.asarray(True), jnp.asarray([residual]), jnp.asarray(0))


# --- the family F(w, p) -----------------------------------------------------------------------


def _tangent_leaf(primal, tangent):
    """The tangent of a params leaf as jvp wants it (float0 for integer leaves, which p cannot move)."""
    if jnp.issubdtype(jnp.result_type(primal), jnp.inexact):
        return tangent
    return np.zeros(np.shape(primal), dtype=jax.dtypes.float0)


@programs
def _system(spec, linear, z0, params, w, dz0, dparams):
    """`(F, F_w, F_p, E)` at (w, p): the KKT residual, the KKT matrix (dense, or the values of the
    sparse pattern of `linear`), ∂F/∂p and the energy."""
    residual = lambda z0_, params_: KKT(spec, z0_, params_).residual(w)
    tangents = jax.tree_util.tree_map(_tangent_leaf, params, dparams)
    F, F_p = jax.jvp(residual, (z0, params), (dz0, tangents))
    kkt = KKT(spec, z0, params)
    return F, linear.matrix(kkt, w), F_p, kkt.energy(w[: spec.n])


@programs
def _energy(spec, z0, params, u):
    return KKT(spec, z0, params).energy(u)


def _float_tangent(leaf):
    """A derivative leaf as a float array (integer params get zero)."""
    leaf = np.asarray(leaf)
    return np.zeros(leaf.shape) if leaf.dtype == jax.dtypes.float0 else leaf.astype(float)


class _Family:
    """`problem_of` with its declaration checked at every p, and `(z0, params)` with their
    p-derivatives: by `jax.jvp` through `problem_of` where it traces, else central differences."""

    def __init__(self, problem_of: Callable, p: float):
        self.problem_of = problem_of
        problem = self.problem(p)
        self.spec = spec_of(problem)
        self.by_jax = True
        # a problem declared local: its KKT matrix from the cells (`dg.local_sum`), as the sparse solvers assemble it
        self.linear = linear_solver_of(problem, self.spec, "sparse", None) if self.spec.is_local else DenseLU()

    def problem(self, p) -> Problem:
        problem = self.problem_of(p)
        if not isinstance(problem, Problem):
            raise InvalidInputError(f"problem_of(p) must return a dg.Problem, got {type(problem).__name__}")
        if hasattr(self, "spec") and spec_of(problem) != self.spec:
            raise InvalidInputError(
                f"problem_of({float(p)!r}) is not the declaration problem_of returned first (another energy or "
                "constraints function, other shapes or fixed entries): build the energy once, outside problem_of, "
                "and let p enter through params or the fixed entries of x0")
        return problem

    def _pieces(self, p):
        problem = self.problem(p)
        return self.spec.layout.ravel(problem.x0), problem.params

    def at(self, p: float):
        """`(z0, params, dz0/dp, dparams/dp, weights)` at p."""
        weights = residual_weights(self.problem(p), self.spec)
        if self.by_jax:
            try:
                (z0, params), (dz0, dparams) = jax.jvp(self._pieces, (jnp.asarray(p, float),), (jnp.ones(()),))
                return z0, params, dz0, jax.tree_util.tree_map(_float_tangent, dparams), weights
            except (TypeError, jax.errors.ConcretizationTypeError):  # NumPy inside problem_of: difference quotients
                self.by_jax = False
        h = FD_STEP * max(1.0, abs(p))
        (zp, pp), (zm, pm) = self._pieces(p + h), self._pieces(p - h)
        z0, params = self._pieces(p)
        diff = lambda a, b: (np.asarray(a, float) - np.asarray(b, float)) / (2 * h)
        return z0, params, diff(zp, zm), jax.tree_util.tree_map(diff, pp, pm), weights

    def system(self, y: np.ndarray):
        """`(F, F_w, F_p, residual)` at y = (w, p) as NumPy arrays, residual the scaled max-norm
        (NaN where the energy is not finite)."""
        import scipy.sparse as sp

        z0, params, dz0, dparams, weights = self.at(float(y[-1]))
        F, K, F_p, energy = _system(self.spec, self.linear, z0, params, np.asarray(y[:-1]), dz0, dparams)
        F, K, F_p = np.asarray(F), np.asarray(K), np.asarray(F_p)
        if not isinstance(self.linear, DenseLU):
            pattern, N = self.linear.pattern, F.size
            K = sp.csc_matrix((K, (pattern.rows, pattern.cols)), shape=(N, N))
        residual = float(scaled_residual(F, weights, self.spec.n))
        return F, K, F_p, residual if np.isfinite(float(energy)) else np.nan  # as `solve`: E must be finite

    def point(self, y: np.ndarray):
        """`(x, multipliers, energy)` of y = (w, p)."""
        spec, p = self.spec, float(y[-1])
        problem = self.problem(p)
        z0 = spec.layout.ravel(problem.x0)
        u, lam = np.asarray(y[: spec.n]), np.asarray(y[spec.n: -1])
        x = jax.tree_util.tree_map(np.asarray, spec.layout.x_of(z0, u))
        energy = float(_energy(spec, z0, problem.params, u))
        return x, jax.tree_util.tree_map(np.asarray, spec.constraint_structure.unravel(lam)), energy


# --- the linear algebra of one point ------------------------------------------------------------


def _bordered_solve(K, F_p, row, rhs) -> np.ndarray:
    """Solve `[[K, F_p], [row]] v = rhs`: LU (sparse for a sparse K), least squares where singular
    (a continuous symmetry that no fixed entry breaks)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    if sp.issparse(K):
        border = [[K, sp.csc_matrix(F_p[:, None])], [sp.csc_matrix(row[None, :-1]), sp.csc_matrix(row[None, -1:])]]
        A = sp.bmat(border, format="csc")
        try:
            v = spla.splu(A).solve(rhs)
            if np.all(np.isfinite(v)):
                return v
        except RuntimeError:  # exactly singular
            pass
        A = A.toarray()
    else:
        A = np.block([[K, F_p[:, None]], [row[None, :]]])
        try:
            v = np.linalg.solve(A, rhs)
            if np.all(np.isfinite(v)):
                return v
        except np.linalg.LinAlgError:
            pass
    return np.linalg.lstsq(A, rhs, rcond=None)[0]


class _Point(NamedTuple):
    y: np.ndarray  # (w, p)
    t: np.ndarray  # unit tangent in the weighted coordinates S y
    residual: float
    steps: int


class _Tracer:
    """Predictor, corrector and tangent in the weighted coordinates `S y`, S = diag(1/√N, …, 1)."""

    def __init__(self, family: _Family, tol: float, max_corrector: int):
        self.family, self.tol, self.max_corrector = family, tol, max_corrector
        N = family.spec.n + family.spec.m
        self.S = np.concatenate([np.full(N, 1.0 / np.sqrt(N)), [1.0]])

    def tangent(self, K, F_p, previous: np.ndarray) -> np.ndarray:
        """The unit null vector of [F_w F_p] (weighted) on the side of `previous`."""
        v = self.S * _bordered_solve(K, F_p, previous * self.S, np.eye(K.shape[0] + 1)[-1])
        return v / np.linalg.norm(v)

    def correct(self, y, row: np.ndarray, previous: np.ndarray) -> _Point | None:
        """Newton on `F(y) = 0, row·(y − y_start) = 0` from y; the converged point with its tangent
        (oriented like `previous`), or None when Newton fails within `max_corrector` steps."""
        y_start = y = np.array(y, dtype=float)
        for step in range(self.max_corrector + 1):
            F, K, F_p, residual = self.family.system(y)
            if not np.isfinite(residual):
                return None
            if residual <= self.tol:
                return _Point(y, self.tangent(K, F_p, previous), residual, step)
            if step == self.max_corrector:
                return None
            y = y + _bordered_solve(K, F_p, row, -np.append(F, row @ (y - y_start)))
        return None

    def step(self, point: _Point, ds: float) -> _Point | None:
        """Predictor Δs along the tangent, corrector on the arclength hyperplane, and the
        safeguards of the module docstring (None: retry with a smaller Δs)."""
        y_pred = point.y + ds * point.t / self.S
        new = self.correct(y_pred, point.t * self.S, point.t)
        if new is None:
            return None
        if np.linalg.norm(self.S * (new.y - y_pred)) > MAX_CORRECTION * ds or new.t @ point.t < MAX_TURN:
            return None
        return new

    def at_parameter(self, a: _Point, b: _Point, p: float) -> _Point | None:
        """The point of the branch at parameter p between a and b (Newton at fixed p from the chord)."""
        theta = (p - a.y[-1]) / (b.y[-1] - a.y[-1])
        y = a.y + theta * (b.y - a.y)
        y[-1] = p
        return self.correct(y, np.eye(y.size)[-1], b.t)


# --- the branch ---------------------------------------------------------------------------------


def continuation(
    problem_of: Callable[[float], Problem],
    p0: float,
    p1: float,
    *,
    x0=None,
    multipliers0=None,
    ds: float | None = None,
    ds_min: float | None = None,
    ds_max: float | None = None,
    max_points: int = 200,
    tol: float = 1e-10,
    max_corrector: int = 8,
    index: bool = True,
    refine_folds: bool = True,
) -> Branch:
    """Follow the branch of critical points of `problem_of(p)` through `(x0, p0)` towards `p1`
    by Keller's pseudo-arclength continuation (module docstring), through folds.

    The first point is `solve(problem_of(p0))` (from `x0` if given); then predictor–corrector
    steps along the branch until it reaches p1 (the last point then lies at p = p1 exactly), turns
    back past p0 (the last point at p0: e.g. the other branch of a fold), `max_points` are taken,
    or the step length falls below `ds_min`.  Folds (`dp/ds = 0`) are refined; the Morse index
    (`solvers.stability`) is evaluated at every point, and a change of it that no fold explains
    is a bifurcation, refined to the zero of the crossing eigenvalue (`Branch.bifurcations`).

    **Arguments:**
    - `problem_of(p) -> Problem`: one declaration (the same energy and constraints functions,
      shapes and fixed mask for every p); p enters through `params` and/or the fixed entries of
      `x0` (e.g. `lambda H: base.with_params({"H": H})`).  Called with a float, and with a JAX
      tracer for `d(z0, params)/dp` (central differences if that fails).
    - `p0`, `p1`: start and target of the parameter (p0 ≠ p1).
    - `x0`, `multipliers0`: the start of the first solve (default `problem_of(p0).x0`).
    - `ds`, `ds_min`, `ds_max`: first, smallest and largest step in the weighted arclength
      (defaults |p1 − p0|/20, 1e-6 ds, |p1 − p0|/4).
    - `max_points`: points on the branch, the first included; `tol`: the scaled KKT residual of
      every point (as in `solve`); `max_corrector`: Newton steps per corrector.
    - `index`: compute the Morse index at each point (`solvers.stability`: by the inertia of the
      sparse KKT matrix for problems declared local, else dense eigenvalues, N ≲ 2,000);
      `refine_folds`: refine the folds and bifurcations (else report the nearer point).

    **Returns:** a `Branch`.

    **Raises:** `InvalidInputError` (p0 = p1 or not finite, bad step options, `problem_of`
    returning another declaration at some p); `ConvergenceError` when the first solve fails.
    """
    p0, p1 = _checked_parameters(p0, p1)
    span = abs(p1 - p0)
    ds = span / 20 if ds is None else float(ds)
    ds_min = 1e-6 * ds if ds_min is None else float(ds_min)
    ds_max = max(span / 4, ds) if ds_max is None else float(ds_max)
    if not (0 < ds_min <= ds <= ds_max < np.inf):
        raise InvalidInputError(f"need 0 < ds_min <= ds <= ds_max < inf, got {ds_min}, {ds}, {ds_max}")
    if int(max_points) < 1:
        raise InvalidInputError(f"max_points must be >= 1, got {max_points}")
    if not (np.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"tol must be finite and positive, got {tol!r}")
    if int(max_corrector) < 1:
        raise InvalidInputError(f"max_corrector must be >= 1, got {max_corrector}")

    family = _Family(problem_of, p0)
    tracer = _Tracer(family, float(tol), int(max_corrector))
    direction = np.sign(p1 - p0)
    first, steps0 = _first_point(family, tracer, p0, direction, x0, multipliers0, tol)
    points, ds_used, stopped = _trace(tracer, first, p0, p1, ds, ds_min, ds_max, int(max_points))
    return _report(family, tracer, points, ds_used, steps0, stopped, index, refine_folds)


def _checked_parameters(p0, p1) -> tuple[float, float]:
    p0, p1 = float(p0), float(p1)
    if not (np.isfinite(p0) and np.isfinite(p1)):
        raise InvalidInputError(f"p0 and p1 must be finite, got {p0}, {p1}")
    if p0 == p1:
        raise InvalidInputError(f"p0 and p1 must differ (the direction of the branch), both are {p0}")
    return p0, p1


def _first_point(family, tracer, p0, direction, x0, multipliers0, tol) -> tuple[_Point, int]:
    problem = family.problem(p0)
    if x0 is not None:
        problem = problem.with_x0(x0)
    sol = solve(problem, tol=tol, multipliers0=multipliers0)
    spec = family.spec
    u = np.asarray(spec.layout.ravel(sol.x))[spec.layout.free]
    y = np.concatenate([u, np.asarray(flatten_multipliers(problem, sol.multipliers)), [p0]])
    F, K, F_p, residual = family.system(y)
    if residual > tol:  # x0's fixed entries differ from problem_of(p0)'s
        raise ConvergenceError(f"the first point has KKT residual {residual:.3e} > tol for problem_of(p0): pass an x0 "
                               "whose fixed entries are problem_of(p0)'s", residual=residual, steps=int(sol.steps))
    return _Point(y, tracer.tangent(K, F_p, direction * np.eye(y.size)[-1]), residual, 0), int(sol.steps)


def _trace(tracer: _Tracer, point: _Point, p0, p1, ds, ds_min, ds_max, max_points):
    """The points of the branch, the step that reached each one, and why it stopped."""
    direction = np.sign(p1 - p0)
    points, ds_used = [point], [0.0]
    while len(points) < max_points:
        new = tracer.step(point, ds)
        while new is None:
            ds *= 0.5
            if ds < ds_min:
                return points, ds_used, f"step too small at p = {point.y[-1]:.12g}"
            new = tracer.step(point, ds)
        end = _crossed(new.y[-1], p0, p1, direction)
        if end is not None:  # the last point at p1 (or p0) exactly, unless Newton fails there
            new = tracer.at_parameter(point, new, end[0]) or new
            points.append(new)
            ds_used.append(float(new.t @ (tracer.S * (new.y - point.y))))
            return points, ds_used, end[1]
        points.append(new)
        ds_used.append(ds)
        point = new
        ds = min(ds * GROW, ds_max) if new.steps <= EASY else (ds * SHRINK if new.steps >= HARD else ds)
        ds = max(ds, ds_min)
    return points, ds_used, "max_points"


def _crossed(p, p0, p1, direction) -> tuple[float, str] | None:
    """`(end, reason)` when p lies beyond p1, or has come back behind p0."""
    if direction * (p - p1) >= 0:
        return p1, "reached p1"
    if direction * (p - p0) < 0:
        return p0, "returned to p0"
    return None


def _illinois(tracer: _Tracer, a: _Point, b: _Point, f, f_a: float, f_b: float, tol: float):
    """`(point, f there, refined)`: the point between a and b where `f(point)` (opposite signs
    `f_a`, `f_b` at a and b) vanishes to `tol`, by the Illinois (regula-falsi) method on the
    predictor distance σ ∈ [0, Δs] from a, each trial a corrector (module docstring)."""
    lo, hi = 0.0, float(a.t @ (tracer.S * (b.y - a.y)))
    f_lo, f_hi = f_a, f_b
    best, f_best = (a, f_a) if abs(f_a) <= abs(f_b) else (b, f_b)
    side = 0
    for _ in range(FOLD_ITERATIONS):
        sigma = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        trial = tracer.correct(a.y + sigma * a.t / tracer.S, a.t * tracer.S, a.t)
        if trial is None:
            return best, f_best, False
        value = f(trial)
        if abs(value) < abs(f_best):
            best, f_best = trial, value
        if abs(value) <= tol or hi - lo <= 1e-14 * max(1.0, hi):
            return best, f_best, abs(f_best) <= tol
        if np.sign(value) == np.sign(f_lo):
            lo, f_lo = sigma, value
            f_hi = f_hi * 0.5 if side == -1 else f_hi
            side = -1
        else:
            hi, f_hi = sigma, value
            f_lo = f_lo * 0.5 if side == 1 else f_lo
            side = 1
    return best, f_best, abs(f_best) <= tol


def _refine_fold(tracer: _Tracer, a: _Point, b: _Point) -> tuple[_Point, bool]:
    """The point between a and b where the tangent's p-component vanishes."""
    fold, _, refined = _illinois(tracer, a, b, lambda point: point.t[-1], a.t[-1], b.t[-1], FOLD_TOL)
    return fold, refined


def _report(family, tracer, points, ds_used, steps0, stopped, with_index, refine_folds) -> Branch:
    p = np.array([pt.y[-1] for pt in points])
    s = np.cumsum(ds_used)
    states = [family.point(pt.y) for pt in points]
    stack = lambda trees: jax.tree_util.tree_map(lambda *leaves: np.stack(leaves), *trees)
    residual = np.array([pt.residual for pt in points])
    index = _morse_indices(family, points, states) if with_index else np.full(len(points), -1)
    turns = _sign_changes([pt.t[-1] for pt in points])
    folds = tuple(_fold(family, tracer, points, s, i, refine_folds) for i in turns)
    changes = tuple(IndexChange(int(i), int(index[i]), int(index[i + 1]), float(p[i + 1]))
                    for i in range(len(points) - 1) if min(index[i], index[i + 1]) >= 0 and index[i] != index[i + 1])
    bifurcations = tuple(_bifurcation(family, tracer, points, s, change, refine_folds)
                         for change in changes if change.after not in set(turns.tolist()))
    x, multipliers, energy = (stack([st[0] for st in states]), stack([st[1] for st in states]),
                              np.array([st[2] for st in states]))
    return Branch(p, x, multipliers, energy, residual, index, s, np.array([pt.t[-1] for pt in points]),
                  np.array([steps0] + [pt.steps for pt in points[1:]]), folds, changes, stopped, bifurcations)


def _sign_changes(values) -> np.ndarray:
    """The i with values[i] and values[i + 1] of opposite signs."""
    values = np.sign(values)
    return np.flatnonzero(values[:-1] * values[1:] < 0)


def _stability_at(family, point: _Point, k: int):
    """`solvers.stability` of the branch's point (by inertia on the sparse path)."""
    x, multipliers, energy = family.point(point.y)
    sol = _solution(x, multipliers, energy, point.residual, point.steps)
    return stability(family.problem(float(point.y[-1])), sol, k=k, method="sparse" if family.spec.is_local else "dense")


def _morse_indices(family, points, states) -> np.ndarray:
    """`solvers.stability`'s index at every point."""
    return np.array([_stability_at(family, pt, 1).index for pt in points], dtype=int)


def _bifurcation(family, tracer, points, s, change: IndexChange, refine: bool) -> Bifurcation:
    """The bifurcation between points `change.after` and `change.after + 1`: where the j-th
    lowest eigenvalue of the reduced Hessian, j = the smaller index, crosses zero."""
    i, j = change.after, min(change.before, change.after_index)
    a, b = points[i], points[i + 1]
    crossing = lambda point: float(_stability_at(family, point, j + 1).eigenvalues[j])
    at_a = _stability_at(family, a, j + 1)
    f_a, f_b = float(at_a.eigenvalues[j]), crossing(b)
    if refine and np.sign(f_a) != np.sign(f_b):
        point, _, refined = _illinois(tracer, a, b, crossing, f_a, f_b, BIFURCATION_TOL * at_a.scale)
    else:
        point, refined = (a if abs(f_a) <= abs(f_b) else b), False
    at = _stability_at(family, point, j + 1)
    x, multipliers, energy = family.point(point.y)
    arclength = float(s[i] + a.t @ (tracer.S * (point.y - a.y)))
    return Bifurcation(float(point.y[-1]), x, multipliers, energy, point.residual, arclength,
                       float(at.eigenvalues[j]), at.mode(j), int(i), change.before, change.after_index, bool(refined))


def _fold(family, tracer, points, s, i, refine: bool) -> Fold:
    """The fold between points i and i + 1."""
    a, b = points[i], points[i + 1]
    fold, refined = _refine_fold(tracer, a, b) if refine else ((a if abs(a.t[-1]) <= abs(b.t[-1]) else b), False)
    x, multipliers, energy = family.point(fold.y)
    arclength = float(s[i] + a.t @ (tracer.S * (fold.y - a.y)))
    return Fold(float(fold.y[-1]), x, multipliers, energy, fold.residual, arclength, float(fold.t[-1]), int(i),
                bool(refined))
