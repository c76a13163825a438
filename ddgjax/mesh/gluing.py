"""Surfaces glued from polygons by words (Sec 4.2, Fig 4.6, Remark 4.6).

A word lists the sides of one polygon in order; a letter names an edge, lowercase traverses it in
its own direction and uppercase in the inverse one.  Each letter appears once (a boundary edge) or
twice (the two sides are glued).  "aA" is the sphere, "aa" the projective plane, "abAB" the torus,
"abaB" the Klein bottle.  The vertices of the cell decomposition are the classes of polygon
corners identified by the gluing, so one polygon may touch itself (the decomposition is a cell
decomposition, Def 4.3, in general not a regular one, Def 4.4).
"""

from __future__ import annotations

import string
from typing import Sequence

import numpy as np

from ..errors import MeshError
from .connectivity import Halfedges, from_gluing

__all__ = ["from_word", "connected_sum", "normal_form"]


def _as_words(word: str | Sequence[str]) -> list[str]:
    words = [word] if isinstance(word, str) else list(word)
    for w_index, w in enumerate(words):
        if len(w) < 2:
            raise MeshError(f"word {w_index} ({w!r}) has {len(w)} sides; a polygon needs at least 2")
        for i, ch in enumerate(w):
            if ch not in string.ascii_letters:
                raise MeshError(f"word {w_index} ({w!r}) has the non-letter {ch!r} at side {i}")
    return words


def from_word(word: str | Sequence[str]) -> Halfedges:
    """The cell decomposition glued from one polygon per word.

    **Arguments:** `word`, a string such as "abAB" or a list of strings (several polygons glued
    along shared letters).

    **Returns:** `Halfedges` whose faces are the polygons, edges the letters (in order of first
    appearance) and vertices the identified corners; all of `ddgjax.mesh`'s topology accepts it.

    **Raises:** `MeshError` for a non-letter or a polygon with fewer than two sides;
    `NonManifoldError` for a letter used more than twice.
    """
    words = _as_words(word)
    text = "".join(words)
    sizes = np.array([len(w) for w in words])
    face = np.repeat(np.arange(sizes.size), sizes)
    start = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    h_next = np.arange(len(text)) + 1
    h_next[start + sizes - 1] = start
    letters = list(dict.fromkeys(text.lower()))
    edge = np.array([letters.index(ch) for ch in text.lower()])
    sign = np.array([1 if ch.islower() else -1 for ch in text])
    return from_gluing(face, h_next, edge, sign)


def _rename(word: str, used: set[str]) -> str:
    """`word` with its letters replaced by lowercase letters not in `used` (cases preserved)."""
    free = [ch for ch in string.ascii_lowercase if ch not in used]
    own = list(dict.fromkeys(word.lower()))
    if len(own) > len(free):
        raise MeshError(f"connected sum needs {len(own)} new letters, only {len(free)} are left")
    table = dict(zip(own, free))
    return "".join(table[ch] if ch.islower() else table[ch.lower()].upper() for ch in word)


def connected_sum(*words: str) -> str:
    """The word of M₁ # M₂ # …: the concatenation of the words with disjoint letters.

    Cutting the polygon w₁w₂ along the diagonal between the two subwords gives the polygons of
    w₁ and w₂ each with a disk removed, glued along the cut: χ(w₁w₂) = χ(w₁) + χ(w₂) − 2.
    """
    out = ""
    for w in words:
        out += _rename(w, set(out.lower()))
    return out


def normal_form(genus: int, orientable: bool = True) -> str:
    """The normal-form word of (T²)#g (a₁b₁a₁⁻¹b₁⁻¹ … , "aA" for g = 0) or of (RP²)#k
    (a₁a₁ a₂a₂ …, k ≥ 1) of Thm 4.1.
    """
    if orientable:
        return connected_sum(*(["abAB"] * genus)) if genus > 0 else "aA"
    if genus < 1:
        raise MeshError(f"a non-orientable surface has at least one cross-cap, got {genus}")
    return connected_sum(*(["aa"] * genus))
