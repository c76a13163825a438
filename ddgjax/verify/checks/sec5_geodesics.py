"""Shortest paths on a polyhedral surface (Sec 5: Example 5.2, unfolding the cube)."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

import ddgjax as dg
from ddgjax import mesh
from ddgjax.verify import check

# Two points on adjacent faces of the unit cube (top z = 1 and front y = 0, sharing the edge y = 0, z = 1),
# both close to the face x = 0: the straight line across the shared edge (the development of Figure 5.8)
# is a geodesic, but the straight line in the development top → left → front is shorter.
X = np.array([0.07, 0.83, 1.0])
Y = np.array([0.11, 0.0, 0.21])


def _faces():
    """The six squares of `mesh.cube()` as (4, 3) arrays of corners, in cyclic order."""
    V, F = mesh.cube()
    return np.asarray(V, float), np.asarray(F)


def _face_of(V, F, p) -> list[int]:
    """Indices of the faces (planes x_i ∈ {0, 1}) that contain the point p of the cube's surface."""
    out = []
    for k, f in enumerate(F):
        n = np.cross(V[f[1]] - V[f[0]], V[f[3]] - V[f[0]])
        if abs(np.dot(n, p - V[f[0]])) < 1e-12:
            out.append(k)
    return out


def _develop(V, F, seq, x, y):
    """Unfold the faces `seq` (consecutive ones share an edge) into the plane of seq[0]: the images of
    x ∈ seq[0] and y ∈ seq[-1] and the images (A, B) of the shared edges, in order.  Each face is laid
    down by the isometry that fixes the image of its shared edge and puts the face on the side away
    from the previous one."""
    f0 = V[F[seq[0]]]
    e1 = (f0[1] - f0[0]) / np.linalg.norm(f0[1] - f0[0])
    n0 = np.cross(f0[1] - f0[0], f0[3] - f0[0])
    e2 = np.cross(n0 / np.linalg.norm(n0), e1)
    origin, frame, side = f0[0], np.array([e1, e2]), None  # 3-D → 2-D: q ↦ frame @ (q − origin) (first face)
    images = {v: frame @ (V[v] - origin) for v in F[seq[0]]}
    edges = []
    for prev, face in pairwise(seq):
        a, b = sorted(set(F[prev]) & set(F[face]))
        A, B = images[a], images[b]
        centre_prev = np.mean([images[v] for v in F[prev]], axis=0)
        E = (B - A) / np.linalg.norm(B - A)
        N = np.array([-E[1], E[0]])
        if np.dot(N, centre_prev - A) > 0:
            N = -N
        e = (V[b] - V[a]) / np.linalg.norm(V[b] - V[a])
        c = V[F[face]].mean(axis=0) - V[a]
        m = c - np.dot(c, e) * e
        m /= np.linalg.norm(m)

        def place(q, a=a, A=A, E=E, N=N, e=e, m=m):
            return A + np.dot(q - V[a], e) * E + np.dot(q - V[a], m) * N

        images = {v: place(V[v]) for v in F[face]}
        edges.append((A, B))
        side = place
    x2 = frame @ (x - origin)
    y2 = (frame @ (y - origin)) if side is None else side(y)
    return x2, y2, edges


def _crossings(x2, y2, edges):
    """Parameters t ∈ [0, 1] where the segment x2 → y2 crosses the shared edges, or None if it misses one
    (then the straight line leaves the strip of faces and is no path on the surface)."""
    ts = []
    d = y2 - x2
    for A, B in edges:
        M = np.column_stack([d, A - B])
        if abs(np.linalg.det(M)) < 1e-14:
            return None
        t, s = np.linalg.solve(M, A - x2)
        if not (-1e-12 <= t <= 1 + 1e-12 and -1e-12 <= s <= 1 + 1e-12):
            return None
        ts.append(t)
    return ts if all(np.diff(ts) >= -1e-12) else None


def _face_sequences(F, start, end, most):
    """All face paths start → … → end without repeated faces, at most `most` faces long."""
    adjacent = {i: [j for j in range(len(F)) if j != i and len(set(F[i]) & set(F[j])) == 2] for i in range(len(F))}
    out, stack = [], [[start]]
    while stack:
        seq = stack.pop()
        if seq[-1] == end:
            out.append(seq)
            continue
        if len(seq) < most:
            stack.extend(seq + [j] for j in adjacent[seq[-1]] if j not in seq)
    return out


def unfolded_lengths(x, y, most=6):
    """{face sequence: length of the straight line x → y in its development} over the sequences whose
    straight line stays in the strip of unfolded faces (each such line is a path on the surface)."""
    V, F = _faces()
    (i,), (j,) = _face_of(V, F, x), _face_of(V, F, y)
    lengths = {}
    for seq in _face_sequences(F, i, j, most):
        x2, y2, edges = _develop(V, F, seq, x, y)
        if _crossings(x2, y2, edges) is not None:
            lengths[tuple(seq)] = float(np.linalg.norm(y2 - x2))
    return lengths


def dijkstra_distance(x, y, n):
    """Graph distance from x to y: nodes are x, y and n + 1 equally spaced points on each edge of the
    cube, joined by a straight segment whenever two of them lie on a common (convex) face.  Every graph
    path is a path on the surface, so this is ≥ d(x, y); no unfolding is used."""
    V, F = _faces()
    t = np.arange(n) / n
    pts = [x, y]
    for f in F:
        for c in range(4):
            p, q = V[f[c]], V[f[(c + 1) % 4]]
            for s in t:
                pts.append(p + s * (q - p))
    P = np.round(np.array(pts), 12)
    P, inverse = np.unique(P, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    on_face = [np.flatnonzero(np.abs(np.dot(P - V[f[0]], np.cross(V[f[1]] - V[f[0]], V[f[3]] - V[f[0]]))) < 1e-9)
               for f in F]
    rows, cols = [], []
    for idx in on_face:
        r, c = np.meshgrid(idx, idx, indexing="ij")
        keep = r < c
        rows.append(r[keep])
        cols.append(c[keep])
    key = np.unique(np.concatenate(rows) * len(P) + np.concatenate(cols))  # pairs on a common edge once
    rows, cols = key // len(P), key % len(P)
    w = np.linalg.norm(P[rows] - P[cols], axis=1)
    G = coo_matrix((w, (rows, cols)), shape=(len(P), len(P))).tocsr()
    return float(dijkstra(G, directed=False, indices=inverse[0])[inverse[1]])


def _geodesic(x, y):
    """d(x, y) = the shortest straight line over the developments, and the lengths of its pieces
    between consecutive edge crossings."""
    V, F = _faces()
    (i,), (j,) = _face_of(V, F, x), _face_of(V, F, y)
    best = None
    for seq in _face_sequences(F, i, j, 6):
        x2, y2, edges = _develop(V, F, seq, x, y)
        ts = _crossings(x2, y2, edges)
        if ts is not None and (best is None or np.linalg.norm(y2 - x2) < best[0]):
            best = (float(np.linalg.norm(y2 - x2)), np.diff([0.0, *ts, 1.0]) * np.linalg.norm(y2 - x2))
    return best


def _rounding_bound(pieces, n):
    """Upper bound for L(rounded) − d when each crossing of the geodesic moves along its edge to the
    nearest of the n + 1 grid points (|δ| ≤ h/2, h = 1/n): the length is stationary at the geodesic and
    ∂²|u + sδ|/∂s² ≤ |δ|²/|u|, so the excess is ≤ ½ Σ_k (|δ_k| + |δ_k+1|)² / (ℓ_k − |δ_k| − |δ_k+1|)."""
    h = 1.0 / n
    move = np.full(len(pieces) + 1, h / 2)
    move[0] = move[-1] = 0.0  # x and y stay
    spread = move[:-1] + move[1:]
    return float(0.5 * np.sum(spread**2 / np.maximum(pieces - spread, 1e-300)))


def _pairs(count):
    """(X, Y) of Figure 5.8's kind, then points on two distinct random faces (fixed seed)."""
    rng = np.random.default_rng(52)
    out = [(X, Y), (np.array([0.3, 0.6, 0.0]), np.array([0.45, 0.35, 1.0]))]  # adjacent, opposite faces
    while len(out) < count:
        a, b = rng.choice(6, 2, replace=False)
        pts = []
        for f in (a, b):
            p = rng.uniform(0.05, 0.95, 3)
            p[f // 2] = f % 2
            pts.append(p)
        out.append(tuple(pts))
    return out[:count]


@check("Example 5.2", "d(x, y) on the cube is the shortest straight line x → y over the developments of "
       "strips of faces; Dijkstra distances on graphs of edge points (no unfolding) approach it from above "
       "within the a-priori O(h²) rounding bound B_n",
       quantity="max over point pairs and n of max((D_n − d)/B_n, (d − D_n)/1e-12)", at_most=1.0,
       quick=dict(pairs=4, ns=(7, 13, 25)), full=dict(pairs=12, ns=(7, 13, 25, 49, 97)))
def cube_shortest_path_unfolding(ctx, pairs, ns):
    worst = 0.0
    for k, (x, y) in enumerate(_pairs(pairs)):
        d, pieces = _geodesic(x, y)
        gaps = [dijkstra_distance(x, y, n) - d for n in ns]
        worst = max(worst, *(max(g / _rounding_bound(pieces, n), -g / 1e-12) for g, n in zip(gaps, ns)))
        if k == 0 and min(gaps) > 0:
            ctx.convergence(dg.limits.ConvergenceTable.from_errors(ns, gaps, label="D_n − d(x, y)"),
                            "cube_dijkstra_gap", title="Dijkstra on edge points − unfolded distance")
    return worst


@check("Example 5.2, Figure 5.8", "a straight line in a development need not be shortest: across the common "
       "edge of two adjacent faces it is longer than a graph path through a third face; negative control: the "
       "3-D chord |x − y| is shorter than d(x, y)",
       quantity="min(L(straight line across the common edge) − D_n, d − |x − y|)", at_least=0.1,
       quick=dict(n=25), full=dict(n=97))
def cube_straight_line_not_shortest(ctx, n):
    lengths = unfolded_lengths(X, Y)
    direct = lengths.get((5, 2), float("nan"))  # top → front, a path on the surface (its line crosses the edge)
    d = min(lengths.values())
    return min(direct - dijkstra_distance(X, Y, n), d - float(np.linalg.norm(X - Y)))
