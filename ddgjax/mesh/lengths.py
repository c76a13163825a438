"""Geometry of triangles from their edge lengths alone (Sec 5.3, 6.3, 7.3).

A triangulation with an edge-length function satisfying the triangle inequalities is a piecewise
flat surface (Def 5.5, 5.6); its areas, angles, angle defects and the Dirichlet energy of affine
functions depend on the lengths only (Thm 5.5).  Extrinsic quantities of a mesh (V, F) are these
functions composed with `edge_lengths(V, F)` (per edge) or `squared_side_lengths(V[F])` (per
face).

Per-face arrays list the sides *opposite the corners*: `l2[..., k]` is the squared length of the
side opposite corner k, i.e. of the edge (F[f, k+1], F[f, k+2]) (indices mod 3).

The scalar functions (`triangle_area`, `corner_cotangents`, `face_harmonic_index`) take numpy or
jax arrays and stay in that library: the flip loop calls them on numpy arrays, the autodiff
kernels on traced ones.

**Scale.**  Angles, cotangents and the Dirichlet energy are invariant under l ↦ s l, areas scale
by s² (Thm 5.5 holds for every s > 0), but the squares and the fourth powers inside Heron's
formula leave float64 beyond s ≈ 1e±77.  So the functions here bring their lengths to ordinary
size by a power of two (`power_of_two_scale`: exact in floating point, and 1 for lengths of
ordinary size, where nothing changes), compute there, and scale a covariant result back
(`scaled_back`, which raises where the result itself does not fit in float64).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import concrete_value, is_concrete
from .._host import namespace
from ..errors import (
    DegenerateFaceError,
    InvalidInputError,
    NonFiniteError,
    ShapeError,
    TriangleInequalityError,
)
from .connectivity import check_has_faces, from_faces

__all__ = [
    "DEGENERATE",
    "angle_defect_from_lengths",
    "angle_defects",
    "check_edge_lengths",
    "check_face_areas",
    "check_triangle_inequalities",
    "corner_angles",
    "corner_angles_from_lengths",
    "corner_angles_of_sides",
    "corner_cotangents",
    "corner_weights",
    "defect_from_angles",
    "dirichlet_energy",
    "dirichlet_form",
    "edge_lengths",
    "face_harmonic_index",
    "face_side_lengths",
    "normalised",
    "on_padded_rows",
    "padded_size",
    "polarised_cotangents",
    "power_of_two_scale",
    "scaled_back",
    "side_cotangent_columns",
    "side_cotangents",
    "squared_side_lengths",
    "stiffness",
    "triangle_area",
]


def _xp(*arrays):
    """jax.numpy if any argument is a jax array (or tracer), else numpy."""
    return jnp if any(isinstance(a, jax.Array) for a in arrays) else np


_SCALE_STEP = 128  # scales are 2^(128 k): lengths within 2^±64 stay as they are
_SCALE_LIMIT = 7  # |128 k| ≤ 896: the scale and its inverse are normal floats


def power_of_two_scale(m):
    """The power of two 2^(128 k) nearest to m > 0 (elementwise; numpy or jax): m / 2^(128 k)
    lies within 2^±65 (for m within 2^±960), so that squares and fourth powers of lengths of
    that size are ordinary floats, and dividing by it is exact.  It is 1 for m of ordinary size
    (within 2^±64), for m = 0 and for non-finite m.  Constant for autodiff (a scale is piecewise
    constant, and the functions normalised by it do not depend on it)."""
    xp = _xp(m)
    if xp is jnp:
        m = jax.lax.stop_gradient(m)
    k = xp.clip(xp.rint(xp.frexp(m)[1] / _SCALE_STEP), -_SCALE_LIMIT, _SCALE_LIMIT)
    return xp.ldexp(xp.ones_like(m, dtype=float), (_SCALE_STEP * k).astype(xp.int32))


def normalised(X):
    """`(X / s, s)`: the array X (numpy or jax) divided by the power of two s =
    `power_of_two_scale(max |X|)` (exact)."""
    xp = _xp(X)
    s = power_of_two_scale(xp.max(xp.abs(X)) if X.size else xp.asarray(0.0))
    if xp is np and s == 1.0:
        return X, s
    return X * (1.0 / s), s


def scaled_back(x, s, power: int, what: str):
    """x · s^power: a result computed on lengths divided by s, returned to the caller's scale
    (as `power` multiplications, so that s^power itself need not be a float).

    **Raises:** `InvalidInputError` when x is concrete and a finite non-zero entry leaves the
    normal float64 range there (it overflows, or underflows to a subnormal or 0): `what` at this
    scale is not a float64.  Traced values are returned as they are (inf or 0 there).
    """
    out = x
    with np.errstate(over="ignore", under="ignore"):
        for _ in range(abs(power)):
            out = out * s if power > 0 else out / s
    if not (is_concrete((x, s)) and np.any(np.asarray(s) != 1.0)):
        return out
    x_, out_ = np.asarray(x), np.asarray(out)
    finite = np.isfinite(x_) & (x_ != 0)
    bad = finite & ~(np.isfinite(out_) & (np.abs(out_) >= np.finfo(np.float64).tiny))
    if np.any(bad):
        index = tuple(int(i) for i in np.argwhere(bad)[0]) if x_.ndim else ()
        where = f" (entry {index[0] if len(index) == 1 else index})" if index else ""
        exponent = np.log10(abs(float(x_[index]))) + power * np.log10(float(s))
        value = f"{np.sign(x_[index]) * 10 ** (exponent % 1):.3g}e{int(np.floor(exponent))}"
        raise InvalidInputError(
            f"{what}{where} is {value}, outside the normal range of float64 (2.2e-308 to "
            "1.8e308): rescale the input"
        )
    return out


def check_edge_lengths(lengths) -> None:
    """Raise, naming the first offending edge (entry of the concrete (ne,) `lengths`):
    `NonFiniteError` for a NaN or infinite length, `TriangleInequalityError` for a length ≤ 0
    (a Euclidean triangle has positive sides, Def 5.5).  Traced lengths are not inspected."""
    if not is_concrete(lengths):
        return
    l = np.asarray(lengths)
    bad = np.flatnonzero(~np.isfinite(l))
    if bad.size:
        raise NonFiniteError(f"edge {bad[0]} has the non-finite length {l[bad[0]]}")
    bad = np.flatnonzero(l <= 0)
    if bad.size:
        raise TriangleInequalityError(f"edge {bad[0]} has the non-positive length {l[bad[0]]}")


# A face is degenerate when |e1 × e2|² ≤ DEGENERATE |e1|²|e2|², i.e. the sine of its angle at
# corner 0 is below ~1e-7: there the cotangents and the normal are round-off.
DEGENERATE = 1e-14


def check_face_areas(sin2, F) -> None:
    """Raise `DegenerateFaceError` naming the first face (and its vertices, rows of F) whose
    sin² of the angle at corner 0 (`sin2`, (nf,), as from `corner_weights`) is ≤ DEGENERATE
    or NaN: a face of zero area up to round-off (Sec 6.3)."""
    bad = np.flatnonzero(~(np.asarray(sin2) > DEGENERATE))
    if bad.size:
        f = int(bad[0])
        raise DegenerateFaceError(
            f"face {f} {np.asarray(F[f]).tolist()} has zero area (sin² of its angle {sin2[f]:.1e}): its "
            "cotangents and normal are undefined; remove or repair degenerate triangles"
        )


def _sorted3(a, b, c):
    """(x, y, z) with x ≥ y ≥ z elementwise: a permutation of (a, b, c), selected (no arithmetic),
    ties broken by position (NaN if a side is NaN).  Selecting, rather than composing min / max, keeps the derivative of
    a symmetric function of the sorted sides right at ties: `max` splits its derivative between
    equal arguments, which at a three-way tie (an equilateral triangle) gives per-side weights
    that do not sum to 1."""
    xp = _xp(a, b, c)
    a, b, c = (xp.asarray(t) for t in (a, b, c))  # Python floats: `~` of a bool is an int
    ab, ac, bc = a >= b, a >= c, b >= c  # "ranks above", a total order with ties broken by position
    a_first, b_first = ab & ac, ~ab & bc
    c_last, b_last = ac & bc, ab & ~bc
    x = xp.where(a_first, a, xp.where(b_first, b, c))
    z = xp.where(c_last, c, xp.where(b_last, b, a))
    a_middle = ~a_first & ~(~c_last & ~b_last)
    b_middle = ~b_first & ~b_last & ~a_middle
    y = xp.where(a_middle, a, xp.where(b_middle, b, c))
    nan = xp.isnan(a) | xp.isnan(b) | xp.isnan(c)  # comparisons with NaN are False: keep NaN sides NaN
    return tuple(xp.where(nan, a + b + c, t) for t in (x, y, z))


def triangle_area(a, b, c):
    """Area of the Euclidean triangle with sides a, b, c by Heron's formula in Kahan's stable
    order, sides sorted x ≥ y ≥ z:

        A = ¼ √((x + (y + z)) (z − (x − y)) (z + (x − y)) (x + (y − z))),

    accurate for needle-like triangles (no cancellation of rounded sums); NaN when a triangle
    inequality fails.  The sides are divided by the power of two m = `power_of_two_scale(x)`
    and A(a, b, c) = m² A(a/m, b/m, c/m), so that the fourth powers stay in range for every
    side that is a float.
    """
    xp = _xp(a, b, c)
    x, y, z = _sorted3(a, b, c)
    m = power_of_two_scale(x)
    x, y, z = (t * (1.0 / m) for t in (x, y, z))
    return 0.25 * xp.sqrt((x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z))) * m * m


def dirichlet_form(d1, d2, a2, b2, c2):
    """8A times the Dirichlet energy ½ ∫ |∇f|² dA of the affine function with f1 − f0 = d1 and
    f2 − f0 = d2 on a triangle with squared sides a2, b2, c2 (opposite corners 0, 1, 2), written
    with the Gram matrix of the edges e1 = P1 − P0, e2 = P2 − P0 (Sec 6.3), no angles:

        g11 = c2,  g22 = b2,  g12 = (b2 + c2 − a2) / 2,    8A · E = g22 d1² − 2 g12 d1 d2 + g11 d2².

    The one definition of a triangle's Dirichlet energy: `dirichlet_energy` divides it by 8A and
    its Hessian derives the cotan Laplacians (`stiffness`, by autodiff); `corner_cotangents`
    derives the same weights from it by polarisation.  Plain arithmetic on scalars or arrays of
    any library, so that numba compiles it into the flip loop."""
    return b2 * d1 * d1 - (b2 + c2 - a2) * d1 * d2 + c2 * d2 * d2


def polarised_cotangents(form):
    """The corner cotangents of a triangle derived from `form` (`dirichlet_form`: 8A times a
    Dirichlet energy, a quadratic form in the vertex values f): its Hessian entries are exact
    second differences (polarisation, E(0) = 0),

        K_jk = E(e_j + e_k) − E(e_j) − E(e_k),

    and cot α_i = −2 K[i+1, i+2] (Thm 6.6).  A factory, so that the flip loop can compile the
    same derivation with a numba-compiled `form` (`ddgjax.intrinsic.flip_algorithm`)."""

    def corner_cotangents(a2, b2, c2, area):
        """(cot α, cot β, cot γ): the cotangents of the angles opposite the sides with squared
        lengths a2, b2, c2, derived from the triangle's Dirichlet energy by polarisation
        (`polarised_cotangents`); their sum is h(Δ)/4 (Lemma 7.17).  Used by the Delaunay test
        of the flip algorithm (Prop 7.9)."""

        def q(f0, f1, f2):
            return form(f1 - f0, f2 - f0, a2, b2, c2)

        inv = -0.25 / area  # cot = −2 K, K = Q / 8A
        return ((q(0.0, 1.0, 1.0) - q(0.0, 1.0, 0.0) - q(0.0, 0.0, 1.0)) * inv,
                (q(1.0, 0.0, 1.0) - q(0.0, 0.0, 1.0) - q(1.0, 0.0, 0.0)) * inv,
                (q(1.0, 1.0, 0.0) - q(1.0, 0.0, 0.0) - q(0.0, 1.0, 0.0)) * inv)

    return corner_cotangents


corner_cotangents = polarised_cotangents(dirichlet_form)


def face_harmonic_index(a, b, c, area):
    """h(Δ) = (a² + b² + c²) / A(Δ) (Def 7.7), = 4 (cot α + cot β + cot γ) by Lemma 7.17;
    scale-invariant, evaluated on a, b, c / m and A / m² (m = `power_of_two_scale(a)`)."""
    m = power_of_two_scale(a)
    a, b, c = (t * (1.0 / m) for t in (a, b, c))
    return (a * a + b * b + c * c) / (area * (1.0 / m) * (1.0 / m))


def _area_from_squares(l2):
    """A of each face from its (…, 3) squared side lengths (Kahan's Heron)."""
    l = jnp.sqrt(l2)
    return triangle_area(l[..., 0], l[..., 1], l[..., 2])


def dirichlet_energy(f: Float[Array, "3"], l2: Float[Array, "3"]) -> Float[Array, ""]:
    """Dirichlet energy ½ ∫ |∇f|² dA of the affine interpolant of the values f on one triangle,
    written in its squared side lengths (Sec 6.3), no angles: `dirichlet_form` over 8A, A by
    Kahan's Heron (`triangle_area`).  It equals ¼ Σ_k cot α_k (f_{k+1} − f_{k+2})² (Thm 6.6), so
    its Hessian in f *derives* the cotan weights (`stiffness`).  `l2[k]` is the squared side
    opposite corner k.  `f` and `l2` may also be triples of equally shaped arrays (one triangle
    per entry, `side_cotangent_columns`).
    """
    area = triangle_area(jnp.sqrt(l2[0]), jnp.sqrt(l2[1]), jnp.sqrt(l2[2]))
    return dirichlet_form(f[1] - f[0], f[2] - f[0], l2[0], l2[1], l2[2]) / (8.0 * area)


def _stiffness(l2):
    """(nf, 3, 3) Hessians of `dirichlet_energy` in f (it is quadratic: any f, here 0)."""
    return jax.vmap(jax.hessian(dirichlet_energy), in_axes=(None, 0))(jnp.zeros(3, l2.dtype), l2)


@jax.jit
def stiffness(l2: Float[Array, "nf 3"]) -> Float[Array, "nf 3 3"]:
    """The local stiffness matrices K = ∇²_f E of `dirichlet_energy`, per face, by autodiff;
    K[k+1, k+2] = −½ cot α_k (Thm 6.6)."""
    return _stiffness(l2)


def _off_diagonal(K):
    """(nf, 3): −K[k+1, k+2] = ½ cot α_k, the face's contribution to the weight of the side
    opposite corner k."""
    return -K[:, jnp.array([1, 2, 0]), jnp.array([2, 0, 1])]


def _sin2(l2):
    """sin² of the angle at corner 0, (2A / l01²)(2A / l02²) = 4A² / (l01² l02²) (each factor
    scale-invariant; 0 or NaN for a degenerate face)."""
    two_area = 2.0 * _area_from_squares(l2)
    return (two_area / l2[:, 1]) * (two_area / l2[:, 2])


def corner_weights(l2: Float[Array, "nf 3"]):
    """`(w, sin2)`: w (nf, 3) the off-diagonal stiffness entries −K[k+1, k+2] = ½ cot α_k, the
    contribution of each face to the cotan weight (6.2) of the side opposite corner k, derived
    by autodiff (`stiffness`); sin2 (nf,) of the angle at corner 0 (to detect degenerate
    faces).  Traceable (for use inside other jitted kernels); `side_cotangents` is the compiled
    call on numpy arrays."""
    return _off_diagonal(_stiffness(l2)), _sin2(l2)


TRIANGLE_BLOCKS = (256, 2048)
"""The numbers of triangles the compiled kernels of this module run on at once (`padded_size`):
two programs per kernel for meshes of every size."""


def padded_size(n: int) -> int:
    """The number of triangles the compiled kernels of this module run on for n: the first of
    `TRIANGLE_BLOCKS` ≥ n, or n rounded up to a multiple of the last (run block by block,
    `_blockwise`); the extra triangles are equilateral, all sides 1.  A kernel thus compiles two
    programs whatever the sizes of the meshes (a shape not compiled yet costs a trace and a
    compilation, 0.05–0.2 s for the derived cotangents), and runs in about a millisecond per
    block of 2048 triangles."""
    small, block = TRIANGLE_BLOCKS
    return small if n <= small else -(-n // block) * block


def _blockwise(kernel, X: np.ndarray, n: int, axis: int):
    """`kernel` on X, whose `axis` has `padded_size` entries, in blocks of `TRIANGLE_BLOCKS[-1]`
    along that axis; outputs (NumPy) joined along their first axis for rows (`axis` 0) or their
    last for columns, and cut back to n entries there."""
    width = X.shape[axis]
    block = min(width, TRIANGLE_BLOCKS[-1])
    cut = (lambda a: a[:n]) if axis == 0 else (lambda a: a[..., :n])

    def run(start: int):
        part = X[start : start + block] if axis == 0 else X[:, start : start + block]
        return jax.tree_util.tree_map(np.asarray, kernel(np.ascontiguousarray(part)))

    parts = [run(start) for start in range(0, width, block)]
    if len(parts) == 1:
        return jax.tree_util.tree_map(cut, parts[0])
    join = (lambda *a: np.concatenate(a)) if axis == 0 else (lambda *a: np.concatenate(a, axis=-1))
    return jax.tree_util.tree_map(lambda *a: cut(join(*a)), *parts)


def on_padded_rows(kernel, X):
    """`kernel(X)` for X (n, 3) with the rows padded by equilateral triangles (ones) up to
    `padded_size(n)` and run in blocks (`_blockwise`), so that a jitted kernel compiles for two
    shapes; outputs cut back to n rows."""
    X = np.asarray(X)
    n = X.shape[0]
    if padded_size(n) > n:
        X = np.concatenate([X, np.ones((padded_size(n) - n, 3), dtype=X.dtype)])
    return _blockwise(kernel, X, n, 0)


def _on_padded_columns(kernel, X, n: int | None = None):
    """`kernel(X)` for X (3, m) holding n ≤ m triangles (default m) in its first n columns, the
    columns padded by equilateral triangles (ones) up to `padded_size(n)` unless X has those
    already, run in blocks (`_blockwise`); outputs cut back to n columns (their last axis)."""
    X = np.asarray(X)
    n = X.shape[1] if n is None else n
    width = padded_size(n)
    if X.shape[1] != width:
        X = np.concatenate([X[:, :n], np.ones((3, width - n), dtype=X.dtype)], axis=1)
    return _blockwise(kernel, X, n, 1)


def _cotangents_of_columns(s2):
    """The derived cot of the angle opposite side i of n triangles, for i = 0, 1, 2 (three (n,)
    arrays), from their (3, n) squared side lengths by side (row i: side i, from corner i to
    corner i + 1, opposite corner i + 2).

    The Hessian of the sum of the n energies `dirichlet_energy` in their 3n vertex values is
    block diagonal, so one Hessian-vector product (forward over reverse mode) with the direction
    e_j at every triangle gives column j of every stiffness matrix K at once; all operations are
    elementwise on (n,) arrays, which XLA fuses into a few loops (a `vmap` of `jax.hessian`
    builds (n, 3, 3) blocks; stacking the three results into one array makes XLA compute each
    of them three times).  cot(side i) = cot α_{i+2} = −2 K[i, i+1] (Thm 6.6): sides 0 and 2
    from column 0 (K[1, 0], K[2, 0]), side 1 from column 2 (K[1, 2])."""
    l2 = (s2[1], s2[2], s2[0])  # l2[k]: the side opposite corner k, side k + 1
    zero = jnp.zeros_like(s2[0])
    one = jnp.ones_like(zero)
    gradient = jax.grad(lambda f: jnp.sum(dirichlet_energy(f, l2)))

    def column(j):
        return jax.jvp(gradient, ((zero,) * 3,), (tuple(one if k == j else zero for k in range(3)),))[1]

    K0, K2 = column(0), column(2)
    return -2.0 * K0[1], -2.0 * K2[1], -2.0 * K0[2]


_side_cotangent_columns = jax.jit(_cotangents_of_columns)


@jax.jit
def _side_cotangents_and_areas(s2):
    return *_cotangents_of_columns(s2), triangle_area(jnp.sqrt(s2[0]), jnp.sqrt(s2[1]), jnp.sqrt(s2[2]))


def side_cotangent_columns(s2, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cot₀, cot₁, cot₂), each (n,): cot of the angle opposite side i of each of n triangles,
    derived from the Dirichlet energy (the off-diagonal of its Hessian, Thm 6.6; `stiffness`
    per face), for the (3, m) numpy squared lengths `s2` of their sides in halfedge order (row
    i: side i, from corner i to corner i + 1), the triangles in the first n columns (default m).
    Compiled for a few widths: an `s2` of width `padded_size(n)` whose extra columns are ones
    is used as it is (no copy)."""
    return _on_padded_columns(_side_cotangent_columns, s2, n)


def side_cotangents(s2) -> tuple[np.ndarray, np.ndarray]:
    """`(cot, area)`: cot (nf, 3) of the angle opposite side i of each face, twice the derived
    `corner_weights` (`side_cotangent_columns`), and the areas (nf,), for the (nf, 3) numpy
    squared lengths `s2` of the sides in halfedge order (side i from corner i to corner i + 1);
    compiled for a few shapes."""
    *cot, area = _on_padded_columns(_side_cotangents_and_areas, np.ascontiguousarray(np.asarray(s2).T))
    return np.stack(cot, axis=1), area


def squared_side_lengths(P):
    """(…, 3): |P_{k+1} − P_{k+2}|², the squared side opposite corner k of the triangles P
    (…, 3, n)."""
    xp = _xp(P)
    P0, P1, P2 = P[..., 0, :], P[..., 1, :], P[..., 2, :]
    D = xp.stack([P2 - P1, P0 - P2, P1 - P0], axis=-2)
    return xp.sum(D * D, axis=-1)


def check_positions(V, dims: tuple | None = (2, 3)) -> None:
    """Vertex positions: shape (nv, d) with d in `dims` (any d ≥ 1 for None; `ShapeError`), and
    finite coordinates when V is concrete (`NonFiniteError`, naming the vertex)."""
    shape = jnp.shape(V)
    if len(shape) != 2 or (shape[1] not in dims if dims else shape[1] < 1):
        want = " or ".join(f"(nv, {d})" for d in dims) if dims else "(nv, d)"
        raise ShapeError(f"V must be an array of positions of shape {want}, got {shape}")
    value = concrete_value(V)
    if value is not None:
        bad = np.argwhere(~np.isfinite(np.asarray(value, dtype=float)))
        if bad.size:
            index = tuple(int(i) for i in bad[0])
            raise NonFiniteError(f"V has the non-finite value {value[index]} at vertex {index[0]} (index {index})")


def edge_lengths(V, F):
    """l(e) = |v_j − v_i| for each edge (i, j) of `ddgjax.mesh.edges(F)`, (ne,); computed on
    V / s (`normalised`) and multiplied by s, so that |v_j − v_i|² need not be a float.

    **Raises:** `ShapeError` (V not (nv, 3) or (nv, 2)), `NonFiniteError` (a coordinate),
    the errors of `connectivity.from_faces`; `InvalidInputError` if a length overflows float64
    (`scaled_back`).
    """
    check_positions(V)
    h = from_faces(np.asarray(F), n_vertices=jnp.shape(V)[0])
    check_has_faces(h.n_faces)
    E = h.edges
    lengths, s = _lengths(namespace(V).asarray(V), E)
    return scaled_back(lengths, s, 1, "an edge length")


@jax.jit
def _lengths(V, E):
    V, s = normalised(V)
    return jnp.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=-1), s


def _triangles(F) -> np.ndarray:
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3:
        raise ShapeError(f"intrinsic angles need triangles, F of shape (nf, 3); got {F.shape}")
    return F


def face_side_lengths(F, lengths):
    """(nf, 3): entry [f, k] is the length of the side of face f opposite its corner k, i.e. of
    the edge (F[f, k+1], F[f, k+2]); `lengths` ordered like `ddgjax.mesh.edges(F)`."""
    h = from_faces(_triangles(F))
    lengths = jnp.asarray(lengths)
    if lengths.shape != (h.n_edges,):
        raise ShapeError(f"lengths must have shape ({h.n_edges},) (one per edge of F), got {lengths.shape}")
    return lengths[np.roll(h.edge.reshape(-1, 3), -1, axis=1)]


def check_triangle_inequalities(L) -> None:
    """Raise `TriangleInequalityError` naming the first face (row of the (nf, 3) side lengths
    `L`) with a side longer than the other two together (equality is allowed)."""
    if not is_concrete(L):
        return
    L = np.asarray(L)
    slack = L.sum(axis=1, keepdims=True) - 2 * L
    bad = np.argwhere(slack < 0)
    if bad.size:
        f = int(bad[0, 0])
        raise TriangleInequalityError(
            f"face {f} has side lengths {tuple(float(x) for x in L[f])}: the side opposite corner "
            f"{int(bad[0, 1])} is longer than the other two together"
        )


def _semiperimeter_differences(L):
    """(2s, 2(s − l_k)) per face with Kahan's ordering: sides sorted x ≥ y ≥ z and
    2(s − x) = z − (x − y), 2(s − y) = z + (x − y), 2(s − z) = x + (y − z), each exact up to one
    rounding (no cancellation of rounded sums)."""
    order = jnp.argsort(-L, axis=1)
    x, y, z = (jnp.take_along_axis(L, order[:, i : i + 1], axis=1)[:, 0] for i in range(3))
    d_sorted = jnp.stack([z - (x - y), z + (x - y), x + (y - z)], axis=1)
    return x + (y + z), jnp.take_along_axis(d_sorted, jnp.argsort(order, axis=1), axis=1)


def corner_angles(L: Float[Array, "nf 3"]) -> Float[Array, "nf 3"]:
    """Corner angles (nf, 3) of triangles with side lengths L (L[f, k] opposite corner k), by the
    half-angle form of the law of cosines:

        tan(α/2) = √((s − b)(s − c) / (s (s − a))),   s = (a + b + c)/2,

    a the side opposite the corner, the differences s − l in Kahan's stable order.  Unlike
    arccos((b² + c² − a²)/2bc) it keeps full relative accuracy for angles near 0 and π.  Each
    face's sides are divided by the power of two nearest its longest (angles are invariant).
    """
    L = L * (1.0 / power_of_two_scale(jnp.max(L, axis=1, keepdims=True)))
    two_s, D = _semiperimeter_differences(L)
    Db, Dc = jnp.roll(D, -1, axis=1), jnp.roll(D, 1, axis=1)
    return 2 * jnp.arctan2(jnp.sqrt(Db * Dc), jnp.sqrt(two_s[:, None] * D))


_corner_angles = jax.jit(corner_angles)


def corner_angles_of_sides(L) -> np.ndarray:
    """`corner_angles` of concrete (nf, 3) side lengths, compiled (for a few shapes)."""
    return on_padded_rows(_corner_angles, L)


def corner_angles_from_lengths(F, lengths):
    """Corner angles (nf, 3) of the triangles F from edge lengths ordered like
    `ddgjax.mesh.edges(F)` (`corner_angles` of `face_side_lengths`).

    **Raises:** `ShapeError` for non-triangles or lengths of the wrong shape, `NonFiniteError` /
    `TriangleInequalityError` naming an edge with a NaN, infinite or non-positive length
    (`check_edge_lengths`), `TriangleInequalityError` naming the first face whose lengths
    violate a triangle inequality.
    """
    L = face_side_lengths(F, lengths)
    check_edge_lengths(lengths)
    check_triangle_inequalities(L)
    return corner_angles(L) if not is_concrete(L) else jnp.asarray(corner_angles_of_sides(L))


def _sums_at(values, index, n: int):
    """(n,) Σ of `values` at each `index` (NumPy's `bincount` for concrete values, else
    `jax.ops.segment_sum`)."""
    if namespace(values, index) is np:
        return np.bincount(np.asarray(index), weights=np.asarray(values), minlength=n)
    return jax.ops.segment_sum(values, index, n)


def defect_from_angles(angles, vertex, boundary):
    """K(p) = 2π − Σ α at interior vertices (Def 5.2), φ(p) = π − Σ α at boundary vertices
    (Remark 5.4), from the flat corner angles, their vertices and the (nv,) boundary mask;
    NumPy for concrete angles."""
    xp = namespace(angles, vertex, boundary)
    return xp.where(boundary, np.pi, 2 * np.pi) - _sums_at(angles, vertex, boundary.shape[0])


def angle_defects(h, L):
    """(nv,) K(p) = 2π − Σ α at interior vertices and φ(p) = π − Σ α at boundary vertices (Def
    5.2, Remark 5.4, Thm 5.5) of the triangles of the connectivity `h` (`Halfedges`) with side
    lengths L (nf, 3), L[f, k] opposite corner k; NumPy for concrete L (its angles computed in
    blocks, `corner_angles_of_sides`)."""
    if is_concrete(L):
        return defect_from_angles(corner_angles_of_sides(L).reshape(-1), h.vertex, h.boundary_vertex_mask)
    return defect_from_angles(corner_angles(L).reshape(-1), jnp.asarray(h.vertex), jnp.asarray(h.boundary_vertex_mask))


def angle_defect_from_lengths(F, lengths):
    """`angle_defects` of the triangles F with edge lengths ordered like `ddgjax.mesh.edges(F)`,
    (nv,) with nv = max(F) + 1.  **Raises:** as `corner_angles_from_lengths`."""
    L = face_side_lengths(F, lengths)
    check_edge_lengths(lengths)
    check_triangle_inequalities(L)
    return angle_defects(from_faces(_triangles(F)), L)
