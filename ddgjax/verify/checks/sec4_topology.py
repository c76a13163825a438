"""Topology of surfaces (Sec 4: Thm 4.1, Cor 4.2)."""

from __future__ import annotations

import string
from collections import Counter

import numpy as np

from ddgjax import mesh
from ddgjax.verify import check

# built-in mesh -> (χ, orientable, genus or number of cross-caps, boundary components, name)
BUILTIN = {
    "tetrahedron": (2, True, 0, 0, "sphere"), "cube": (2, True, 0, 0, "sphere"),
    "octahedron": (2, True, 0, 0, "sphere"), "icosahedron": (2, True, 0, 0, "sphere"),
    "icosphere": (2, True, 0, 0, "sphere"), "torus": (0, True, 1, 0, "torus"),
    "projective_plane": (1, False, 1, 0, "projective plane"), "klein_bottle": (0, False, 2, 0, "Klein bottle"),
    "double_torus": (-2, True, 2, 0, "double torus"), "disk": (1, True, 0, 1, "disk"),
    "annulus": (0, True, 0, 2, "annulus"), "mobius_strip": (0, False, 1, 1, "Möbius strip"),
}


@check("Thm 4.1, Cor 4.2", "every built-in mesh is classified as the surface it is (χ, orientability, genus, boundary)",
       quantity="number of misclassified meshes (by `classification` or by any of the single invariants)", at_most=0,
       quick=dict())
def builtin_meshes_classified(ctx):
    wrong = 0
    for name, expected in BUILTIN.items():
        F = getattr(mesh, name)()[1]
        c = mesh.classification(F)
        single = (mesh.euler_characteristic(F), mesh.is_orientable(F), mesh.genus(F), len(mesh.boundary_loops(F)))
        wrong += ((c.euler_characteristic, c.orientable, c.genus, c.boundary_components, c.name) != expected
                  or single != expected[:4] or expected[4] not in mesh.classify(F))
    return wrong


@check("Thm 4.1", "χ = 2 − 2g − b (orientable) and χ = 2 − g − b (non-orientable) on every built-in mesh",
       quantity="max |χ − formula|", at_most=0, quick=dict())
def euler_characteristic_formula(ctx):
    worst = 0
    for name, (_, orientable, g, b, _) in BUILTIN.items():
        F = getattr(mesh, name)()[1]
        formula = 2 - 2 * g - b if orientable else 2 - g - b
        worst = max(worst, abs(mesh.euler_characteristic(F) - formula))
    return worst


@check("Sec 4.2", "the connected sum of polygon words has χ(M # N) = χ(M) + χ(N) − 2 and is orientable iff M and N are",
       quantity="max |χ(M # N) − χ(M) − χ(N) + 2| over pairs of words + number of pairs with the wrong orientability",
       at_most=0, quick=dict())
def connected_sum_euler_characteristic(ctx):
    words = ["aA", "aa", "abAB", "abaB", "abcabc"]
    chi = {w: mesh.euler_characteristic(mesh.from_word(w)) for w in words}
    orientable = {w: mesh.is_orientable(w) for w in words}
    sums = {(u, w): mesh.connected_sum(u, w) for u in words for w in words}
    defect = max(abs(mesh.euler_characteristic(mesh.from_word(s)) - chi[u] - chi[w] + 2) for (u, w), s in sums.items())
    return defect + sum(mesh.is_orientable(s) != (orientable[u] and orientable[w]) for (u, w), s in sums.items())


# Thm 4.1 by an independent route: the classical cut-and-paste reduction of a polygon schema.  A
# word is a cyclic list of tokens (letter, ±1); a letter occurring twice names two glued sides, one
# occurring once a boundary edge.  Every step below is a homeomorphism of the glued surface:
#   x x⁻¹ → ∅ (fold two adjacent sides),  boundary b b' → b (join two boundary edges at a corner),
#   a Y a Z = RP² # Y⁻¹Z,   a X b Y a⁻¹ Z b⁻¹ W = T² # ZYXW,   a X a⁻¹ Y = X # Y (no pair shared),
# with M # N the concatenation of the words (`mesh.connected_sum`) and RP² # T² = (RP²)#3.


def _tokens(word: str) -> list:
    return [(ch.lower(), 1 if ch.islower() else -1) for ch in word]


def _inverse(w: list) -> list:
    return [(letter, -s) for letter, s in reversed(w)]


def _polygon_schema(F) -> list:
    """The word of one polygon glued from the faces of `F` along a spanning tree of the dual graph
    (letters: the edges {u, v}, sign +1 when traversed from the smaller vertex label)."""
    faces = [[int(v) for v in f] for f in F]
    sides = [[((min(u, v), max(u, v)), 1 if u < v else -1) for u, v in zip(f, f[1:] + f[:1])] for f in faces]
    owners: dict = {}
    for i, f in enumerate(sides):
        for e, _ in f:
            owners.setdefault(e, []).append(i)
    word, seen, queue = list(sides[0]), {0}, [0]
    while queue:
        for e, _ in sides[queue.pop()]:
            for j in owners[e]:
                if j not in seen:
                    seen.add(j)
                    queue.append(j)
                    word = _glue(sides[j], word, e)
    return word


def _glue(polygon: list, word: list, letter) -> list:
    """`word` with its side `letter` replaced by the rest of `polygon` (which has that side once):
    in polygon = t R the side t is the path R⁻¹."""
    i = next(k for k, (x, _) in enumerate(polygon) if x == letter)
    t, rest = polygon[i], polygon[i + 1:] + polygon[:i]
    j = next(k for k, (x, _) in enumerate(word) if x == letter)
    return word[:j] + (_inverse(rest) if word[j] == t else rest) + word[j + 1:]


def _reduced(w: list) -> list:
    """Cancel adjacent x x⁻¹ (cyclically), then join runs of boundary edges into one."""
    stack: list = []
    for t in w:
        if stack and stack[-1] == (t[0], -t[1]):
            stack.pop()
        else:
            stack.append(t)
    while len(stack) >= 2 and stack[0] == (stack[-1][0], -stack[-1][1]):
        stack = stack[1:-1]
    count = Counter(x for x, _ in stack)
    paired = [k for k, (x, _) in enumerate(stack) if count[x] == 2]
    if not paired:
        return stack[:1]
    stack = stack[paired[0]:] + stack[:paired[0]]
    return [t for k, t in enumerate(stack) if count[t[0]] == 2 or count[stack[k - 1][0]] == 2]


def _handles_crosscaps_holes(word: list) -> tuple[int, int, int]:
    """`(h, k, b)` with the glued surface = (T²)#h # (RP²)#k minus b disks (rules above)."""
    h = k = b = 0
    pending = [word]
    while pending:
        w = _reduced(pending.pop())
        where: dict = {}
        for i, (x, _) in enumerate(w):
            where.setdefault(x, []).append(i)
        pairs = [p for p in where.values() if len(p) == 2]
        if not pairs:
            b += len(w)  # ∅ is the sphere, one boundary edge the disk
            continue
        cap = next(((i, j) for i, j in pairs if w[i] == w[j]), None)
        if cap is not None:
            i, j = cap
            k, w = k + 1, _inverse(w[i + 1:j]) + w[j + 1:] + w[:i]
            pending.append(w)
            continue
        i, j = pairs[0]
        X, Y = w[i + 1:j], w[j + 1:] + w[:i]  # w = a X a⁻¹ Y
        shared = set(x for x, _ in X) & set(x for x, _ in Y)
        if not shared:
            pending += [X, Y]
            continue
        x = next(iter(shared))
        p, q = next(n for n, t in enumerate(X) if t[0] == x), next(n for n, t in enumerate(Y) if t[0] == x)
        h += 1
        pending.append(Y[:q] + X[p + 1:] + X[:p] + Y[q + 1:])
    return h, k, b


def _normal_form(counts: tuple[int, int, int]) -> tuple[bool, int, int]:
    """`(orientable, g or k, b)` of (T²)#h # (RP²)#k minus b disks, using RP² # T² = (RP²)#3."""
    h, k, b = counts
    return (True, h, b) if k == 0 else (False, 2 * h + k, b)


def _as_normal_form(c) -> tuple[bool, int, int]:
    return (c.orientable, c.genus, c.boundary_components)


def _random_word(rng, pairs: int, boundary: int, orientable: bool) -> str:
    """A random polygon with `pairs` glued pairs of sides (each x … x⁻¹ when `orientable`)."""
    letters = string.ascii_lowercase[:pairs + boundary]
    first = [ch if rng.random() < 0.5 else ch.upper() for ch in letters[:pairs]]
    second = [ch.swapcase() if orientable else ch if rng.random() < 0.5 else ch.swapcase() for ch in first]
    return "".join(rng.permutation(first + second + list(letters[pairs:])))


def _normal_form_pairs(words: int):
    """`(surface, normal form by reduction, library classification)` on every built-in mesh, on
    `words` random gluing words (with boundary letters) and on their pairwise connected sums."""
    rng = np.random.default_rng(4)
    for name in BUILTIN:
        F = getattr(mesh, name)()[1]
        yield name, _normal_form(_handles_crosscaps_holes(_polygon_schema(F))), mesh.classification(F)
    sample = [_random_word(rng, int(rng.integers(1, 9)), int(rng.integers(0, 4)), n % 2 == 0) for n in range(words)]
    for u, w in zip(sample, sample[1:]):
        s = mesh.connected_sum(u, w)
        yield s, _normal_form(_handles_crosscaps_holes(_tokens(s))), mesh.classification(s)
    for u in sample:
        yield u, _normal_form(_handles_crosscaps_holes(_tokens(u))), mesh.classification(u)


@check("Thm 4.1, Remark 4.6", "the cut-and-paste normal form of the polygon schema (T²)#g or (RP²)#k minus b disks "
       "agrees with `classification` on every built-in mesh, random gluing words and their connected sums",
       quantity="number of surfaces whose reduced normal form (orientable, g or k, b) differs from the classifier's",
       at_most=0, quick=dict(words=60), full=dict(words=400))
def normal_form_by_reduction(ctx, words):
    return sum(reduced != _as_normal_form(c) for _, reduced, c in _normal_form_pairs(words))


@check("Thm 4.1", "negative control: classifications with the orientability swapped at equal χ (g handles ↔ 2g "
       "cross-caps) are told apart from the normal form",
       quantity="fraction of the swapped classifications that differ from the reduced normal form",
       at_least=1.0, quick=dict(words=60), full=dict(words=400))
def normal_form_detects_swapped_orientability(ctx, words):
    swapped = [(not o, 2 * g if o else g // 2, b) for o, g, b in (_as_normal_form(c) for _, _, c in
                                                                 _normal_form_pairs(words))]
    reduced = [r for _, r, _ in _normal_form_pairs(words)]
    return float(np.mean([s != r for s, r in zip(swapped, reduced)]))
