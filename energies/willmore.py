"""Willmore and Helfrich energies of closed simplicial surfaces (Sec 6.4, Thm 6.7; Bobenko 2005).

**Helfrich** (`helfrich`).  W(S) = κ Σ_i (H_i − H₀)² A_i over the vertices, with the discrete mean
curvature *derived from the area*: by Thm 6.7 the area gradient at a vertex is the
mean-curvature normal times the vertex area, ∇_i A = (L f)(i) ≈ 2 H N A_i, so

    H_i = ⟨∇_i A, N_i⟩ / (2 A_i),   N_i = ∇_i Vol / |∇_i Vol|,   A_i = ⅓ Σ_{f ∋ i} A(f),

N_i the unit (area-weighted) normal, from the gradient of the enclosed volume
Vol = Σ_f det(v0, v1, v2)/6, and A_i the barycentric vertex area.  ∇_i A and ∇_i Vol are taken
by `jax.grad` of the area and volume of the star of i inside the density (no cotan formula), so
H_i is exactly the cotan mean curvature ⟨(L f)(i), N_i⟩ / 2A_i.  Convention H = (κ₁ + κ₂)/2 with
the outward normal of a positively oriented closed surface (Vol > 0): a round sphere of radius r
has H = 1/r and W = 4π for κ = 1, H₀ = 0 (Willmore's theorem: W ≥ 4π, equality for round spheres).
W with H₀ = 0 is scale invariant; H₀ ≠ 0 depends on the orientation (H changes sign with it).

Measured on icospheres (levels 1–5): W − 4π = −0.862, −0.222, −0.0559, −0.0140, −0.0035, order 2
in the edge length and from below (the discrete W of an icosphere is < 4π: the discrete Willmore
inequality fails for this energy).  H converges in the mean (∫|H − 1| dA at order ~2) but not
pointwise: at the 12 valence-5 vertices |H − 1| → 0.146 (barycentric areas on an irregular mesh).
icosphere(1) is a critical point under its own area and volume (λ_A = 8.194, λ_V = −17.417,
2Aλ_A + 3Vol λ_V = 0 by scale invariance); the icospheres are not critical for W alone.

The energy is declared with `dg.local_sum` over the vertex stars: the stencil of vertex i is i and
its link vertices, padded to the largest valence with copies of i (the padded faces are masked
out), so the sparse solvers apply (the Hessian couples vertices at combinatorial distance ≤ 2).
Constraints (optional, named): `"area"`: A(S) − area, `"volume"`: Vol(S) − volume, each a
`dg.local_sum` over the faces; their multipliers are the surface tension and the pressure
(∇W = λ_A ∇A + λ_V ∇Vol at a critical point).

**Conformal** (`conformal`).  Bobenko's discrete Willmore energy ("A conformal energy for
simplicial surfaces", 2005): W(S) = Σ_e β_e − π |V| on a closed surface, β_e ∈ [0, π] the
exterior intersection angle of the circumcircles of the two triangles at the edge e.  It is
invariant under Möbius transformations of R³, W = Σ_v W(v)/2 with W(v) = Σ_{e ∋ v} β_e − 2π ≥ 0,
and W(v) = 0 iff the star of v is convex and inscribed in a sphere.

β_e from the four vertices: for the edge (i, j) between the triangles (i, j, k) and (j, i, l),
invert in the unit sphere about x_i, p ↦ (p − x_i)/|p − x_i|²: both circles pass through x_i, so
they become the lines (j'k') and (j'l'), and the angle between circles is the angle between the
lines (inversion is conformal).  The exterior angle is the turning angle of the polyline
k' → j' → l' (zero when the four points are concyclic with k and l on opposite arcs of the chord ij):

    β_e = ∠(j' − k', l' − j'),   p' = (p − x_i)/|p − x_i|²,

evaluated with the vectors scaled by |x_j − x_i|² (a = x_j − x_i, b = x_k − x_i, c = x_l − x_i:
u = a − b |a|²/|b|², w = c |a|²/|c|² − a, β = atan2(|u × w|, u·w)), so all terms are of the size
of the edge.  Declared with `dg.local_sum` over the edges (stencil (i, j, k, l)); the constant
−π|V| is spread over the edges as per-edge data.  The energy has the Möbius group as a
10-dimensional family of zero modes, so `solve` on it is singular; it is a functional to
evaluate, differentiate and use in flows.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

import ddgjax as dg
from ddgjax._checks import check_finite, check_positive, checked_count
from ddgjax.errors import InvalidInputError, MeshError
from ddgjax.laplace import check_nondegenerate, checked_triangle_mesh
from ddgjax.mesh import boundary_vertices
from ddgjax.mesh.connectivity import glue_triangles
from ddgjax.quaternion import cross

from .area import face_area, face_volume

__all__ = ["circle_angle", "circle_angles", "conformal", "edge_stencil", "helfrich", "mean_curvature", "revolve",
           "revolve_vesicle", "revolved_points", "revolved_stars", "star_stencil", "torus_of_revolution", "vertex_density",
           "vesicle_of_revolution"]


# ---------------------------------------------------------------------------------------------
# meshes: closed, oriented; stencils


def _closed(V, F) -> tuple[np.ndarray, np.ndarray]:
    V, F = checked_triangle_mesh(V, F, manifold=True)
    check_nondegenerate(V, F)
    b = boundary_vertices(F, V.shape[0])
    if b.size:
        raise InvalidInputError(f"the Willmore energies need a closed surface; vertex {int(b[0])} lies on a boundary edge")
    unused = np.flatnonzero(np.bincount(F.ravel(), minlength=len(V)) == 0)
    if unused.size:
        raise MeshError(f"vertex {int(unused[0])} is in no face: remove unreferenced vertices")
    return V, F


def _halfedges(F: np.ndarray):
    """Tails, heads and opposite corners of the 3·nf halfedges h = 3f + i, and the twin of each
    (`dg.mesh.connectivity.glue_triangles`; a closed surface has no −1).

    **Raises:** `OrientationError` naming an edge that two faces traverse alike."""
    halfedges, _ = glue_triangles(F, int(F.max()) + 1)
    return halfedges.vertex, halfedges.head, halfedges.vertex[halfedges.prev], halfedges.twin


def edge_stencil(F) -> np.ndarray:
    """(ne, 4) rows (i, j, k, l): the edge (i, j) between the triangles (i, j, k) and (j, i, l) of
    the closed, consistently oriented surface F, each edge once.

    **Raises:** `OrientationError` naming an edge traversed twice in the same direction."""
    tail, head, opp, twin = _halfedges(np.asarray(F, dtype=np.int64))
    h = np.flatnonzero(tail < head)
    return np.stack([tail[h], head[h], opp[h], opp[twin[h]]], axis=1)


def star_stencil(F, nv: int) -> tuple[np.ndarray, dict]:
    """The vertex stars as a `dg.local_sum` stencil: `(stencil, data)`, stencil (nv, 1 + m) =
    (i, link vertices of i, padded with i), m the largest valence; data `{"faces": (nv, m, 2)`
    local indices (a, b) of the star's triangles (i, a, b) in the orientation of F, `"mask": (nv, m)`
    1 for a triangle, 0 for padding (a copy of the first triangle)}."""
    tail, head, opp, _ = _halfedges(np.asarray(F, dtype=np.int64))  # corner (tail, head, opp) seen from tail
    order = np.argsort(tail, kind="stable")
    tail, head, opp = tail[order], head[order], opp[order]  # grouped by centre vertex
    valence = np.bincount(tail, minlength=nv)
    m = int(valence.max())
    slot = np.arange(tail.size) - np.concatenate([[0], np.cumsum(valence)[:-1]])[tail]  # rank in its star
    stencil = np.repeat(np.arange(nv)[:, None], 1 + m, axis=1)
    stencil[tail, 1 + slot] = head  # on a closed surface the heads of a star are its link, each once
    key = tail * nv + head  # the opposite corner opp is the head of another corner of the same star
    by_key = np.argsort(key)
    faces = np.zeros((nv, m, 2), dtype=np.int64)
    faces[tail, slot, 0] = 1 + slot
    faces[tail, slot, 1] = 1 + slot[by_key[np.searchsorted(key[by_key], tail * nv + opp)]]
    mask = np.zeros((nv, m))
    mask[tail, slot] = 1.0
    pad = mask == 0
    faces[pad] = np.repeat(faces[:, :1], m, axis=1)[pad]
    return stencil, {"faces": faces, "mask": mask}


# ---------------------------------------------------------------------------------------------
# Helfrich: the mean curvature derived from the area and the volume


def _star_measures(X, star):
    """(∇_i A, ∇_i Vol, A_i) of the star of vertex i = X[0]: gradients by `jax.grad` of the star's
    area and volume with respect to the centre, in coordinates centred at x_i (the star is closed,
    so both gradients are translation invariant)."""
    R = X - X[0]
    a, b = R[star["faces"][:, 0]], R[star["faces"][:, 1]]

    def measures(q):
        P = jnp.stack([jnp.broadcast_to(q, a.shape), a, b], axis=1)
        area = jnp.sum(star["mask"] * jax.vmap(face_area)(P))
        volume = jnp.sum(star["mask"] * jax.vmap(face_volume)(P))
        return area, volume

    zero = jnp.zeros(3, dtype=X.dtype)
    (grad_area, grad_volume) = jax.jacrev(measures)(zero)
    return grad_area, grad_volume, measures(zero)[0] / 3.0


def _mean_curvature_of_star(X, star):
    grad_area, grad_volume, vertex_area = _star_measures(X, star)
    normal = grad_volume / jnp.linalg.norm(grad_volume)
    return jnp.dot(grad_area, normal) / (2.0 * vertex_area), vertex_area


def vertex_density(X: Float[Array, "s 3"], star: dict, params: dict) -> Float[Array, ""]:
    """κ (H_i − H₀)² A_i of the star of i = X[0] (`star_stencil`)."""
    H, vertex_area = _mean_curvature_of_star(X, star)
    return params["kappa"] * (H - params["H0"]) ** 2 * vertex_area


def mean_curvature(V, F) -> tuple[np.ndarray, np.ndarray]:
    """`(H, A)`: the discrete mean curvature H_i = ⟨∇_i A, N_i⟩ / 2A_i and the barycentric vertex
    area A_i of the closed surface (V, F), (nv,) each (module docstring).

    **Raises:** as `helfrich`."""
    V, F = _closed(V, F)
    stencil, data = star_stencil(F, len(V))
    H, A = _mean_curvatures(np.asarray(V)[stencil], data)  # host arrays: gathered in NumPy, nothing compiled
    return np.asarray(H), np.asarray(A)


_mean_curvatures = jax.jit(jax.vmap(_mean_curvature_of_star))


def _area_constraint(P, share, params):
    return jnp.reshape(face_area(P) - share * params["area"], (1,))


def _volume_constraint(P, share, params):
    return jnp.reshape(face_volume(P) - share * params["volume"], (1,))


def helfrich(V, F, *, kappa: float = 1.0, H0: float = 0.0, area: float | None = None,
             volume: float | None = None) -> dg.Problem:
    """The Helfrich energy W = κ Σ_i (H_i − H₀)² A_i of the closed surface (V, F) as a functional
    of the vertex positions (nv, 3) (module docstring; κ = 1, H₀ = 0: the Willmore energy ∫H² dA,
    4π on round spheres).  `params = {"kappa", "H0"[, "area"][, "volume"]}`.

    **Constraints** (named, only those given): `"area"`: A(S) − area, `"volume"`: Vol(S) − volume
    (shape (1,) each); the multipliers are `{"area": (1,), "volume": (1,)}`.

    **Raises:** `NonFiniteError`, `MeshError` / `NonManifoldError` (as `area.simplicial`),
    `DegenerateFaceError` (a zero-area face), `InvalidInputError` (a boundary: the surface must be
    closed; `kappa` or `area` not finite and positive), `OrientationError` (faces not
    consistently oriented).
    """
    V, F = _closed(V, F)
    check_positive(kappa, "kappa, the bending rigidity,")
    check_finite(H0, "H0")
    if area is not None:
        check_positive(area, "area, the prescribed surface area,")
    if volume is not None:
        check_finite(volume, "volume")
    stencil, data = star_stencil(F, len(V))
    params = {"kappa": float(kappa), "H0": float(H0)}
    named = {}
    share = np.full(len(F), 1.0 / len(F))
    if area is not None:
        params["area"] = float(area)
        named["area"] = dg.local_sum(_area_constraint, F, share)
    if volume is not None:
        params["volume"] = float(volume)
        named["volume"] = dg.local_sum(_volume_constraint, F, share)
    constraints = dg.locality.concat(**named) if named else None
    return dg.Problem(dg.local_sum(vertex_density, stencil, data), V, constraints=constraints, params=params,
                      name=f"Helfrich energy (nv={len(V)}, nf={len(F)})")


# ---------------------------------------------------------------------------------------------
# tori of revolution: the Willmore problem on a profile polygon


def revolved_points(P: Float[Array, "n 2"], profile_of, angle_of) -> Float[Array, "k 3"]:
    """Points of a surface of revolution about the z-axis: point v is the profile point
    P[profile_of[v]] = (ρ, z) turned by the angle angle_of[v], (ρ cos a, ρ sin a, z)."""
    rho, z = P[profile_of, 0], P[profile_of, 1]
    return jnp.stack([rho * jnp.cos(angle_of), rho * jnp.sin(angle_of), z], axis=-1)


def _torus_of_revolution(m: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """`(profile_of, angle_of)` of the vertices of `dg.mesh.torus(m, n)`: vertex i n + j is the
    profile point j on the meridian u_i = 2πi/m."""
    vertex = np.arange(m * n)
    return vertex % n, 2 * np.pi * (vertex // n) / m


def revolve(P: Float[Array, "n 2"], m: int) -> Float[Array, "mn 3"]:
    """The vertices of the torus of revolution of the closed profile polygon P = (ρ_j, z_j)
    (n, 2) about the z-axis, m meridians: v_{i,j} = (ρ_j cos u_i, ρ_j sin u_i, z_j),
    u_i = 2πi/m, as an (m n, 3) array ordered like `dg.mesh.torus(m, n)` (vertex i n + j)."""
    return revolved_points(P, *_torus_of_revolution(m, jnp.shape(P)[0]))


def _revolved(Q, star):
    """The star's vertices in R³ (`revolved_points` of its stencil's profile points)."""
    return revolved_points(Q, star["which"], star["angle"])


def _revolved_star(Q: Float[Array, "3 2"], star: dict, params: dict) -> Float[Array, ""]:
    """`weight` times the Helfrich density (`vertex_density`) of one vertex star of a surface of
    revolution, from the profile points Q of its stencil: by the rotational symmetry the stars
    of one meridian, each counted m times (once at a pole), sum to W of the whole surface."""
    return star["weight"] * vertex_density(_revolved(Q, star), star, params)


def revolved_stars(F, profile_of: np.ndarray, angle_of: np.ndarray, rows: np.ndarray, cells: np.ndarray,
                   weights: np.ndarray) -> dict:
    """The `dg.local_sum` data of `_revolved_star` for the surface (V, F) of revolution whose
    vertex v is the profile point `profile_of[v]` turned by `angle_of[v]`: the stars of the
    vertices `rows` (one per profile point), each with the stencil of profile points `cells[k]`
    (3 of them, repeats allowed) and the weight `weights[k]`."""
    stencil, star = star_stencil(F, len(profile_of))
    star = {key: value[rows] for key, value in star.items()}
    on = profile_of[stencil[rows]]  # (rows, s): the profile point of each star vertex
    star["which"] = np.argmax(on[:, :, None] == cells[:, None, :], axis=2)
    assert np.all(np.take_along_axis(cells, star["which"], axis=1) == on), "a star vertex off its stencil"
    star["angle"] = angle_of[stencil[rows]]
    star["weight"] = np.asarray(weights, dtype=float)
    return star


def _edge_difference(Q: Float[Array, "4 2"], params) -> Float[Array, ""]:
    """|p_{j+1} − p_j| − |p_1 − p_0| from Q = (p_j, p_{j+1}, p_0, p_1)."""
    return jnp.linalg.norm(Q[1] - Q[0]) - jnp.linalg.norm(Q[3] - Q[2])


def _height_above_p0(Q: Float[Array, "2 2"], share, params) -> Float[Array, "1"]:
    """(z_j − z_0)/n from Q = (p_j, p_0): summed over j, the mean height of the profile minus z_0."""
    return jnp.reshape(share * (Q[0, 1] - Q[1, 1]), (1,))


def torus_of_revolution(m: int, n: int, *, ratio: float = 2.5, kappa: float = 1.0) -> dg.Problem:
    """The Willmore energy (`helfrich` with H₀ = 0) of tori of revolution, as a functional of the
    profile polygon P (n, 2) of points (ρ_j, z_j) in the half-plane ρ > 0, revolved into m
    meridians (`revolve`) and triangulated like `dg.mesh.torus(m, n)`.

    The smooth problem: among tori, W ≥ 2π² with equality exactly for the Clifford torus and its
    Möbius images (Marques–Neves 2014), which among tori of revolution is the torus of a circle
    of radius r about ρ = R with R/r = √2 (Willmore 1965; Langer–Singer 1984).  Discretely:

    - constraint `"equal_edges"` (n − 1,): the profile is equilateral, |p_{j+1} − p_j| =
      |p_1 − p_0|.  Without it the vertices slide along the profile and crowd where the discrete
      energy, which is not the smooth one on a coarse mesh, is lowest (measured: a minimiser of
      W alone at 24 × 12 has W/2π² = 0.78, its profile 28 % away from a circle);
    - p_0 is fixed: W is invariant under scaling and under translation along the axis, which
      would leave the critical point undetermined (both move p_0);
    - constraint `"phase"` (1,): the mean height of the profile is z_0.  Turning the vertices of
      an equilateral profile along it (a reparametrisation, a symmetry of the smooth problem)
      changes the discrete W only by an amount that falls exponentially in n; with p_0 fixed it
      is the rotation of the profile about p_0, which moves its mean height.  Without this
      constraint that direction is a near-zero mode of either sign (measured: the reduced
      Hessian's lowest eigenvalue −3.7e-3 at 24 × 12, −1e-4 at 32 × 16).

    Start `x0`: the circle of radius 1 about ρ = `ratio` (R/r = 2.5 by default), equilateral.
    `params = {"kappa", "H0"}` as for `helfrich`.  The critical point from the default start is a
    minimum (`solvers.stability` index 0), with R/r → √2 and W → 2π² at order 2 in 1/n
    (`ddgjax verify --only clifford`).

    **Raises:** `InvalidInputError` (m, n < 3; `ratio` ≤ 1: the start would meet the axis;
    `kappa` not finite and positive).
    """
    m = checked_count(m, 3, "m, the number of meridians,")
    n = checked_count(n, 3, "n, the number of profile points,")
    check_positive(kappa, "kappa, the bending rigidity,")
    if not (np.isfinite(ratio) and ratio > 1):
        raise InvalidInputError(f"ratio = R/r of the starting torus must be > 1 (the profile circle must not meet the axis), got {ratio}")
    V0, F = dg.mesh.torus(m, n, R=float(ratio), r=1.0)
    _closed(V0, F)
    j = np.arange(n)
    cells = np.stack([(j - 1) % n, j, (j + 1) % n], axis=1)
    star = revolved_stars(F, *_torus_of_revolution(m, n), j, cells, np.full(n, float(m)))
    energy = dg.local_sum(_revolved_star, cells, star)
    rest = j[1:]
    constraints = dg.concat(
        equal_edges=dg.local_map(_edge_difference, np.stack([rest, (rest + 1) % n, 0 * rest, 0 * rest + 1], axis=1)),
        phase=dg.local_sum(_height_above_p0, np.stack([j, 0 * j], axis=1), data=np.full(n, 1.0 / n)),
    )
    v = 2 * np.pi * j / n
    P0 = np.stack([ratio + np.cos(v), np.sin(v)], axis=1)
    fixed = np.zeros((n, 2), bool)
    fixed[0] = True
    return dg.Problem(energy, P0, constraints=constraints, params={"kappa": float(kappa), "H0": 0.0}, fixed=fixed,
                      name=f"Willmore energy of tori of revolution (m={m}, n={n})")


def _sphere_of_revolution(m: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(F, profile_of, angle_of)` of the sphere of revolution of a profile p_0 … p_n from the
    north pole p_0 to the south pole p_n (both on the axis), m meridians: vertex 0 the north
    pole, 1 + i (n − 1) + j − 1 the point p_j (0 < j < n) on meridian i, 1 + m (n − 1) the south
    pole; fans at the poles, each quad of the rings split in two, outward for a profile running
    from the north pole down the half-plane ρ > 0."""
    i, j = np.meshgrid(np.arange(m), np.arange(1, n - 1), indexing="ij")
    ring = lambda i, j: 1 + (i % m) * (n - 1) + j - 1  # noqa: E731
    south = 1 + m * (n - 1)
    k = np.arange(m)
    a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
    F = np.concatenate([
        np.stack([np.zeros(m, int), ring(k, 1), ring(k + 1, 1)], axis=1),
        np.stack([a, b, c], axis=-1).reshape(-1, 3), np.stack([a, c, d], axis=-1).reshape(-1, 3),
        np.stack([np.full(m, south), ring(k + 1, n - 1), ring(k, n - 1)], axis=1),
    ])
    profile_of = np.concatenate([[0], np.tile(np.arange(1, n), m), [n]])
    angle_of = np.concatenate([[0.0], np.repeat(2 * np.pi * np.arange(m) / m, n - 1), [0.0]])
    return F, profile_of, angle_of


def _star_area_and_volume(Q: Float[Array, "3 2"], star: dict, params: dict) -> Float[Array, "2"]:
    """`weight` × (A_i, Vol_i) − share × (area, volume): A_i = ⅓ Σ_{f ∋ i} A(f) and
    Vol_i = ⅓ Σ_{f ∋ i} det(f)/6 of the star, so that the weighted sum over one meridian's stars
    is (A(S) − area, Vol(S) − volume) of the whole surface of revolution."""
    X = _revolved(Q, star)
    T = X[jnp.concatenate([jnp.zeros_like(star["faces"][:, :1]), star["faces"]], axis=1)]
    measures = jnp.stack([jnp.sum(star["mask"] * jax.vmap(face_area)(T)), jnp.sum(star["mask"] * jax.vmap(face_volume)(T))])
    return star["weight"] * measures / 3.0 - star["share"] * jnp.stack([params["area"], params["volume"]])


def vesicle_of_revolution(m: int, n: int, *, reduced_volume: float = 0.6, aspect: float = 0.6,
                          kappa: float = 1.0) -> dg.Problem:
    """A closed vesicle of revolution under area and volume constraints (the Helfrich model of a
    lipid membrane with H₀ = 0, Canham 1970, Helfrich 1973): W = κ∫H² dA of the profile polygon
    P (n + 1, 2) of points (ρ_j, z_j) from the north pole p_0 to the south pole p_n, revolved into
    m meridians (the stars of one meridian counted m times, the poles' once; `revolved_stars`).

    - constraint `"measures"` (2,): the area A and the volume Vol of the surface are those of
      the start (an oblate spheroid of semi-axes 1, 1, `aspect`) and `reduced_volume` v times the
      volume of the round sphere of that area, v = Vol / (4π/3 (A/4π)^{3/2});
    - constraint `"equal_edges"` (n − 1,): the profile is equilateral (as for
      `torus_of_revolution`: without it the vertices slide);
    - p_0 fixed (translation along the axis), the south pole's ρ fixed at 0 (on the axis).

    At v ≈ 0.6 the minimiser is the biconcave discocyte, the shape of a red blood cell
    (Seifert, Berndl, Lipowsky 1991): thinner at the axis than at its rim.  Params `{"kappa",
    "H0", "area", "volume"}`; multipliers `{"equal_edges": (n − 1,), "measures": (2,)}` (the
    tension and the pressure).

    **Raises:** `InvalidInputError` (m < 3, n < 3, `reduced_volume` not in (0, 1), `aspect` not
    positive, `kappa` not finite and positive).
    """
    m = checked_count(m, 3, "m, the number of meridians,")
    n = checked_count(n, 3, "n, the number of profile edges,")
    check_positive(kappa, "kappa, the bending rigidity,")
    check_positive(aspect, "aspect, the starting spheroid's polar semi-axis,")
    if not (0 < reduced_volume < 1):
        raise InvalidInputError(f"reduced_volume must lie in (0, 1) (1 is the round sphere), got {reduced_volume}")
    F, profile_of, angle_of = _sphere_of_revolution(m, n)
    theta = np.pi * np.arange(n + 1) / n
    P0 = np.stack([np.sin(theta), aspect * np.cos(theta)], axis=1)
    P0[[0, n], 0] = 0.0
    V0 = np.asarray(revolved_points(P0, profile_of, angle_of))
    _closed(V0, F)
    rows = np.concatenate([[0], 1 + np.arange(n - 1), [len(V0) - 1]])  # the poles and meridian 0
    j = np.arange(1, n)
    cells = np.concatenate([[[0, 0, 1]], np.stack([j - 1, j, j + 1], axis=1), [[n - 1, n, n]]])
    weights = np.concatenate([[1.0], np.full(n - 1, float(m)), [1.0]])
    star = revolved_stars(F, profile_of, angle_of, rows, cells, weights)
    star["share"] = np.full(len(rows), 1.0 / len(rows))
    area0 = float(dg.mesh.surface_area(V0, F))
    volume = float(reduced_volume) * 4 * np.pi / 3 * (area0 / (4 * np.pi)) ** 1.5
    constraints = dg.concat(
        equal_edges=dg.local_map(_edge_difference, np.stack([j, j + 1, 0 * j, 0 * j + 1], axis=1)),
        measures=dg.local_sum(_star_area_and_volume, cells, star),
    )
    fixed = np.zeros((n + 1, 2), bool)
    fixed[0] = True
    fixed[n, 0] = True
    return dg.Problem(dg.local_sum(_revolved_star, cells, star), P0, constraints=constraints,
                      params={"kappa": float(kappa), "H0": 0.0, "area": area0, "volume": volume}, fixed=fixed,
                      name=f"vesicle of revolution (m={m}, n={n}, v={reduced_volume})")


def revolve_vesicle(P: Float[Array, "n1 2"], m: int) -> tuple[np.ndarray, np.ndarray]:
    """`(V, F)` of the vesicle of revolution of the profile P (n + 1, 2), m meridians (the mesh
    `vesicle_of_revolution` declares its energy on)."""
    P = np.asarray(P)
    F, profile_of, angle_of = _sphere_of_revolution(m, len(P) - 1)
    return np.asarray(revolved_points(P, profile_of, angle_of)), F


# ---------------------------------------------------------------------------------------------
# Bobenko's conformal energy


def _norm(v):
    """|v| with a finite gradient at v = 0 (β = 0 or π exactly)."""
    s = jnp.dot(v, v)
    safe = jnp.where(s > 0, s, 1.0)
    return jnp.where(s > 0, jnp.sqrt(safe), 0.0)


def circle_angle(X: Float[Array, "4 3"], params=None) -> Float[Array, ""]:
    """β_e ∈ [0, π]: the exterior intersection angle of the circumcircles of the triangles
    (x_i, x_j, x_k) and (x_j, x_i, x_l), X = (x_i, x_j, x_k, x_l), by inversion about x_i
    (module docstring)."""
    a, b, c = X[1] - X[0], X[2] - X[0], X[3] - X[0]
    aa = jnp.dot(a, a)
    u = a - b * (aa / jnp.dot(b, b))  # |a|² (j' − k')
    w = c * (aa / jnp.dot(c, c)) - a  # |a|² (l' − j')
    return jnp.arctan2(_norm(cross(u, w)), jnp.dot(u, w))


def _edge_density(X, offset, params):
    return circle_angle(X) - offset


def circle_angles(V, F) -> tuple[np.ndarray, np.ndarray]:
    """`(edges, β)`: the `edge_stencil` (ne, 4) of the closed surface (V, F) and the angles β_e (ne,)."""
    V, F = _closed(V, F)
    E = edge_stencil(F)
    return E, np.asarray(_circle_angles(np.asarray(V)[E]))


_circle_angles = jax.jit(jax.vmap(circle_angle))


def conformal(V, F) -> dg.Problem:
    """Bobenko's conformal (Möbius-invariant) Willmore energy W = Σ_e β_e − π|V| of the closed
    surface (V, F), a functional of the vertex positions (nv, 3); W ≥ 0, = 0 iff every vertex star
    is convex and inscribed in a sphere (module docstring).

    **Raises:** as `helfrich`."""
    V, F = _closed(V, F)
    E = edge_stencil(F)
    offset = np.full(len(E), np.pi * len(V) / len(E))
    return dg.Problem(dg.local_sum(_edge_density, E, offset), V, name=f"conformal Willmore energy (nv={len(V)}, nf={len(F)})")
