"""Curvature of polyhedral surfaces (Sec 5.2): angle defects and edge mean curvature, in jnp.

`V` is (nv, 3) float; `F` an (nf, k) int array (numpy or jnp) or a list of convex planar polygons.
The geometry is jnp and differentiable in `V`; for an (nf, k) array everything is jnp, so
`jax.jit(angle_defect)(V, F)` works with a traced `F`, and functions of `V` alone
(`jax.jit(lambda V: edge_mean_curvature(V, F))`) close over a concrete `F` whose connectivity is
built (and validated) once, at trace time.

**Scale.**  Angles, angle defects and dihedral angles are invariant under V ↦ sV, edge mean
curvature scales by s and areas by s².  Every kernel works on V / s for a power of two s
(`lengths.normalised`: exact, and s = 1 at ordinary sizes) and scales its result back
(`lengths.scaled_back`), so the answers are right for coordinates from 1e-300 to 1e300, or an
error says which result is not a float64.

**Validation** (of concrete input): NaN / inf coordinates (`NonFiniteError` naming the index);
coincident vertices of an edge, where the angles are undefined (`SingularVertexError` naming the
vertices, the edge and a face); faces of zero area up to round-off, where the normal is undefined,
in the functions that use normals (`DegenerateFaceError` naming the face).  A collinear triangle
whose vertices are distinct has the angles 0, 0, π (the limit), so angle defects are defined there.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check_positive, is_concrete
from .._host import namespace
from ..errors import MeshError, OrientationError, SingularVertexError
from .connectivity import Halfedges, check_has_faces, checked_corners, faces_as_corners, from_faces
from .lengths import check_positions
from .lengths import (
    angle_defects,
    check_face_areas,
    corner_angles_of_sides,
    defect_from_angles,
    normalised,
    scaled_back,
    squared_side_lengths,
)
from .lengths import corner_angles as angles_from_sides

__all__ = [
    "corner_angles",
    "angle_defect",
    "vertex_kind",
    "face_area_vectors",
    "surface_area",
    "dihedral_angles",
    "edge_mean_curvature",
    "total_mean_curvature",
    "steiner_area",
]


def _corners(F):
    """`(vertex, next, prev)` per corner; jnp-traceable for an (nf, k) array."""
    if hasattr(F, "shape") and len(F.shape) == 2:
        nf, k = F.shape
        index = np.arange(nf * k).reshape(nf, k)
        xp = namespace(F)
        return xp.reshape(xp.asarray(F), -1), np.roll(index, -1, 1).reshape(-1), np.roll(index, 1, 1).reshape(-1)
    vertex, _, nxt = faces_as_corners(F)
    prv = np.empty_like(nxt)
    prv[nxt] = np.arange(nxt.size)
    return vertex, nxt, prv


def _check_positions(V) -> None:
    """Shape (nv, 3), and finite coordinates when V is concrete (`NonFiniteError`)."""
    check_positions(V, dims=(3,))


def _validate(V, F):
    """Shape checks, finite coordinates, and for a concrete `F` its connectivity (at least one
    face, manifold, indices, no unused vertex, no edge of length 0 when V is concrete), returned
    as `Halfedges`; None for a traced `F`.
    """
    _check_positions(V)
    if not is_concrete(F):
        return None
    nv = jnp.shape(V)[0]
    h = from_faces(F if not hasattr(F, "shape") else np.asarray(F), n_vertices=nv)
    check_has_faces(h.n_faces)
    unused = np.flatnonzero(np.bincount(h.vertex, minlength=nv) == 0)
    if unused.size:
        raise MeshError(f"vertex {unused[0]} lies in no face; remove unused vertices first")
    _check_distinct_ends(V, h)
    return h


def _check_distinct_ends(V, h: Halfedges) -> None:
    """`SingularVertexError` naming the first edge whose two vertices have equal coordinates
    (concrete V): the angles at its ends, and the normals of its faces, are undefined."""
    if not is_concrete(V):
        return
    V, E = np.asarray(V), h.edges
    same = np.flatnonzero(np.all(V[E[:, 0]] == V[E[:, 1]], axis=1))
    if same.size:
        e = int(same[0])
        raise SingularVertexError(
            f"vertices {E[e, 0]} and {E[e, 1]} coincide (edge {e} of face {h.face[h.halfedges[e, 0]]} "
            "has length 0): the angles at them are undefined; weld or move them"
        )


def _first_corners(F):
    """(v_0, v_1, v_{k−1}) of each face, as int arrays."""
    if hasattr(F, "shape"):
        F = np.asarray(F)
        return F[:, 0], F[:, 1], F[:, -1]
    return tuple(np.array([f[i] for f in F], dtype=np.int64) for i in (0, 1, -1))


def _check_areas(V, F, N) -> None:
    """`DegenerateFaceError` (`lengths.check_face_areas`) naming the first face of zero area up
    to round-off: (2A / |e₁|²)(2A / |e₂|²) ≤ DEGENERATE, A = |N| the area of the face (the norm
    of its area vector N) and e₁, e₂ its sides at corner 0 (for a triangle, sin² of the angle
    there).  V and N of one scale (concrete; nothing is checked for traced values)."""
    if not is_concrete((V, N)):
        return
    V, two_area = np.asarray(V), 2.0 * np.linalg.norm(np.asarray(N), axis=1)
    v0, v1, vk = _first_corners(F)
    e1, e2 = V[v1] - V[v0], V[vk] - V[v0]
    check_face_areas((two_area / np.einsum("ij,ij->i", e1, e1)) * (two_area / np.einsum("ij,ij->i", e2, e2)), F)


def boundary_vertex_mask(h: Halfedges) -> np.ndarray:
    """Bool (n_vertices,): the vertex lies on a boundary edge (`Halfedges.boundary_vertex_mask`)."""
    return h.boundary_vertex_mask


def _angle_between(u, w):
    """Unsigned angle in [0, π] between rows of u and w: atan2(|u × w|, u · w) (accurate near 0, π)."""
    return jnp.arctan2(jnp.linalg.norm(jnp.cross(u, w), axis=-1), jnp.sum(u * w, axis=-1))


def _is_triangle_array(F) -> bool:
    return hasattr(F, "shape") and len(F.shape) == 2 and F.shape[1] == 3


@partial(jax.jit, static_argnames="triangles")
def _angles_at_corners(V, vertex, nxt, prv, triangles: bool):
    """Flat corner angles of V / s (`lengths.normalised`; angles are scale-invariant).
    `triangles` (corners of an (nf, 3) array): from the side lengths alone
    (`lengths.corner_angles`, Thm 5.5); polygons, whose angles the side lengths do not
    determine: ∠(v_next − v, v_prev − v)."""
    V = normalised(V)[0]
    if triangles:
        L = jnp.sqrt(squared_side_lengths(V[vertex.reshape(-1, 3)]))
        return angles_from_sides(L).reshape(-1)
    P = V[vertex]
    return _angle_between(P[nxt] - P, P[prv] - P)


def corner_angles(V, F):
    """Interior angle α at every corner of every (convex) face: for triangles from the side
    lengths |v_j − v_i| (`lengths.corner_angles`), for polygons α = ∠(v_next − v, v_prev − v).

    **Returns:** (nf, k) for an (nf, k) array `F`, else (n_corners,) in the order of the faces.
    **Raises:** as `angle_defect`; scale-invariant (module docstring).
    """
    h = _validate(V, F)
    L = _concrete_side_lengths(V, F, h)
    if L is not None:
        return corner_angles_of_sides(L)
    angles = _angles_at_corners(namespace(V).asarray(V), *_corners(F), triangles=_is_triangle_array(F))
    return angles.reshape(jnp.shape(F)) if hasattr(F, "shape") else angles


def _concrete_side_lengths(V, F, h) -> np.ndarray | None:
    """(nf, 3) side lengths of V / s (`normalised`; L[f, k] opposite corner k) in NumPy for a
    concrete V and a concrete (nf, 3) `F` (checked: `h`), whose angles are then computed in
    blocks (`lengths.corner_angles_of_sides`) rather than by a kernel compiled per mesh; None
    otherwise."""
    if h is None or not _is_triangle_array(F) or not is_concrete(V):
        return None
    return np.sqrt(squared_side_lengths(normalised(np.asarray(V, dtype=float))[0][np.asarray(F)]))


def _boundary_vertices(vertex, nxt, nv):
    """Bool (nv,): the vertex is on a boundary edge (an edge with a single halfedge); jnp, for a
    traced F (with a concrete F, `boundary_vertex_mask` avoids sorting constants under jit).
    """
    head = vertex[nxt]
    key = jnp.minimum(vertex, head) * nv + jnp.maximum(vertex, head)
    ordered = jnp.sort(key)
    count = jnp.searchsorted(ordered, key, side="right") - jnp.searchsorted(ordered, key, side="left")
    lonely = (count == 1).astype(jnp.int32)
    return jnp.maximum(jax.ops.segment_max(lonely, vertex, nv), jax.ops.segment_max(lonely, head, nv)) > 0


def angle_defect(V, F):
    """Discrete Gaussian curvature per vertex, (nv,) (Def 5.2, Remark 5.4):

        K(p) = 2π − Σ_i α_i  at an interior vertex,   φ(p) = π − Σ_i α_i  at a boundary vertex,

    so that Σ_p = 2πχ for every (possibly bounded, possibly non-orientable) surface (Thm 5.6).
    Scale-invariant (module docstring).

    **Raises:** `ShapeError` for V not (nv, 3); `NonFiniteError` for NaN / inf coordinates; for
    concrete `F`, `MeshError` / `NonManifoldError` for bad faces (see `connectivity.from_faces`)
    and for a vertex in no face, and `SingularVertexError` naming two vertices of an edge that
    coincide.
    """
    h = _validate(V, F)
    L = _concrete_side_lengths(V, F, h)
    if L is not None:
        return angle_defects(h, L)
    vertex, nxt, prv = _corners(F)
    nv = jnp.shape(V)[0]
    boundary = _boundary_vertices(vertex, nxt, nv) if h is None else h.boundary_vertex_mask
    return _angle_defect_kernel(namespace(V).asarray(V), vertex, nxt, prv, boundary, triangles=_is_triangle_array(F))


@partial(jax.jit, static_argnames="triangles")
def _angle_defect_kernel(V, vertex, nxt, prv, boundary, triangles: bool):
    return defect_from_angles(_angles_at_corners(V, vertex, nxt, prv, triangles), vertex, boundary)


def vertex_kind(V, F, atol: float = 1e-12):
    """+1 elliptic (K > atol), 0 flat (|K| ≤ atol), −1 hyperbolic (K < −atol) per vertex (Def 5.2);
    boundary vertices are classified by their turning angle.

    **Raises:** `InvalidInputError` unless atol is finite and positive; as `angle_defect`.
    """
    check_positive(atol, "atol")
    K = angle_defect(V, F)
    return jnp.where(K > atol, 1, jnp.where(K < -atol, -1, 0))


def face_area_vectors(V, F):
    """(nf, 3): ½ Σ_i v_i × v_{i+1} over each face (Newell); its norm is the area of a planar
    face and its direction the normal given by the face's orientation.  Computed on V / s and
    scaled back by s² (module docstring).

    **Raises:** `ShapeError`, `NonFiniteError` (coordinates); `MeshError` (a face with an index
    that is not a vertex of V, or repeating a vertex, named); `InvalidInputError` where an entry
    is not a float64 at this scale (`lengths.scaled_back`).
    """
    _check_positions(V)
    N, s = _normalised_area_vectors(V, F)
    return scaled_back(N, s, 2, "a face area vector")


def _normalised_area_vectors(V, F):
    """`(N, s)`: the area vectors of the faces of V / s, s = `lengths.normalised(V)[1]`; a
    concrete F is checked first (`connectivity.checked_corners`: indices of vertices of V, no
    repeated vertex in a face)."""
    if is_concrete(F):
        vertex, face, nxt = checked_corners(np.asarray(F) if hasattr(F, "shape") else F, jnp.shape(V)[0])
        n_faces = int(face.max()) + 1
    else:  # traced faces of an (nf, k) array
        vertex, nxt, _ = _corners(F)
        n_faces, k = jnp.shape(F)
        face = np.repeat(np.arange(n_faces), k)
    V, s = normalised(namespace(V).asarray(V))
    return _area_vectors(V, vertex, nxt, face, n_faces), s


@partial(jax.jit, static_argnums=4)
def _area_vectors(V, vertex, nxt, face, n_faces):
    P = V[vertex]
    return 0.5 * jax.ops.segment_sum(jnp.cross(P, P[nxt]), face, n_faces)


def surface_area(V, F):
    """A(S) = Σ_f |face area vector| (planar faces); scales by s² (module docstring).

    **Raises:** as `face_area_vectors`.
    """
    _check_positions(V)
    N, s = _normalised_area_vectors(V, F)
    return scaled_back(jnp.sum(jnp.linalg.norm(N, axis=-1)), s, 2, "the surface area")


def _interior_pairs(F, nv):
    """For each edge: a halfedge h1 on it, its twin h2 (−1 on the boundary), and their faces;
    raises `OrientationError` where both faces run through an edge in the same direction.
    `F` may already be `Halfedges`.
    """
    h = F if isinstance(F, Halfedges) else from_faces(np.asarray(F) if hasattr(F, "shape") else F, n_vertices=nv)
    first, h2 = h.halfedges[:, 0], h.halfedges[:, 1]
    inner = h2 >= 0
    same = inner & (h.sign[first] == h.sign[np.where(inner, h2, first)])
    if np.any(same):
        e = int(np.argmax(same))
        raise OrientationError(
            f"edge {e} ({h.edges[e, 0]}, {h.edges[e, 1]}) is traversed in the same direction by faces "
            f"{h.face[first[e]]} and {h.face[h2[e]]}; the signed dihedral angle needs a consistent "
            "orientation (mesh.orient(F), if the surface is orientable)"
        )
    return h, first, h2


def dihedral_angles(V, F):
    """Signed exterior dihedral angle θ(e) ∈ (−π, π] per edge, ordered like `edges(F)` (Def 5.3).

    With N₁, N₂ the unit normals of the faces left and right of e (N from the face orientation)
    and d the unit direction of e as traversed by the first face,

        θ(e) = atan2(⟨d, N₁ × N₂⟩, ⟨N₁, N₂⟩),

    the angle turning N₁ into N₂.  It is positive at convex edges of an outward-oriented surface
    (θ = π/2 on the cube) and negative at concave ones; θ = 0 on boundary edges.  Scale-invariant
    (module docstring).

    **Raises:** `OrientationError` if two faces traverse an edge in the same direction; as
    `angle_defect`; `DegenerateFaceError` naming a face of zero area (its normal is undefined).
    """
    return _dihedral_angles_and_edges(V, F)[0]


def _dihedral_angles_and_edges(V, F):
    """`(θ, edges, V / s, s)` (`lengths.normalised`)."""
    checked = _validate(V, F)
    h, h1, h2 = _interior_pairs(F if checked is None else checked, jnp.shape(V)[0])
    inner = h2 >= 0
    f1, f2 = h.face[h1], h.face[np.where(inner, h2, h1)]
    N, s = _normalised_area_vectors(V, F)
    V = namespace(V).asarray(V) * (1.0 / s)
    _check_areas(V, F, N)
    theta = _signed_dihedral(N, V, h.vertex[h1], h.head[h1], f1, f2)
    return namespace(V, theta).where(inner, theta, 0.0), h.edges, V, s


@jax.jit
def _signed_dihedral(N, V, tail, head, f1, f2):
    N = N / jnp.linalg.norm(N, axis=-1, keepdims=True)
    d = V[head] - V[tail]
    d = d / jnp.linalg.norm(d, axis=-1, keepdims=True)
    N1, N2 = N[f1], N[f2]
    return jnp.arctan2(jnp.sum(d * jnp.cross(N1, N2), axis=-1), jnp.sum(N1 * N2, axis=-1))


def edge_mean_curvature(V, F):
    """H(e) = ½ θ(e) l(e) per edge, ordered like `edges(F)` (Def 5.3); θ as in `dihedral_angles`
    (positive at convex edges of an outward-oriented surface, 0 on the boundary).  Scales by s
    (a mean curvature 1/s integrated over an area s²; module docstring).

    **Raises:** as `dihedral_angles`; `InvalidInputError` where H(e) is not a float64.
    """
    H, s = _normalised_edge_mean_curvature(V, F)
    return scaled_back(H, s, 1, "an edge mean curvature")


def _normalised_edge_mean_curvature(V, F):
    """`(H, s)`: the edge mean curvatures of V / s."""
    theta, E, V, s = _dihedral_angles_and_edges(V, F)
    return _half_angle_times_length(theta, V, E), s


@jax.jit
def _half_angle_times_length(theta, V, E):
    return 0.5 * theta * jnp.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=-1)


def total_mean_curvature(V, F):
    """H(S) = Σ_e H(e) = ½ Σ_e θ(e) l(e) (Def 5.3); scales by s.  **Raises:** as
    `edge_mean_curvature`."""
    H, s = _normalised_edge_mean_curvature(V, F)
    return scaled_back(jnp.sum(H), s, 1, "the total mean curvature")


def steiner_area(V, F, rho):
    """A(S_ρ) = A(S) + 2 H(S) ρ + K(S) ρ², K(S) = Σ_p K(p) = 2πχ (Thm 5.7 for convex polyhedra,
    where K(S) = 4π; Remark 5.5 for closed polyhedral surfaces with signed pieces).  Evaluated
    on V / s and ρ / s and scaled back by s².  **Raises:** as `edge_mean_curvature`.
    """
    K = jnp.sum(angle_defect(V, F))
    H, s = _normalised_edge_mean_curvature(V, F)
    A = jnp.sum(jnp.linalg.norm(_normalised_area_vectors(V, F)[0], axis=-1))
    r = rho * (1.0 / s)
    return scaled_back(A + 2 * jnp.sum(H) * r + K * r**2, s, 2, "the area of the parallel surface")
