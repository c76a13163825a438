"""The edge-flip algorithm (Fig 7.13) as a sequential loop, compiled by numba.

Fig 7.13 flips one non-Delaunay edge after another; done literally, each flip is a few dozen
scalar operations on the flat halfedge arrays of `delaunay` (layout: `triangulation`).  A
compiled loop is fine here: the flip sequence is inherently sequential, and these functions are
plain float and integer arithmetic that nothing differentiates or traces.  numba compiles them
on first use and caches the machine code on disk (`cache=True`); this module is imported only
by `delaunay.flip_owned`, so `import ddgjax` does not load numba.

The formulas are those of the rest of `intrinsic`: the test key of a halfedge is cot + tol · s
of the angle opposite it (Prop 7.9 with the tie tolerance of `delaunay`), the cotangents of new
triangles are derived from the triangle's Dirichlet energy (`ddgjax.mesh.lengths.dirichlet_form`,
by polarisation: `polarised_cotangents`, compiled here with a compiled form), their areas Kahan's Heron
(`ddgjax.mesh.lengths.triangle_area`), the new diagonal is read off the unfolded quadrilateral
(`geometry.apex`, Lemma 5.8), and a flip writes the slots that `flips.flip_batch` writes.
numba's cache is keyed on this file alone: after editing `dirichlet_form`, `polarised_cotangents` or `apex`, touch
this file so that the loop is compiled again.

The keys of the start come from the same formulas (`start_keys`); the cotangents that the
Laplacian is built from are not these but the derived ones of the result (`delaunay.flip_owned`).
The helpers are inlined into the loop (`inline="always"`): a call that passes arrays costs numba
more than the arithmetic of a flip.  So does an array variable that is reassigned inside the
loop (reference counting at every iteration): the history of a recorded run goes into a buffer
of fixed size, and when it is full the loop returns and is resumed from its state (`sweep`)
with a larger one.
"""

from __future__ import annotations

import numba
import numpy as np

from ..mesh.lengths import dirichlet_form as _dirichlet_form_of
from ..mesh.lengths import polarised_cotangents
from .geometry import apex as _apex_of

__all__ = ["flip_algorithm", "interleaved", "squared_sides", "start_keys"]

inline = numba.njit(cache=True, inline="always")
corner_cotangents = inline(polarised_cotangents(inline(_dirichlet_form_of)))
apex = inline(_apex_of)


@inline
def triangle_area(a, b, c):
    """Heron's formula in Kahan's order, sides sorted x ≥ y ≥ z (`ddgjax.mesh.lengths.
    triangle_area` on scalars): A = ¼ √((x + (y + z)) (z − (x − y)) (z + (x − y)) (x + (y − z)))."""
    x = max(max(a, b), c)
    z = min(min(a, b), c)
    y = max(min(a, b), min(max(a, b), c))
    return 0.25 * np.sqrt((x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z)))


@inline
def quarter_harmonic_index(x, y, z, area):
    """s = (x² + y² + z²) / 4A = h(Δ)/4 = cot α + cot β + cot γ (Def 7.7, Lemma 7.17)."""
    return (x * x + y * y + z * z) / (4.0 * area)


@inline
def flipped_length(l_ab, l_bc, l_ca, l_ad, l_db, area_abc, area_bad):
    """The other diagonal cd of the quadrilateral a d b c unfolded along ab (Lemma 5.8, Fig 5.11):
    |c − d| with c = apex above and d = apex below the base ab (`geometry.flipped_length`)."""
    xc, yc = apex(l_ab, l_ca, l_bc, area_abc, 1.0)
    xd, yd = apex(l_ab, l_ad, l_db, area_bad, -1.0)
    return np.hypot(xc - xd, yc - yd)


@inline
def next_and_previous(h):
    """(next, previous) of halfedge h = 3 f + i in its triangle."""
    i = h - 3 * (h // 3)
    return (h - 2 if i == 2 else h + 1), (h + 2 if i == 0 else h - 1)


@inline
def fails_angle_test(key, halfedges, e):
    """Prop 7.9 with the tie tolerance: cot α + tol s₁ + cot β + tol s₂ < 0 on the cached keys;
    a boundary edge passes (its second halfedge is -1, whose key, the last entry, is +inf)."""
    return key[halfedges[e, 0]] + key[halfedges[e, 1]] < 0.0


@inline
def new_face(key, area, face, slots, x, y, z, tol):
    """Store the area of the new face with sides x, y, z on the halfedges `slots` (in order) and
    the keys cot + tol · s of the angles opposite them (`corner_cotangents`, derived from the
    Dirichlet energy); returns s = h(Δ)/4."""
    A = triangle_area(x, y, z)
    area[face] = A
    s = quarter_harmonic_index(x, y, z, A)
    shift = tol * s
    cot_x, cot_y, cot_z = corner_cotangents(x * x, y * y, z * z, A)
    key[slots[0]] = cot_x + shift
    key[slots[1]] = cot_y + shift
    key[slots[2]] = cot_z + shift
    return s


@inline
def move(halfedges, e, old, new):
    """In the two halfedges of edge e, replace `old` by `new`."""
    if halfedges[e, 0] == old:
        halfedges[e, 0] = new
    else:
        halfedges[e, 1] = new


@inline
def flip_edge(F, edge, halfedges, lengths, key, area, tol, e, record):
    """Flip the interior edge e = ab (Lemma 5.8) in place, exactly as `flips.flip_batch`: the
    triangles (a, b, c) on the slots (h, h1, h2) and (b, a, d) on (t, t1, t2) become (a, d, c)
    and (b, c, d) on the same slots, e takes the length of cd and the new faces their areas and
    keys.  Returns the change of the harmonic index, 4 (s_new₁ + s_new₂ − s_old₁ − s_old₂)
    (Def 7.7, Lemma 7.17), when `record` (else 0)."""
    h, t = halfedges[e, 0], halfedges[e, 1]
    f, g = h // 3, t // 3
    h1, h2 = next_and_previous(h)
    t1, t2 = next_and_previous(t)
    e_bc, e_ca, e_ad, e_db = edge[h1], edge[h2], edge[t1], edge[t2]
    l_ab, l_bc, l_ca, l_ad, l_db = lengths[e], lengths[e_bc], lengths[e_ca], lengths[e_ad], lengths[e_db]
    A1, A2 = area[f], area[g]
    new = flipped_length(l_ab, l_bc, l_ca, l_ad, l_db, A1, A2)
    F[h1], F[t1] = F[t2], F[h2]
    move(halfedges, e_bc, h1, t)
    move(halfedges, e_ad, t1, h)
    halfedges[e, 0], halfedges[e, 1] = h1, t1
    edge[h], edge[h1], edge[t], edge[t1] = e_ad, e, e_bc, e
    lengths[e] = new
    s_f = new_face(key, area, f, (h, h1, h2), l_ad, new, l_ca, tol)
    s_g = new_face(key, area, g, (t, t1, t2), l_bc, new, l_db, tol)
    if not record:
        return 0.0
    before = quarter_harmonic_index(l_ab, l_bc, l_ca, A1) + quarter_harmonic_index(l_ab, l_ad, l_db, A2)
    return 4.0 * (s_f + s_g - before)


@inline
def push(stack, depth, queued, top, e, d):
    """Put e (at cascade depth d) on the stack unless it is there already; returns the new top."""
    if queued[e]:
        return top
    queued[e] = True
    stack[top], depth[top] = e, d
    return top + 1


@numba.njit(cache=True)
def start_keys(edge, lengths, tol):
    """(key, area, h): the keys cot + tol · s of the angles opposite all halfedges (3 nf,) and
    one more entry, +inf, read by the boundary's halfedge -1 (so that boundary edges always
    pass); the areas of the faces (nf,); h(T) = 4 Σ s (Def 7.7, Lemma 7.17; summed in blocks)."""
    nf = edge.size // 3
    key = np.empty(3 * nf + 1)
    key[3 * nf] = np.inf
    area = np.empty(nf)
    total = 0.0
    for first in range(0, nf, 1024):
        block = 0.0
        for f in range(first, min(first + 1024, nf)):
            h = 3 * f
            block += new_face(key, area, f, (h, h + 1, h + 2),
                              lengths[edge[h]], lengths[edge[h + 1]], lengths[edge[h + 2]], tol)
        total += block
    return key, area, 4.0 * total


DONE, FULL = -1, -2


@numba.njit(cache=True)
def sweep(F, edge, halfedges, lengths, key, area, tol, budget, record, steps, stack, depth, queued, state):
    """Fig 7.13 on the flat arrays, in place, from `state` = (the next edge of the sweep, the
    height of the stack, flips so far, rounds so far) on, which it updates: sweep over the edges
    in index order; an edge that fails the angle test starts a stack of edges to test, and an
    edge taken from the stack is flipped if it still fails and its two triangles are distinct
    (an edge lying twice on one triangle is Delaunay, Lemma 7.11), and those of the four outer
    edges of its quadrilateral that now fail go on the stack (at the depth of the flip + 1).
    A flip changes the quadrilaterals of these four edges only, so every non-Delaunay edge is on
    the stack or not yet swept; when the sweep ends the triangulation is Delaunay (termination:
    Thm 7.12).  With `record`, the change of the harmonic index at flip k goes to `steps[k]`.

    **Returns:** DONE; FULL when a flip is due and `steps` is full (the edge is back on the
    stack); or the edge, still non-Delaunay, that would be flip number `budget` + 1.
    """
    ne = halfedges.shape[0]
    start, top, n_flips, n_rounds = state[0], state[1], state[2], state[3]
    status = DONE
    while True:
        if top == 0:
            while start < ne and not fails_angle_test(key, halfedges, start):
                start += 1
            if start == ne:
                break
            top = push(stack, depth, queued, top, start, 1)
            start += 1
        top -= 1
        e, d = stack[top], depth[top]
        queued[e] = False
        h, t = halfedges[e, 0], halfedges[e, 1]
        if not fails_angle_test(key, halfedges, e) or h // 3 == t // 3:
            continue
        if n_flips == budget or (record and n_flips == steps.size):
            status = e if n_flips == budget else FULL
            top = push(stack, depth, queued, top, e, d)
            break
        step = flip_edge(F, edge, halfedges, lengths, key, area, tol, e, record)
        if record:
            steps[n_flips] = step
        n_flips += 1
        n_rounds = max(n_rounds, d)
        h2 = next_and_previous(h)[1]
        t2 = next_and_previous(t)[1]
        for side in (edge[t], edge[h2], edge[h], edge[t2]):  # bc, ca, ad, db after the flip
            if fails_angle_test(key, halfedges, side):
                top = push(stack, depth, queued, top, side, d + 1)
    state[0], state[1], state[2], state[3] = start, top, n_flips, n_rounds
    return status


@numba.njit(cache=True)
def grown(steps):
    """A copy of `steps` with twice the room."""
    out = np.empty(2 * steps.size)
    for i in range(steps.size):  # (a loop: numba compiles slice assignment slowly)
        out[i] = steps[i]
    return out


@numba.njit(cache=True)
def flip_algorithm(F, edge, halfedges, lengths, tol, budget, record):
    """Fig 7.13 on the flat arrays, in place (`sweep`), from the keys of `start_keys`.

    **Returns:** (n_flips, n_rounds, steps, stuck, h, key): `n_rounds` the longest cascade (a
    flip of an edge found by the sweep has depth 1, a flip of an edge that a flip of depth d
    made non-Delaunay has depth d + 1), `steps` the change of the harmonic index at each flip
    when `record` (else empty), `stuck` -1, or a non-Delaunay edge when more than `budget`
    flips would be needed, `h` the harmonic index of the start, `key` the keys at the end
    (3 nf + 1,) (a buffer for `interleaved`).
    """
    key, area, h = start_keys(edge, lengths, tol)
    ne = halfedges.shape[0]
    stack = np.empty(ne, dtype=np.int64)
    depth = np.empty(ne, dtype=np.int64)
    queued = np.zeros(ne, dtype=np.bool_)
    state = np.zeros(4, dtype=np.int64)
    steps = np.empty(1024 if record else 0)
    status = sweep(F, edge, halfedges, lengths, key, area, tol, budget, record, steps, stack, depth, queued, state)
    while status == FULL:
        steps = grown(steps)
        status = sweep(F, edge, halfedges, lengths, key, area, tol, budget, record, steps, stack, depth, queued, state)
    n_flips = state[2]
    return n_flips, state[3], steps[:n_flips], status, h, key


@numba.njit(cache=True)
def squared_sides(edge, lengths, width):
    """(3, width): the squared length of side i of face f at [i, f], ones in the columns
    f ≥ nf (the input of `ddgjax.mesh.lengths.side_cotangent_columns`, padded)."""
    nf = edge.size // 3
    s2 = np.empty((3, max(width, nf)))
    for f in range(nf):
        for i in range(3):
            l = lengths[edge[3 * f + i]]
            s2[i, f] = l * l
    s2[:, nf:] = 1.0
    return s2


@numba.njit(cache=True)
def interleaved(a, b, c, out):
    """out[:3 n] = a[0], b[0], c[0], a[1], … (three (n,) arrays, one per side, in halfedge
    order); returns that part of `out`."""
    n = a.size
    for f in range(n):
        out[3 * f], out[3 * f + 1], out[3 * f + 2] = a[f], b[f], c[f]
    return out[:3 * n]
