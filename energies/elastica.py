"""Discrete elastica (Def 3.2, Thm 3.8, Cor 3.9, Remark 3.7): the bending energy of an arc-length
polygon, declared as a functional of its unit edge tangents.

**Energy.**  With edge length h = L/n and unit tangents T_0 … T_{n−1}, the local bending energy
at an interior vertex is (Sec 3.3, Def 3.2)

    E_k = log(1 + κ_k²/4),   κ_k = 2 tan(φ_k/2) = 2 |T_k − T_{k−1}| / |T_k + T_{k−1}|,

equal on unit vectors to log 2 − log(1 + <T_k, T_{k−1}>).  We evaluate the first form: its
gradient is O(h) with no O(1) terms cancelling against the unit-length multipliers, so the
KKT residual can be driven to ~ε/h instead of ~ε/h² (it matters from n ≈ 10³ on).

and the problem's energy is `(2/h) Σ_k E_k`, which tends to `½ ∫ κ² ds` (κ_k/h → κ).  The
scale does not change the critical points; it makes the multipliers converge (below), and it
is how the KKT residual is scaled with the discretisation: the gradient with respect to T_k is
then the integral over edge k of the pointwise Euler–Lagrange residual `−T'' + cT + … ` (the
weak residual), so `tol` bounds the same quantity at every n.  (Dividing further by h, to the
pointwise residual, would put its float64 round-off floor, ~ε/h², above 1e-10 from n ≈ 10³.)

**Constraints** (named).  `"unit"`: |T_k|² − 1 = 0 for every free edge, in edge order;
`"chord"`: `c − h Σ_k T_k = 0` (3,) (Remark 3.7: factorising translations, the end points
become the chord).  `solve(...).multipliers` is the dict `{"chord": (3,), "unit": (m,)}`; the
flat constraint vector is the chord, then the unit constraints (sorted names).

**Clamps.**  `clamp="edge"` is Def 3.2: T_0 and T_{n−1} are fixed.  It prescribes the tangent of
the first *edge*, i.e. of the smooth curve at s = h/2, so the discrete curve is only O(h) close
to the smooth clamped elastica.  `clamp="vertex"` prescribes the tangent at the end *vertex*:
T_0 and T_{n−1} are free and the end vertex gets a bending term at half weight with a ghost
edge, the mirror image of T_0 in the line of `t_start` (of T_{n−1} in `t_end`), so that the
vertex tangent T_0 + T_{−1} is `t_start` — a second-order boundary condition, O(h²).

**Multipliers and Theorem 3.8.**  The chord multipliers λ converge to the smooth load `a` of
Thm 3.2 (`T'' = c T + a`): `load(solution)` returns them.  Thm 3.8 (with its typo fixed: the
denominator is 1 + <T_k, T_{k−1}>) holds in the form

    T_k × T_{k−1} / (1 + <T_k, T_{k−1}>) = a_h × γ_k + b,   a_h = (h/2) λ,

at every interior vertex of the curve γ = from_tangents(T, edge_length=h); `theorem_3_8_a`.
The discrete spherical pendulum (Def 3.3, Thm 3.10) of the same tangents has gravity
`(h²/2) λ` (`pendulum_gravity`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

import ddgjax as dg
from ddgjax._checks import check_positive, checked_count, checked_shape, concrete_value, is_concrete, when_concrete
from ddgjax._host import namespace, with_set
from ddgjax.errors import InvalidInputError, NonFiniteError

__all__ = [
    "bending_density",
    "bending_energy",
    "clamped",
    "clamped_bending",
    "finite_scalar",
    "closed",
    "loaded",
    "load",
    "resample",
    "great_circle",
    "initial_tangents",
    "unit_vector",
    "theorem_3_8_a",
    "pendulum_gravity",
    "edge_length",
    "curve",
    "unit_and_chord",
    "InfeasibleChordError",
]


class InfeasibleChordError(InvalidInputError):
    """The prescribed chord is longer than the curve: no arc-length curve realises it."""


def bending_density(T_prev: Float[Array, "3"], T_next: Float[Array, "3"]) -> Float[Array, ""]:
    """`E_k = log(1 + κ_k²/4)` with `κ_k/2 = tan(φ_k/2) = |T_k − T_{k−1}| / |T_k + T_{k−1}|` (Def 3.2).

    On unit vectors this equals `dg.curves.local_bending_energy` (`log 2 − log(1 + <T_k,
    T_{k−1}>)`), whose extension off the sphere defines the flows of Prop 2.1/2.2; this
    extension is the one with the better round-off (module docstring).  Infinite at a
    singular vertex (φ = π).
    """
    d, s = T_next - T_prev, T_next + T_prev
    return jnp.log1p(jnp.dot(d, d) / jnp.dot(s, s))


def bending_energy(T: Float[Array, "n 3"], closed: bool = False) -> Float[Array, ""]:
    """`Σ_k E_k` over the interior vertices (all vertices if `closed`): Def 3.2's functional."""
    T = jnp.asarray(T)
    previous = jnp.roll(T, 1, axis=0) if closed else T[:-1]
    following = T if closed else T[1:]
    return jnp.sum(jax.vmap(bending_density)(previous, following))


# Densities of the declaration: module-level functions, so that every problem of the same size
# shares one compiled solver (parameters carry h, the chord and the clamps).


def _bend(T2, p):
    return (2.0 / p["h"]) * bending_density(T2[0], T2[1])


def _mirrored(T, t):
    """The mirror image of T in the line of the unit vector t: 2<T, t> t − T."""
    return 2.0 * jnp.dot(T, t) * t - T


def _ghost_bend(T1, which, p):
    """Half the bending term of an end vertex with a ghost edge mirrored in the clamp tangent."""
    t = jnp.where(which == 0, p["t_start"], p["t_end"])
    return 0.5 * (2.0 / p["h"]) * bending_density(_mirrored(T1[0], t), T1[0])


def _unit(T1, _):
    return jnp.dot(T1[0], T1[0]) - 1.0


def _chord(T1, share, p):
    return share * p["chord"] - p["h"] * T1[0]


def unit_and_chord(free_edges: np.ndarray, n: int, unit=_unit, chord=_chord) -> dg.locality.Local:
    """The named constraints `{"unit": |T_k|² − 1 (k in free_edges), "chord": c − h Σ_k T_k}`
    (module docstring), with the densities `unit`, `chord` (the rod passes its own)."""
    return dg.concat(
        unit=dg.local_map(unit, free_edges[:, None]),
        chord=dg.local_sum(chord, np.arange(n)[:, None], data=np.full(n, 1.0 / n)),
    )


def edge_length(problem: dg.Problem) -> Float[Array, ""]:
    return problem.params["h"]


@when_concrete
def _check_nonzero(v, name: str) -> None:
    norm = np.linalg.norm(v)
    if not np.isfinite(norm) or norm == 0:
        raise InvalidInputError(f"{name} must be a finite non-zero vector, got {v}")


def unit_vector(v, name: str) -> Float[Array, "3"]:
    """`v / |v|` for a vector `v` of shape (3,), traceable (a clamp direction, an end tangent).

    **Raises:** `ShapeError` for another shape; when `v` is concrete, `InvalidInputError` unless
    it is finite and non-zero (naming it).
    """
    v = jnp.asarray(v, dtype=float)
    checked_shape(v, (3,), name)
    _check_nonzero(v, name)
    return v / jnp.linalg.norm(v)


def start_data(*values):
    """`(xp, values)` for computing a default start: NumPy and the values as NumPy arrays when
    all are concrete (no compilation), else `jax.numpy` and the values without derivative.

    The start carries no derivative either way: the solution's derivative with respect to the
    parameters does not depend on the start (implicit function theorem), only on the fixed
    entries, which the constructors set from the traced parameters themselves.
    """
    known = [concrete_value(v) for v in values]
    if all(k is not None for k in known):
        return np, known
    return jnp, [jax.lax.stop_gradient(jnp.asarray(v, dtype=float)) for v in values]


def _perpendicular(a, xp=np):
    """A unit vector orthogonal to the unit vector a (a × e1, or a × e2 when a is near e1)."""
    helper = xp.where(xp.abs(a[0]) < 0.9, xp.asarray([1.0, 0.0, 0.0]), xp.asarray([0.0, 1.0, 0.0]))
    p = xp.cross(a, helper)
    return p / xp.linalg.norm(p)


def great_circle(a, b, s, xp=np, amplitude=0.0):
    """Points `cos ψ(s) a + sin ψ(s) u` (len(s), 3) of the great circle through the unit vectors
    a and b, with `ψ(s) = θs + A sin(2πs)`: θ = ∠(a, b) and u the unit vector orthogonal to a in
    the plane of a, b (`_perpendicular(a)` when b = ±a).  With the `amplitude` A = 0 the arc from
    a (s = 0) to b (s = 1); with A ≠ 0 the same ends, the tangent turning back and forth in the
    plane like the first buckling mode of a column clamped at both ends (ψ − θs antisymmetric
    about s = ½).  `xp`: the array module (NumPy or jax.numpy)."""
    a, b, s = xp.asarray(a, dtype=float), xp.asarray(b, dtype=float), xp.asarray(s, dtype=float)
    u = b - (a @ b) * a
    norm = xp.linalg.norm(u)  # sin θ
    u = xp.where(norm > 1e-9, u / xp.where(norm > 1e-9, norm, 1.0), _perpendicular(a, xp))
    theta = xp.arctan2(norm, a @ b)  # accurate at θ ≈ 0 and θ ≈ π, unlike arccos
    angle = (theta * s + amplitude * xp.sin(2.0 * np.pi * s))[:, None]
    return xp.cos(angle) * a + xp.sin(angle) * u


@when_concrete
def _check_feasible_chord(chord, length, name: str) -> None:
    if not np.all(np.isfinite(chord)):
        raise NonFiniteError(f"{name} must be finite, got {chord}")
    if np.linalg.norm(chord) >= length:
        raise InfeasibleChordError(
            f"the {name} |γ_n − γ_0| = {np.linalg.norm(chord):.6g} is not shorter than the length "
            f"{float(length):.6g}: no bent arc-length curve has it (infeasible)"
        )


def checked_length(length) -> Float[Array, ""]:
    """The curve's length L as a traceable scalar; when concrete, `InvalidInputError` unless it
    is finite and positive."""
    length = jnp.asarray(length, dtype=float)
    checked_shape(length, (), "length")
    check_positive(length, "the length")
    return length


def checked_chord(chord, length) -> Float[Array, "3"]:
    """The chord as a traceable (3,) array (`ShapeError` for another shape); when concrete,
    `NonFiniteError` for NaN and `InfeasibleChordError` if |chord| ≥ length (no bent arc-length
    curve of that length has it).  `length`: from `checked_length`."""
    chord = jnp.asarray(chord, dtype=float)
    checked_shape(chord, (3,), "chord")
    _check_feasible_chord(chord, length, "chord")
    return chord


def starting_array(x0, default, shape: tuple):
    """`x0` (shape-checked) or the `default()` start, as an array `Problem` then copies."""
    X0 = default() if x0 is None else x0
    checked_shape(X0, shape, "x0")
    return namespace(X0).asarray(X0, dtype=float)


def clamp_ends(X0, first, last) -> tuple[jax.Array, np.ndarray]:
    """X0 with its first and last rows set to the clamps (traceable: the derivative with
    respect to the clamps flows through these fixed entries), and the `fixed` mask of those rows."""
    X0 = with_set(with_set(namespace(X0).asarray(X0, dtype=float), 0, first), -1, last)
    fixed = np.zeros(X0.shape, bool)
    fixed[[0, -1]] = True
    return X0, fixed


def chord_shifted(T, target, steps: int, xp=np):
    """`U = (T + σ)/|T + σ|` with the constant vector σ from the fixed-point iteration
    `σ ← σ + target − mean(U)`, σ = 0 first: tangents whose mean approaches `target`
    (= chord/L, so that h Σ U ≈ chord) when the rows of T are spread out enough."""

    def shifted(shift):
        U = T + shift
        return U / xp.linalg.norm(U, axis=1, keepdims=True)

    shift = xp.zeros(3)
    for _ in range(steps):
        shift = shift + target - shifted(shift).mean(axis=0)
    return shifted(shift)


# the first minimum of the Bessel function J_0: mean_s cos(A sin 2πs) = J_0(A) decreases on [0, it]
BUCKLING_AMPLITUDE_MAX = 3.8317059702075125


def buckling_amplitude(a, b, s, target, xp=np, steps: int = 40):
    """The amplitude A ∈ [0, `BUCKLING_AMPLITUDE_MAX`] of the buckled arc
    `great_circle(a, b, s, amplitude=A)` whose mean has the component of `target` along the
    mean of the plain arc, by bisection.  For parallel ends (a = b) the mean is `J_0(A) a` in the
    limit of many points, decreasing in A; a target beyond `J_0(A_max) ≈ −0.40` gets A_max."""
    axis = great_circle(a, b, s, xp).mean(axis=0)
    axis = axis / xp.linalg.norm(axis)
    wanted = target @ axis
    low, high = xp.asarray(0.0), xp.asarray(BUCKLING_AMPLITUDE_MAX)
    for _ in range(steps):
        mid = 0.5 * (low + high)
        too_long = great_circle(a, b, s, xp, amplitude=mid).mean(axis=0) @ axis > wanted
        low, high = xp.where(too_long, mid, low), xp.where(too_long, high, mid)
    return 0.5 * (low + high)


def chord_mismatch(U, target, xp=np):
    """`|mean(U) − target|`, +∞ when not finite: how far h Σ U is from the chord, over L."""
    mismatch = xp.linalg.norm(U.mean(axis=0) - target)
    return xp.where(xp.isfinite(mismatch), mismatch, xp.inf)


START_MISMATCH = 1e-3  # a chord_shifted arc meets the chord to ~1e-4 or better when it can


def initial_tangents(n: int, length, chord, t_start, t_end, steps: int = 50):
    """A rough start: the great-circle arc from t_start to t_end (`great_circle`, s = k/(n−1)),
    made to meet the chord by `chord_shifted`.

    When that cannot meet it (mean tangent off by more than `START_MISMATCH`, or not finite) the
    end tangents are (nearly) parallel to each other and to the chord: Euler buckling, where the
    straight arc is a bifurcation point and shifting all the tangents by one vector keeps them
    parallel (or divides by zero).  The start is then the arc buckled in its plane,
    `great_circle(..., amplitude=A)`, `A = buckling_amplitude(...)` so that its mean tangent
    has the chord's component along the plain arc — the first buckling mode ψ(s) = A sin(2πs)
    of a column clamped at both ends, ends unchanged — then `chord_shifted` for the rest.  No
    derivative (`start_data`).
    """
    xp, (length, chord, t_start, t_end) = start_data(length, chord, t_start, t_end)
    s, target = xp.linspace(0.0, 1.0, n), chord / length
    with np.errstate(invalid="ignore", divide="ignore"):  # the failed plain start, when it fails
        plain = chord_shifted(great_circle(t_start, t_end, s, xp), target, steps, xp)
    amplitude = buckling_amplitude(t_start, t_end, s, target, xp)
    buckled = chord_shifted(great_circle(t_start, t_end, s, xp, amplitude=amplitude), target, steps, xp)
    plain_error, buckled_error = chord_mismatch(plain, target, xp), chord_mismatch(buckled, target, xp)
    use_buckled = (plain_error > START_MISMATCH) & (buckled_error < plain_error)
    return xp.where(use_buckled, buckled, plain)


def clamped(
    n: int,
    *,
    length: float = 1.0,
    chord,
    t_start,
    t_end,
    clamp: str = "edge",
    x0=None,
) -> dg.Problem:
    """A clamped discrete elastica: n unit edge tangents `T` (n, 3), length L, chord c.

    Critical points of `(2/h) Σ E_k` (Def 3.2) on `{|T_k| = 1, h Σ T_k = chord}` with the ends
    clamped (`clamp="edge"`: T_0 = t_start, T_{n−1} = t_end; `clamp="vertex"`: the end vertex
    tangents, see the module docstring).  The curve is `curve(T, problem)`.

    Constraints `{"unit": (m,), "chord": (3,)}`: `"unit"` has one entry per free edge, m = n − 2
    with `clamp="edge"` (the unit multiplier of a clamped edge is undetermined: T_0 and
    T_{n−1} are fixed, so it has no equation) and m = n with `clamp="vertex"`.

    Differentiable in `length`, `chord`, `t_start`, `t_end`: they enter `params` (h = L/n) and
    the clamped rows of `x0` as traced values, so `jax.grad` of a function of
    `solve(clamped(...))` with respect to them is the implicit derivative; the default start
    carries no derivative (`start_data`).

    **Raises:** `InfeasibleChordError` if |chord| ≥ length (only the straight segment, or
    nothing, is left); `InvalidInputError` for n < 3, a length that is not finite and positive,
    zero or non-finite clamp tangents, an unknown clamp; `ShapeError` for vectors of the wrong
    shape; `NonFiniteError` for NaN in `chord` or `x0`.  Values are checked when concrete
    (also under `jax.grad`; not under `jit`/`vmap`).
    """
    n = checked_count(n, 3, "n, the number of edges of a clamped elastica,")
    if clamp not in ("edge", "vertex"):
        raise InvalidInputError(f"clamp must be 'edge' or 'vertex', got {clamp!r}")
    length = checked_length(length)
    chord = checked_chord(chord, length)
    t_start, t_end = unit_vector(t_start, "t_start"), unit_vector(t_end, "t_end")
    T0 = starting_array(x0, lambda: initial_tangents(n, length, chord, t_start, t_end), (n, 3))
    energy, T0, fixed, free_edges = clamped_bending(n, T0, t_start, t_end, clamp)
    constraints = unit_and_chord(free_edges, n)
    params = {"h": length / n, "chord": chord, "t_start": t_start, "t_end": t_end}
    return dg.Problem(
        energy, T0, constraints=constraints, params=params, fixed=fixed,
        name=f"clamped elastica (n={n}, clamp={clamp})",
    )


def clamped_bending(n: int, T0, t_start, t_end, clamp: str):
    """`(energy, T0, fixed, free_edges)` of the clamped bending energy (2/h) Σ E_k (module
    docstring, Clamps): `clamp="edge"` fixes T_0 = t_start and T_{n−1} = t_end in T0,
    `clamp="vertex"` adds the half-weight ghost-edge terms at the end vertices instead."""
    edges = np.arange(n)
    energy = dg.local_sum(_bend, np.stack([edges[:-1], edges[1:]], axis=1))
    fixed = np.zeros((n, 3), bool)
    if clamp == "edge":
        T0, fixed = clamp_ends(T0, t_start, t_end)
        return energy, T0, fixed, edges[1:-1]
    energy = energy + dg.local_sum(_ghost_bend, np.array([[0], [n - 1]]), data=np.array([0, 1]))
    return energy, T0, fixed, edges


def finite_scalar(value, name: str) -> Float[Array, ""]:
    """`value` as a float64 scalar; `ShapeError` unless it is one, `InvalidInputError` unless it
    is finite (when concrete), naming it."""
    value = jnp.asarray(value, dtype=float)
    checked_shape(value, (), name)
    if is_concrete(value) and not np.isfinite(float(value)):
        raise InvalidInputError(f"{name} must be finite, got {float(value)!r}")
    return value


def _load_potential(T1, p):
    return p["load"] * p["h"] * jnp.dot(T1[0], p["t_start"])


def _lateral(T1, p):
    return p["h"] * (p["across"] @ T1[0])


def loaded(n: int, *, load: float = 0.0, length: float = 1.0, direction=(1.0, 0.0, 0.0), clamp: str = "vertex",
           x0=None) -> dg.Problem:
    """Euler's column: a discrete elastica clamped straight at both ends along the unit vector
    d = `direction` and compressed by an end load P = `load`: n unit edge tangents T (n, 3),
    critical points of

        (2/h) Σ_k E_k + P h Σ_k ⟨T_k, d⟩     on {|T_k| = 1, h Σ_k ⟨T_k, e⟩ = 0 for e ⊥ d},

    the clamped bending energy of `clamped` (`clamp="vertex"`: the end vertex tangents are d,
    O(h²); `"edge"`: T_0 = T_{n−1} = d) plus the potential of the load, P times the chord's
    length along d (its work is −P times the shortening).  Constraint `"lateral"` (2,) keeps the
    far end on the load's line (the chord's components across d vanish); the chord's length is
    free: P is prescribed, where `clamped` prescribes the chord and returns the load as its
    multiplier.

    The straight column T_k = d is critical for every P (unit multipliers P h/2, so the reduced
    Hessian is that of the bending energy minus P h); it is stable up to the first discrete
    Euler load P₁ and loses stability there without a fold, in a bifurcation whose critical
    eigenvalue is double (the column buckles in any plane through d: the index jumps by 2).
    `solvers.continuation` in `load` reports it (`Branch.bifurcations`); P₁ → 4π²/L² (the
    smooth clamped–clamped Euler load of ½∫κ², Euler 1744).

    Constraints `{"lateral": (2,), "unit": (m,)}`; params `{"h", "load", "t_start", "t_end",
    "across"}` (the clamps are d; `across` (2, 3) the unit vectors ⊥ d).  Differentiable in
    `load`.  The default start is the straight column.

    **Raises:** `InvalidInputError` for n < 3, a length that is not finite and positive, a zero
    direction, an unknown clamp, a non-finite load; `ShapeError`, `NonFiniteError` as `clamped`.
    """
    n = checked_count(n, 3, "n, the number of edges of Euler's column,")
    if clamp not in ("edge", "vertex"):
        raise InvalidInputError(f"clamp must be 'edge' or 'vertex', got {clamp!r}")
    length = checked_length(length)
    d = unit_vector(direction, "direction")
    load = finite_scalar(load, "load")
    e1 = _perpendicular(d, jnp)
    across = jnp.stack([e1, jnp.cross(d, e1)])
    T0 = starting_array(x0, lambda: jnp.tile(d, (n, 1)), (n, 3))
    energy, T0, fixed, free_edges = clamped_bending(n, T0, d, d, clamp)
    energy = energy + dg.local_sum(_load_potential, np.arange(n)[:, None])
    constraints = dg.concat(
        unit=dg.local_map(_unit, free_edges[:, None]),
        lateral=dg.local_sum(_lateral, np.arange(n)[:, None]),
    )
    params = {"h": length / n, "load": load, "t_start": d, "t_end": d, "across": across}
    return dg.Problem(energy, T0, constraints=constraints, params=params, fixed=fixed,
                      name=f"Euler's column (n={n}, clamp={clamp})")


def closed(n: int, *, length: float = 1.0, x0) -> dg.Problem:
    """A closed discrete elastica (Remark 3.7): n unit tangents with Σ T_k = 0 and the bending
    energy summed over all n vertices.  Critical points include the regular n-gon (the minimum)
    and Euler's figure-eight (a saddle).  Rotations act freely: the KKT matrix is singular.

    **Raises:** `InvalidInputError` for n < 3 or a length that is not finite and positive,
    `ShapeError` / `NonFiniteError` for `x0`.
    """
    n = checked_count(n, 3, "n, the number of edges of a closed elastica,")
    length = checked_length(length)
    T0 = starting_array(x0, lambda: None, (n, 3))
    edges = np.arange(n)
    energy = dg.local_sum(_bend, np.stack([np.roll(edges, 1), edges], axis=1))
    constraints = unit_and_chord(edges, n)
    params = {"h": length / n, "chord": jnp.zeros(3), "t_start": jnp.zeros(3), "t_end": jnp.zeros(3)}
    return dg.Problem(
        energy, T0, constraints=constraints, params=params,
        name=f"closed elastica (n={n})",
    )


def resample(T: Float[Array, "n 3"], n: int) -> Float[Array, "m 3"]:
    """Tangents of an n-edge curve of the same length from those of another one: linear
    interpolation in arc length between edge midpoints, renormalised.  A start for refining a
    solved elastica (continuation in n), where Newton then needs two or three steps."""
    T = np.asarray(T, dtype=float)
    old = (np.arange(len(T)) + 0.5) / len(T)
    new = (np.arange(n) + 0.5) / n
    U = np.stack([np.interp(new, old, T[:, i]) for i in range(T.shape[1])], axis=1)
    return U / np.linalg.norm(U, axis=1, keepdims=True)


def load(solution) -> Float[Array, "3"]:
    """The chord multipliers λ = `multipliers["chord"]` (3,): they converge to the smooth load a
    of `T'' = cT + a` (Thm 3.2)."""
    return solution.multipliers["chord"]


def theorem_3_8_a(solution, problem: dg.Problem) -> Float[Array, "3"]:
    """The vector a of Thm 3.8 for the curve with edge length h: a = (h/2) λ."""
    return 0.5 * problem.params["h"] * load(solution)


def pendulum_gravity(solution, problem: dg.Problem) -> Float[Array, "3"]:
    """Gravity of the discrete spherical pendulum traced by the tangents (Thm 3.10): (h²/2) λ."""
    return 0.5 * problem.params["h"] ** 2 * load(solution)


def curve(T: Float[Array, "n 3"], problem: dg.Problem, start=(0.0, 0.0, 0.0)) -> Float[Array, "n1 3"]:
    """The vertices γ_0 … γ_n of the polygon with edges h T_k (γ_0 = start)."""
    return dg.curves.from_tangents(T, start=start, edge_length=problem.params["h"])
