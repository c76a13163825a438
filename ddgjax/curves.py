"""Discrete curves (reference Sections 1.1–1.3 and 2.2): tangents, turning angles, the three
discrete curvatures, the vertex tangent, and the tangent and Heisenberg flows.

**Conventions.**  A polyline `gamma` is an (N, 3) or (N, 2) array of vertices.  Edge k joins
vertex k to vertex k + 1; vertex k sits between the edges k − 1 and k, and its turning angle φ_k
is the angle from T_{k−1} to T_k.  An open curve (`closed=False`, the default) has N − 1 edges
and vertex quantities only at its N − 2 interior vertices: entry j belongs to vertex j + 1.  A
closed curve has N edges (edge N − 1 joins vertex N − 1 back to vertex 0, which is not repeated)
and a value at every vertex.  (N, 2) arrays are planar curves: their turning angles and
curvatures are signed, positive for a left turn (κ_± with N = iT, Section 1.3).

**Scaling.**  All three curvatures are inverse radii of osculating circles, so they scale like
1/length and converge to κ on curves sampled at spacing ε → 0 with no extra factor; for unit
edges the "arclength" kind is (1.1) exactly.  The vertex tangent and the flows use the unit
tangents T_k = Δγ_k / ε of an arc-length curve with edges of length ε (Section 1.2), so the
vertex tangent tends to γ' and the Heisenberg flow, with time rescaled t → εt/2, to T' × T
(Remark 2.3).  Every core works on γ / s for a power of two s (`ddgjax.mesh.lengths.normalised`:
exact, and s = 1 at ordinary sizes) and scales its result back (lengths by s, curvatures by
1/s), so tangents, turning angles and curvatures are right for coordinates from 1e-300 to 1e300
(|Δγ|² would leave float64 beyond about 1e±154).

**The flows are derived, not typed in.**  `tangent_flow` and `heisenberg_flow` are the
gradients of the local bending energy E_k = log 2 − log(1 + <T_k, T_{k−1}>) (Remark 3.6),
taken by `jax.grad`:  v_k = −(∇_{T_k} + ∇_{T_{k−1}}) E_k  and  w_k = −T_k × ∇_{T_k} E_k.

Every computation works under `jax.jit` and `jax.grad` (with `closed` and `kind` static);
inputs are validated only when concrete, and never mutated.  The predicates `is_regular`,
`is_arc_length` and the `check_*` functions inspect values, so they need concrete input.
"""

from __future__ import annotations

import functools
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._checks import check_positive, is_concrete
from ._host import namespace, on_device
from .errors import ArcLengthError, InvalidInputError, NonFiniteError, ShapeError, SingularVertexError
from .mesh.lengths import normalised

__all__ = [
    "edge_vectors",
    "edge_lengths",
    "tangents",
    "tangent_velocity",
    "turning_angles",
    "curvature",
    "vertex_tangent",
    "is_regular",
    "check_regular",
    "is_arc_length",
    "check_arc_length",
    "sample",
    "from_tangents",
    "local_bending_energy",
    "tangent_flow",
    "heisenberg_flow",
]

ARC_LENGTH_TOL = 1e-8
"""Default relative tolerance of `is_arc_length` / `check_arc_length`."""

SINGULAR_TOL = 1e-14
"""A vertex with `1 + <T_k, T_{k−1}> <= SINGULAR_TOL` counts as anti-parallel (φ_k = π)."""

Curve = Float[Array, "n d"]


# ---------------------------------------------------------------------------------------------
# validation (numpy, concrete input only)


def _as_rows(x, name: str, noun: str, fewest: int) -> Array:
    """`x` as a float (M, 2) or (M, 3) array; shape checked always, values when concrete."""
    shape = np.shape(x)
    if len(shape) != 2 or shape[1] not in (2, 3):
        raise ShapeError(f"{name} must be an (M, 3) or (M, 2) array, one {noun} a row, got shape {shape}")
    if shape[0] < fewest:
        plural = "vertices" if noun == "vertex" else noun + "s"
        raise ShapeError(f"{name} needs at least {fewest} {plural}, got {shape[0]}")
    if not is_concrete(x):
        return jnp.asarray(x, dtype=float)
    arr = np.asarray(x, dtype=float)
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        k, j = (int(i) for i in bad[0])
        raise NonFiniteError(f"{name}: {noun} {k} has the non-finite coordinate {arr[k, j]} (index ({k}, {j}))")
    return jax.device_put(arr)  # not jnp.asarray, which compiles a program per shape


def _as_curve(gamma, closed: bool, name: str = "gamma") -> Array:
    return _as_rows(gamma, name + (" (closed)" if closed else ""), "vertex", 3 if closed else 2)


def _vertex_index(j: int, closed: bool) -> int:
    """The vertex of entry j of a vertex quantity."""
    return j if closed else j + 1


def _zero_edge_message(E: np.ndarray, closed: bool) -> str | None:
    """Which successive vertices coincide (an edge vector E_k that is exactly 0), or None."""
    zero = np.flatnonzero(np.all(E == 0, axis=1))
    if not zero.size:
        return None
    k = int(zero[0])
    n_vertices = len(E) + (0 if closed else 1)
    return f"vertices {k} and {(k + 1) % n_vertices} coincide (edge {k} has length 0)"


def _antiparallel_message(T_prev: np.ndarray, T_next: np.ndarray, closed: bool) -> str | None:
    """The first vertex with `1 + <T_{k−1}, T_k> <= SINGULAR_TOL` (unit tangents), or None."""
    bad = np.flatnonzero(1 + np.sum(T_prev * T_next, axis=-1) <= SINGULAR_TOL)
    if not bad.size:
        return None
    k = _vertex_index(int(bad[0]), closed)
    prev = (k - 1) % len(T_prev) if closed else k - 1
    return f"vertex {k}: the tangents T_{prev} and T_{k} are anti-parallel (turning angle π)"


def _validate(gamma, closed: bool, *, arc_length: bool = False, singular: str | None = None) -> Array:
    """`gamma` as a float array, after raising for: bad shape (always); when concrete, NaN,
    coinciding successive vertices, edges of different lengths (`arc_length`), and
    anti-parallel successive tangents where the formula `singular` divides by 1 + <T_k, T_{k−1}>."""
    gamma = _as_curve(gamma, closed)
    if not is_concrete(gamma):
        return gamma
    host = np.asarray(gamma)  # the checks in NumPy: no program compiled per number of vertices
    if message := _zero_edge_message(_edges_of(host, closed), closed):
        raise SingularVertexError(f"{message}: the tangent T_k (Def 1.2) is undefined")
    if arc_length:
        check_arc_length(gamma, closed=closed)
    if singular and (message := _antiparallel_message(*_vertex_pairs(_unit_tangents_of(host, closed), closed),
                                                      closed)):
        raise SingularVertexError(f"{message}, where {singular} divides by 1 + <T_k, T_k-1> = 0")
    return gamma


def _irregularity(gamma, closed: bool) -> str | None:
    """Why `gamma` is not regular (Def 1.2: any three successive points differ), or None."""
    E = _edges_of(np.asarray(_as_curve(gamma, closed)), closed)
    if message := _zero_edge_message(E, closed):
        return message
    E_prev, E_next = _vertex_pairs(E, closed)
    back = np.flatnonzero(~np.any(E_prev + E_next != 0, axis=1))  # γ_{k+1} − γ_{k−1} = 0
    if not back.size:
        return None
    k, n = _vertex_index(int(back[0]), closed), len(E) + (0 if closed else 1)
    return f"at vertex {k} the neighbours {(k - 1) % n} and {(k + 1) % n} coincide (the curve turns back, φ = π)"


def is_regular(gamma: Curve, closed: bool = False) -> bool:
    """True when any three successive vertices are different (Def 1.2); concrete input only."""
    return _irregularity(gamma, closed) is None


def check_regular(gamma: Curve, closed: bool = False) -> None:
    """Raise `SingularVertexError` naming the first vertex where `gamma` is not regular (Def 1.2).

    Regular: any three successive vertices γ_{k−1}, γ_k, γ_{k+1} are different.  Concrete input only.
    """
    if message := _irregularity(gamma, closed):
        raise SingularVertexError(f"gamma is not regular (Def 1.2): {message}")


def _arc_length_defect(gamma, length, tol: float, closed: bool) -> str | None:
    check_positive(tol, "tol")
    if length is not None:
        check_positive(length, "length")
    lengths = _lengths_of(np.asarray(_as_curve(gamma, closed)), closed)  # NumPy: nothing compiled per size
    reference = float(np.median(lengths)) if length is None else float(length)
    bad = np.flatnonzero(~(np.abs(lengths - reference) <= tol * reference))
    if not bad.size:
        return None
    k = int(bad[0])
    which = "its median edge length" if length is None else "length"
    return f"edge {k} has length {lengths[k]:.15g}, not {which} {reference:.15g} (relative tolerance {tol:g})"


def is_arc_length(
    gamma: Curve, length: float | None = None, tol: float = ARC_LENGTH_TOL, closed: bool = False
) -> bool:
    """True when every edge has length `length` (default: the median edge length) up to the
    relative tolerance `tol`: a discrete arc-length curve (Def 1.2), with edges of length
    ε = `length` (Section 1.2).  Concrete input only.  **Raises:** `InvalidInputError` unless
    `tol` (and `length`, if given) is finite and positive."""
    return _arc_length_defect(gamma, length, tol, closed) is None


def check_arc_length(
    gamma: Curve, length: float | None = None, tol: float = ARC_LENGTH_TOL, closed: bool = False
) -> None:
    """Raise `ArcLengthError` naming the first edge whose length differs from `length` (default:
    the median edge length) by more than `tol·length` (Def 1.2).  Concrete input only; raises
    `InvalidInputError` as `is_arc_length`."""
    if message := _arc_length_defect(gamma, length, tol, closed):
        raise ArcLengthError(f"gamma is not arc-length parametrised (Def 1.2): {message}")


# ---------------------------------------------------------------------------------------------
# computational cores (jitted; `closed` static)

_jit = functools.partial(jax.jit, static_argnames="closed")


def _vertex_pairs(E, closed: bool):
    """`(E_{k−1}, E_k)` at every vertex k of a closed curve, at the interior vertices of an open one."""
    if closed:
        return E[np.arange(-1, len(E) - 1)], E
    return E[:-1], E[1:]


def _on_vertices(V: Array, closed: bool) -> Array:
    """A field on the vertices, 0 at the two end vertices of an open curve."""
    if closed:
        return V
    zero = jnp.zeros_like(V[:1])
    return jnp.concatenate([zero, V, zero])


def _norm(x: Array) -> Array:
    """Euclidean norm over the last axis, with gradient 0 (not NaN) at 0 (straight vertices);
    NumPy for concrete x (`namespace`)."""
    xp = namespace(x)
    sq = xp.sum(x * x, axis=-1)
    positive = sq > 0
    return xp.where(positive, xp.sqrt(xp.where(positive, sq, 1.0)), 0.0)


def _edges_of(gamma: Array, closed: bool) -> Array:
    """Δγ_k = γ_{k+1} − γ_k; NumPy for concrete γ (`_edges` is the compiled call)."""
    xp = namespace(gamma)
    ends = xp.concatenate([gamma[1:], gamma[:1]]) if closed else gamma[1:]
    return ends - gamma[: len(ends)]


_edges = _jit(_edges_of)


def _normalised_lengths(gamma: Array, closed: bool) -> tuple[Array, Array]:
    """`(|Δγ_k| / s, s)`: the edge lengths of γ / s (`ddgjax.mesh.lengths.normalised`)."""
    gamma, s = normalised(gamma)
    return _norm(_edges_of(gamma, closed)), s


def _lengths_of(gamma: Array, closed: bool) -> Array:
    """|Δγ_k|; NumPy for a NumPy γ (`_lengths` is the compiled call)."""
    lengths, s = _normalised_lengths(gamma, closed)
    return lengths * s


_lengths = _jit(_lengths_of)


def _unit_tangents_of(gamma: Array, closed: bool) -> Array:
    """T_k = Δγ_k / |Δγ_k| (of γ / s, `normalised`); NumPy for a NumPy γ (`_unit_tangents` is
    the compiled call)."""
    E = _edges_of(normalised(gamma)[0], closed)
    return E / _norm(E)[:, None]


_unit_tangents = _jit(_unit_tangents_of)


def _sin_cos(gamma: Array, closed: bool) -> tuple[Array, Array]:
    """`(sin φ_k, cos φ_k)` of the turning angles from T_{k−1} to T_k; signed in the plane;
    NumPy for a NumPy γ (`namespace`)."""
    xp = namespace(gamma)
    T_prev, T_next = _vertex_pairs(_unit_tangents_of(gamma, closed), closed)
    if gamma.shape[-1] == 2:
        sin = T_prev[:, 0] * T_next[:, 1] - T_prev[:, 1] * T_next[:, 0]
    else:
        sin = _norm(xp.cross(T_prev, T_next))
    return sin, xp.sum(T_prev * T_next, axis=-1)


def _half_angle_tangents(gamma: Array, closed: bool) -> Array:
    """`tan(φ_k / 2) = sin φ_k / (1 + cos φ_k)`."""
    sin, cos = _sin_cos(gamma, closed)
    return sin / (1 + cos)


# ---------------------------------------------------------------------------------------------
# Def 1.2: edges and tangents


def edge_vectors(gamma: Curve, closed: bool = False) -> Curve:
    """Vertex difference vectors `Δγ_k = γ_{k+1} − γ_k` (Def 1.2), one per edge.

    **Returns:** (N − 1, d) for an open curve, (N, d) for a closed one.
    **Raises:** `ShapeError`, `NonFiniteError` (naming the vertex).
    """
    return _edges(_as_curve(gamma, closed), closed)


def edge_lengths(gamma: Curve, closed: bool = False) -> Float[Array, " m"]:
    """`|Δγ_k| = |γ_{k+1} − γ_k|` (Def 1.2): (N − 1,) open, (N,) closed."""
    return _lengths(_as_curve(gamma, closed), closed)


def tangents(gamma: Curve, closed: bool = False) -> Curve:
    """Unit edge tangents `T_k = (γ_{k+1} − γ_k) / |γ_{k+1} − γ_k|` (Def 1.2).

    **Returns:** (N − 1, d) for an open curve, (N, d) for a closed one.
    **Raises:** `SingularVertexError` when two successive vertices coincide, `ShapeError`,
    `NonFiniteError` (naming the vertex).
    """
    return _unit_tangents(_validate(gamma, closed), closed)


# ---------------------------------------------------------------------------------------------
# Section 1.3: turning angles and curvatures


def turning_angles(gamma: Curve, closed: bool = False) -> Float[Array, " m"]:
    """Turning angles `φ_k = ∢(T_{k−1}, T_k)` at the vertices (Section 1.3).

    In R³ `φ_k ∈ [0, π]`; for a planar (N, 2) curve `φ_k ∈ [−π, π]`, positive for a left turn.
    **Returns:** (N − 2,) for an open curve (entry j at vertex j + 1), (N,) for a closed one.
    **Raises:** as `tangents`.
    """
    return _turning_angles(_validate(gamma, closed), closed)


@_jit
def _turning_angles(gamma: Array, closed: bool) -> Array:
    """φ_k = atan2(sin φ_k, cos φ_k), compiled."""
    return jnp.arctan2(*_sin_cos(gamma, closed))


def _vertex_curvature(gamma: Array, closed: bool) -> Array:
    """Def 1.4: `κ_k = 2 sin φ_k / |γ_{k+1} − γ_{k−1}|`, the inverse radius of the circle through
    γ_{k−1}, γ_k, γ_{k+1}.  Equals 2 sin(φ_k/2) ≤ 2 for unit edges (Remark 1.4)."""
    sin, _ = _sin_cos(gamma, closed)
    gamma, s = normalised(gamma)
    E_prev, E_next = _vertex_pairs(_edges_of(gamma, closed), closed)
    return 2 * sin / _norm(E_prev + E_next) / s


def _edge_curvature(gamma: Array, closed: bool) -> Array:
    """Def 1.5: `κ_k = (tan(φ_k/2) + tan(φ_{k+1}/2)) / |Δγ_k|` at edge k, the inverse radius of
    the oriented circle touching the lines of the edges k − 1, k, k + 1."""
    half = _half_angle_tangents(gamma, closed)
    lengths, s = _normalised_lengths(gamma, closed)
    if closed:
        return (half + namespace(half).roll(half, -1)) / lengths / s
    return (half[:-1] + half[1:]) / lengths[1:-1] / s


def _arclength_curvature(gamma: Array, closed: bool) -> Array:
    """Def 1.6, (1.1): `κ_k = 2 tan(φ_k/2) / ε`, the inverse radius of the circle touching the
    edges k − 1 and k at their midpoints (ε = 1 gives (1.1)); ε is the mean of the two lengths."""
    lengths, s = _normalised_lengths(gamma, closed)
    length_prev, length_next = _vertex_pairs(lengths, closed)
    return 4 * _half_angle_tangents(gamma, closed) / (length_prev + length_next) / s


def _checked_vertex(gamma, closed: bool) -> Array:
    gamma = _as_curve(gamma, closed)
    if is_concrete(gamma):
        check_regular(gamma, closed)
    return gamma


def _checked_edge(gamma, closed: bool) -> Array:
    if np.shape(gamma)[-1:] != (2,):
        raise ShapeError(
            "curvature kind 'edge' (Def 1.5) is defined for planar curves only: pass an (N, 2) "
            f"array (e.g. gamma[:, :2] for a curve in the xy-plane), got shape {np.shape(gamma)}"
        )
    return _validate(gamma, closed, singular="the edge curvature (Def 1.5)")


def _checked_arclength(gamma, closed: bool) -> Array:
    return _validate(gamma, closed, arc_length=True, singular="the arc-length curvature (Def 1.6)")


_CURVATURES = {
    "vertex": (_checked_vertex, _vertex_curvature, _jit(_vertex_curvature)),
    "edge": (_checked_edge, _edge_curvature, _jit(_edge_curvature)),
    "arclength": (_checked_arclength, _arclength_curvature, _jit(_arclength_curvature)),
}
"""Per kind: the input's checks, the formula (NumPy or traced) and its compiled call."""


def curvature(gamma: Curve, kind: str, closed: bool = False) -> Float[Array, " m"]:
    """Discrete curvature from osculating circles (Section 1.3): the inverse radius of

    - `"vertex"` (Def 1.4): the circle through γ_{k−1}, γ_k, γ_{k+1};
      `κ_k = 2 sin φ_k / |γ_{k+1} − γ_{k−1}|`, at vertices.
    - `"edge"` (Def 1.5, planar (N, 2) curves only): the oriented circle touching the lines of
      the edges k − 1, k, k + 1; `κ_k = (tan(φ_k/2) + tan(φ_{k+1}/2)) / |Δγ_k|`, at edges.
    - `"arclength"` (Def 1.6, arc-length curves only): the circle touching the edges k − 1 and
      k at their midpoints; `κ_k = 2 tan(φ_k/2) / ε` for edges of length ε.  For unit edges this
      is (1.1); the division by ε (the scaling of Section 1.2) makes it converge to κ as ε → 0.

    Signed for planar curves (positive for left turns), non-negative in R³.

    **Returns:** vertex kinds: (N − 2,) open (entry j at vertex j + 1) or (N,) closed; `"edge"`:
    (N − 3,) open (entry j at edge j + 1, the edges between two interior vertices) or (N,) closed.
    **Raises:** `InvalidInputError` (unknown kind), `ShapeError` (`"edge"` on a non-planar
    array), `SingularVertexError` (not regular for `"vertex"`; φ_k = ±π for `"edge"` and
    `"arclength"`, naming the vertex), `ArcLengthError` (`"arclength"` on a curve whose edges
    differ, naming the edge), `NonFiniteError` (naming the vertex).
    """
    if kind not in _CURVATURES:
        raise InvalidInputError(f"curvature kind must be one of {tuple(_CURVATURES)}, got {kind!r}")
    checked, formula, compiled = _CURVATURES[kind]
    gamma = checked(gamma, closed)
    if is_concrete(gamma):  # the formula in NumPy: no program compiled per number of vertices
        return on_device(formula(np.asarray(gamma), closed))
    return compiled(gamma, closed)


# ---------------------------------------------------------------------------------------------
# Remark 3.6 and Section 2.2: the local bending energy and the flows it generates


def local_bending_energy(T_prev: Float[Array, " d"], T_next: Float[Array, " d"]) -> Float[Array, ""]:
    """`E_k = log(1 + κ_k²/4) = log 2 − log(1 + <T_k, T_{k−1}>)` for unit tangents (Remark 3.6).

    The flows differentiate this formula as a function on all of R^d × R^d (not only on unit
    vectors): `∇_{T_k} E_k = −T_{k−1} / (1 + <T_k, T_{k−1}>)`.  Smooth limit: with edges of
    length ε, `E_k ≈ κ² ε² / 4`, so `(4/ε) Σ_k E_k → ∫ κ² ds`.
    """
    return jnp.log(2.0) - jnp.log1p(jnp.dot(T_prev, T_next))


_bending_gradients = jax.vmap(jax.grad(local_bending_energy, argnums=(0, 1)))


def tangent_velocity(T_prev: Array, T_next: Array) -> Array:
    """`−(∇_{T_{k−1}} + ∇_{T_k}) E_k = (T_k + T_{k−1}) / (1 + <T_k, T_{k−1}>)` (Prop 2.1), by autodiff,
    for stacked tangent pairs (m, 3): the vertex velocities of the tangent flow."""
    grad_prev, grad_next = _bending_gradients(T_prev, T_next)
    return -(grad_prev + grad_next)


def _binormal_velocity(T_prev: Array, T_next: Array) -> Array:
    """`−T_k × ∇_{T_k} E_k = T_k × T_{k−1} / (1 + <T_k, T_{k−1}>)`."""
    _, grad_next = _bending_gradients(T_prev, T_next)
    return -jnp.cross(T_next, grad_next)


@_jit
def _vertex_tangent(gamma: Array, closed: bool) -> Array:
    return tangent_velocity(*_vertex_pairs(_unit_tangents(gamma, closed), closed))


def vertex_tangent(gamma: Curve, closed: bool = False) -> Curve:
    """Vertex tangent vector `(T_k + T_{k−1}) / (1 + <T_k, T_{k−1}>)` (Remark 2.1).

    Uses the unit tangents T_k of Def 1.2, which for an arc-length curve with edges of length ε
    are `Δγ_k / ε`: this division by ε is the scaling under which the vertex tangent converges to
    γ' (with the raw differences Δγ_k it would tend to 0).  Its length is
    `2 / |T_k + T_{k−1}| = 1 / cos(φ_k / 2) ≥ 1`.  Computed, like the tangent flow, by `jax.grad`
    of `local_bending_energy`.

    **Returns:** (N − 2, d) open (entry j at vertex j + 1), (N, d) closed.
    **Raises:** `SingularVertexError` where T_k = −T_{k−1} (naming the vertex), and as `tangents`.
    """
    return _vertex_tangent(_validate(gamma, closed, singular="the vertex tangent (Remark 2.1)"), closed)


def _flow_pairs(gamma: Array, closed: bool) -> tuple[Array, Array]:
    """`(T_{k−1}, T_k)` with `T_k = Δγ_k / ε`, ε the mean edge length: unit on arc-length curves
    (computed on γ / s, scale-invariant)."""
    E = _edges(normalised(gamma)[0], closed)
    return _vertex_pairs(E / jnp.mean(_norm(E)), closed)


@_jit
def _tangent_flow(gamma: Array, closed: bool) -> Array:
    return _on_vertices(tangent_velocity(*_flow_pairs(gamma, closed)), closed)


@_jit
def _heisenberg_flow(gamma: Array, closed: bool) -> Array:
    return _on_vertices(_binormal_velocity(*_flow_pairs(gamma, closed)), closed)


def tangent_flow(gamma: Curve, closed: bool = True) -> Curve:
    """Discrete tangent flow (Prop 2.1): `∂_x γ_k = v_k = (T_k + T_{k−1}) / (1 + <T_k, T_{k−1}>)`.

    Derived by `jax.grad`: `v_k = −(∇_{T_k} + ∇_{T_{k−1}}) E_k` with `E_k = local_bending_energy`.
    `T_k = Δγ_k / ε` are the edge vectors of the arc-length curve `gamma` divided by its (mean)
    edge length ε, not normalised edge by edge, so the field is smooth in `gamma`; on arc-length
    curves it keeps every edge length, `<v_{k+1} − v_k, T_k> = 0` (2.5).

    For an open curve only interior vertices move: `v` is 0 at the two end vertices, so the end
    edges 0 and N − 2 do not keep their length (all other edges do).

    **Returns:** (N, d), one velocity per vertex.
    **Raises:** `ArcLengthError` (edges of different lengths, naming the edge),
    `SingularVertexError` (anti-parallel tangents, naming the vertex), `ShapeError`,
    `NonFiniteError`.
    """
    return _tangent_flow(_validate(gamma, closed, arc_length=True, singular="the tangent flow (Prop 2.1)"), closed)


def heisenberg_flow(gamma: Float[Array, "n 3"], closed: bool = True) -> Float[Array, "n 3"]:
    """Discrete Heisenberg flow (Prop 2.2, (2.9)): `∂_t γ_k = w_k = T_k × T_{k−1} / (1 + <T_k, T_{k−1}>)`.

    Derived by `jax.grad`: `w_k = −T_k × ∇_{T_k} E_k` with `E_k = local_bending_energy`, and
    `T_k = Δγ_k / ε` as in `tangent_flow`.  It is normal to both adjacent edges, so it keeps
    every edge length (open curves included), and it commutes with `tangent_flow` on closed
    arc-length curves.  Smooth limit (Remark 2.3): `(2/ε) w_k → T' × T`.  For an open curve `w`
    is 0 at the end vertices.

    **Returns:** (N, 3).
    **Raises:** `ShapeError` (not a space curve), and as `tangent_flow`.
    """
    if np.shape(gamma)[-1:] != (3,):
        raise ShapeError(f"the Heisenberg flow needs a curve in R³ (N, 3), got shape {np.shape(gamma)}")
    checked = _validate(gamma, closed, arc_length=True, singular="the Heisenberg flow (Prop 2.2)")
    return _heisenberg_flow(checked, closed)


# ---------------------------------------------------------------------------------------------
# sampling smooth curves (Section 1.2) and reconstruction from tangents


def _spacing(n: int | None, eps: float | None, length: float | None) -> tuple[int, float]:
    """`(n, eps)` from two of: n edges, spacing eps, total parameter length `length = n·eps`."""
    if sum(v is not None for v in (n, eps, length)) != 2:
        raise InvalidInputError(f"give exactly two of n, eps, length; got n={n}, eps={eps}, length={length}")
    if n is None:
        n = int(round(length / eps))
        if n < 1 or abs(n * eps - length) > 1e-9 * abs(length):
            raise InvalidInputError(f"length / eps = {length / eps} must be a positive integer (the number of edges)")
    elif eps is None:
        eps = length / n
    if int(n) < 1 or not eps > 0:
        raise InvalidInputError(f"need n >= 1 edges and a spacing eps > 0, got n={n}, eps={eps}")
    return int(n), float(eps)


@functools.lru_cache(maxsize=16)
def _evaluate(curve: Callable) -> Callable:
    """`s ↦ curve(s)` on an array of parameters, compiled (once per curve and size)."""
    return jax.jit(jax.vmap(curve))


def _equal_chord_spacings(points: Callable, start: float, h: np.ndarray, max_iterations: int = 60) -> np.ndarray:
    """Parameter steps `h` (same sum) after which all chords |c(s_{k+1}) − c(s_k)| are equal.

    Fixed point of `h_k ← h_k · mean(chord) / chord_k`: for an arc-length parametrisation
    chord_k = h_k (1 − κ² h_k² / 24 + …), so each step shrinks the deviation by O(κ² h²).
    """
    total = h.sum()
    for _ in range(max_iterations):
        p = np.asarray(points(jnp.asarray(start + np.concatenate([[0.0], np.cumsum(h)]))))
        chords = np.linalg.norm(np.diff(p, axis=0), axis=1)
        deviation = np.max(np.abs(chords / chords.mean() - 1))
        if deviation <= 8 * np.finfo(float).eps * max(1.0, np.max(np.abs(p))) / chords.mean():
            break
        h = h * chords.mean() / chords
        h = h * total / h.sum()
    if not deviation <= 1e-3 * ARC_LENGTH_TOL:
        raise InvalidInputError(
            f"equal chords not reached (relative chord spread {deviation:.3g} after {max_iterations} "
            "iterations): is curve parametrised by arc length?"
        )
    return h


def sample(
    curve: Callable,
    n: int | None = None,
    *,
    eps: float | None = None,
    length: float | None = None,
    start: float = 0.0,
    closed: bool = False,
    equal_chords: bool = False,
    return_parameters: bool = False,
) -> Curve | tuple[Curve, Float[Array, " m"]]:
    """A discrete curve sampled from a smooth one at spacing ε (Section 1.2).

    **Arguments:**
    - `curve(s) -> (d,)`: a JAX-traceable smooth curve of one scalar parameter; for `eps` to be
      the arc-length spacing it must be parametrised by arc length.
    - two of `n` (number of edges), `eps` (parameter spacing) and `length` (= n·eps: the
      parameter length of the sampled piece, or the period of a closed curve).
    - `closed`: `curve` has period n·eps; returns the n vertices `curve(start + k·eps)`,
      k = 0..n − 1 (no repeated vertex).  Open: the n + 1 vertices k = 0..n.
    - `equal_chords`: move the parameters (keeping both ends, or the period) until all edges
      have the same length, up to round-off: a discrete arc-length curve (Def 1.2) inscribed in
      `curve`, with edge length ε(1 + O(ε²)).  Needs an arc-length parametrisation (nearly).
    - `return_parameters`: also return the parameters `s_k` of the vertices (to compare with
      smooth quantities at the same points).

    **Returns:** (n + 1, d) open, (n, d) closed; with `return_parameters`, `(gamma, s)`.
    **Raises:** `InvalidInputError` (inconsistent n, eps, length; equal chords not reached),
    `NonFiniteError` (curve gives NaN; naming the vertex).
    """
    n, eps = _spacing(n, eps, length)
    h = np.full(n, eps)
    if equal_chords:
        h = _equal_chord_spacings(_evaluate(curve), start, h)
    s = start + np.concatenate([[0.0], np.cumsum(h)])
    s = jnp.asarray(s[:-1] if closed else s)
    gamma = _as_curve(_evaluate(curve)(s), closed, "sample(curve)")
    return (gamma, s) if return_parameters else gamma


def from_tangents(T: Curve, start=None, edge_length: float = 1.0) -> Curve:
    """The curve with `γ_0 = start` and `γ_{k+1} = γ_k + edge_length · T_k` (Def 1.2 inverted).

    **Arguments:** `T` (M, d) edge tangents (unit for an arc-length curve; not normalised here),
    `start` (d,) (default: the origin, (0, 0, 0) or (0, 0)), `edge_length` ε.
    **Returns:** (M + 1, d): an open curve; for a closed curve (Σ T_k = 0) the last vertex is
    `start` again and is dropped by `[:-1]`.
    **Raises:** `ShapeError`, `NonFiniteError` (naming the tangent).
    """
    T = _as_rows(T, "T", "tangent", 1)
    d = T.shape[1]
    start = np.zeros(d) if start is None else namespace(start).asarray(start, dtype=float)
    if np.shape(start) != (d,):
        raise ShapeError(f"start must have shape ({d},) like the rows of T, got {np.shape(start)}")
    return _summed_steps(T, start, edge_length)


@jax.jit
def _summed_steps(T: Float[Array, "m d"], start: Float[Array, " d"], edge_length) -> Float[Array, "m+1 d"]:
    """`γ_k = start + ε Σ_{j<k} T_j`, k = 0..M."""
    steps = jnp.cumsum(edge_length * T, axis=0)
    return start + jnp.concatenate([jnp.zeros((1, T.shape[1]), steps.dtype), steps])
