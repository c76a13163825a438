"""The trust audit: scripted probes of bad and extreme input, each judged against what the API
promises (`../shared/API.md`: bad input raises a `ddgjax.errors.DDGError` subclass naming the
offending element; inputs are never mutated; extreme but valid input gets the right answer).

A probe is one call with one defect (a NaN coordinate, an index out of range, a negative
length, a scale of 1e150, a truncated file, …) and what must come of it:

- `"raises"`: a `DDGError` subclass whose message names the element (one of `names`);
- `"value"`: a result equal to `expected()` (relative `rtol`), e.g. `s^p f(V)` for a quantity
  that scales with degree p (scale covariance, exact since the library normalises by powers of 2);
- `"finite_or_raises"`: either a `DDGError`, or a result whose every number is finite (for
  inputs that are legitimate for some quantities, e.g. a zero-area face for the edge lengths).

Every probe also checks that its NumPy inputs are unchanged.  Outcomes: `ok`, `silent`
(returned where it had to raise, or returned NaN/inf), `wrong` (a wrong number), `foreign`
(an exception that is not a `DDGError`, e.g. a raw `JaxRuntimeError`), `unnamed` (a `DDGError`
whose message does not name the element), `mutated`, and, when run isolated (the default of the
command line: one worker process, restarted after a crash), `crash` (the process ended), `hang`
(over the time limit) and `memory` (the peak resident memory grew by more than `MEMORY_MB`).

    python tests/probes.py [--only SUBSTRING] [--list] [--in-process]

prints a table per family and every probe that is not `ok`; exit status 1 if any is not.
`tests/test_probes.py` runs all of them in the test suite (in process).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

MEMORY_MB = 400
TIME_LIMIT_S = 120
KINDS = ("raises", "value", "finite_or_raises")


@dataclass
class Probe:
    id: str
    call: Callable[[], Any]
    expect: str = "raises"
    names: tuple = ()
    expected: Callable[[], Any] | None = None
    rtol: float = 1e-10
    inputs: tuple = ()
    family: str = ""
    error: type | None = None  # a DDGError subclass the error must be an instance of

    def __post_init__(self):
        assert self.expect in KINDS, self.expect
        self.family = self.family or self.id.split(":")[0]


# ---------------------------------------------------------------------------------- judging


def _numbers(result) -> list[np.ndarray]:
    """Every number in a result (arrays, scalars, sparse matrices, tuples, dataclasses)."""
    import scipy.sparse as sp

    out = []

    def walk(r, depth=0):
        if depth > 6 or r is None or isinstance(r, (str, bytes)):
            return
        if isinstance(r, (bool, np.bool_)):
            out.append(np.asarray(float(r)))
            return
        if sp.issparse(r):
            out.append(np.asarray(r.toarray() if r.shape[0] * r.shape[1] < 4e6 else r.data, dtype=float))
        elif isinstance(r, (int, float, complex, np.number)):
            out.append(np.asarray(r, dtype=complex if isinstance(r, complex) else float))
        elif hasattr(r, "__array__") and not isinstance(r, (list, tuple, dict)):
            a = np.asarray(r)
            if a.dtype.kind in "fciub":
                out.append(a.astype(complex if a.dtype.kind == "c" else float))
        elif isinstance(r, dict):
            for v in r.values():
                walk(v, depth + 1)
        elif isinstance(r, (list, tuple)):
            for v in r:
                walk(v, depth + 1)
        elif hasattr(r, "__dataclass_fields__"):
            for name in r.__dataclass_fields__:
                walk(getattr(r, name), depth + 1)

    walk(result)
    return out


def _close(result, expected, rtol: float) -> tuple[bool, str]:
    got, want = _numbers(result), _numbers(expected)
    if len(got) != len(want):
        return False, f"{len(got)} arrays returned, {len(want)} expected"
    for i, (g, w) in enumerate(zip(got, want)):
        if g.shape != w.shape:
            return False, f"array {i}: shape {g.shape}, expected {w.shape}"
        if not np.all(np.isfinite(g) == np.isfinite(w)):
            return False, f"array {i}: non-finite entries differ ({np.sum(~np.isfinite(g))} returned)"
        fin = np.isfinite(w)
        scale = np.max(np.abs(w[fin]), initial=0.0)
        err = np.max(np.abs(g[fin] - w[fin]), initial=0.0)
        if err > rtol * scale + 1e-300 * (scale == 0):
            return False, f"array {i}: max error {err:.3g} relative to {scale:.3g}"
    return True, ""


def judge(probe: Probe) -> tuple[str, str]:
    """(outcome, detail) of one probe, run in this process."""
    from ddgjax.errors import DDGError

    before = [np.array(a, copy=True) for a in probe.inputs]
    try:
        result = probe.call()
    except DDGError as e:
        msg = str(e)
        if probe.error is not None and not isinstance(e, probe.error):
            outcome = ("wrong", f"{type(e).__name__} (wanted {probe.error.__name__}): {msg[:200]}")
        elif probe.expect == "value":
            outcome = ("wrong", f"raised {type(e).__name__} on valid input: {msg[:200]}")
        elif probe.names and not any(re.search(n, msg, re.IGNORECASE) for n in probe.names):
            outcome = ("unnamed", f"{type(e).__name__}: {msg[:200]}")
        else:
            outcome = ("ok", f"{type(e).__name__}: {msg[:120]}")
    except BaseException as e:  # noqa: BLE001 — the point is to see everything
        if isinstance(e, KeyboardInterrupt):
            raise
        tb = traceback.extract_tb(e.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        outcome = ("foreign", f"{type(e).__module__}.{type(e).__name__}{where}: {str(e)[:200]}")
    else:
        if probe.expect == "raises":
            outcome = ("silent", f"returned {_summary(result)}")
        elif probe.expect == "finite_or_raises":
            bad = [a for a in _numbers(result) if not np.all(np.isfinite(a))]
            outcome = ("silent", f"non-finite result {_summary(result)}") if bad else ("ok", "finite")
        else:
            ok, detail = _close(result, probe.expected(), probe.rtol)
            outcome = ("ok", "equal") if ok else ("wrong", detail)
    for a, b in zip(before, probe.inputs):
        if not np.array_equal(a, np.asarray(b), equal_nan=a.dtype.kind in "fc"):
            return "mutated", "an input array changed"
    return outcome


def _summary(result) -> str:
    nums = _numbers(result)
    if not nums:
        return repr(result)[:120]
    a = nums[0]
    return f"{type(result).__name__} (first array {a.shape}, {np.sum(~np.isfinite(a))} non-finite, e.g. {a.ravel()[:3]})"


# ---------------------------------------------------------------------------------- meshes

VERTEX = (r"vert(ex|ices)\D{0,30}3\b", r"V\[3", r"row 3\b", r"\b3\b.*vert", r"index \(3, ")
FACE = (r"face\D{0,30}5\b", r"F\[5", r"triangle\D{0,20}5\b")


def probe_meshes() -> dict:
    """A closed mesh (sphere-like, not Delaunay everywhere) and an open one (a saddle grid)."""
    import ddgjax as dg

    V, F = dg.mesh.icosphere(2)
    V = np.asarray(V, float) * np.array([1.0, 1.3, 0.7])  # not intrinsically Delaunay
    W, G, _ = dg.mesh.saddle_grid(5)
    return {"closed": (np.asarray(V, float), np.asarray(F)), "open": (np.asarray(W, float), np.asarray(G))}


def _vf_functions():
    """(name, f(V, F), scaling degree p: f(sV) = s^p f(V), needs a closed mesh)."""
    import ddgjax as dg
    from ddgjax import laplace, mesh

    return [
        ("angle_defect", mesh.angle_defect, 0, False),
        ("edge_mean_curvature", mesh.edge_mean_curvature, 1, False),
        ("total_mean_curvature", mesh.total_mean_curvature, 1, False),
        ("corner_angles", mesh.corner_angles, 0, False),
        ("dihedral_angles", mesh.dihedral_angles, 0, False),
        ("edge_lengths", mesh.edge_lengths, 1, False),
        ("surface_area", mesh.surface_area, 2, False),
        ("cotan_weights", laplace.cotan_weights, 0, False),
        ("cotan_laplacian", laplace.cotan_laplacian, 0, False),
        ("laplace_beltrami", dg.intrinsic.laplace_beltrami, 0, False),
        ("subdivide", lambda V, F: mesh.subdivide(V, F)[0], 1, False),  # positions: translated with V
        ("steiner_area", lambda V, F: mesh.steiner_area(V, F, 0.1 * _scale_of(V)), 2, True),
    ]


def _scale_of(V) -> float:
    """The extent of the vertices (translation-invariant, covariant with scaling)."""
    V = np.asarray(V, float)
    if V.ndim != 2 or not np.all(np.isfinite(V)):
        return 1.0
    return float(np.max(np.ptp(V, axis=0)))


def _angle_based(name: str) -> bool:
    """Quantities undefined at a zero-area face (normals, cotangents); a collinear face still
    has angles (π, 0, 0), so angles and defects may be returned there."""
    return name not in ("edge_lengths", "surface_area", "subdivide", "corner_angles", "angle_defect")


def mesh_probes() -> list[Probe]:
    meshes = probe_meshes()
    probes = []
    for name, f, p, closed_only in _vf_functions():
        for kind, (V, F) in meshes.items():
            if closed_only and kind != "closed":
                continue
            tag = f"mesh:{name}:{kind}"
            for label, bad in (("nan", np.nan), ("inf", np.inf), ("-inf", -np.inf)):
                V2 = V.copy()
                V2[3, 1] = bad
                probes.append(Probe(f"{tag}:vertex 3 {label}", _bind(f, V2, F), names=VERTEX, inputs=(V2, F)))
            F2 = F.copy()
            F2[5, 2] = len(V)
            probes.append(Probe(f"{tag}:face 5 index = nv", _bind(f, V, F2), names=FACE, inputs=(V, F2)))
            F2 = F.copy()
            F2[5, 0] = -1
            probes.append(Probe(f"{tag}:face 5 index -1", _bind(f, V, F2), names=FACE, inputs=(V, F2)))
            F2 = F.astype(float)
            F2[5, 1] += 0.5
            probes.append(Probe(f"{tag}:face 5 fractional index", _bind(f, V, F2), names=FACE, inputs=(V, F2)))
            F2 = F.copy()
            F2[5, 1] = F2[5, 0]
            probes.append(Probe(f"{tag}:face 5 repeats a vertex", _bind(f, V, F2), names=FACE, inputs=(V, F2)))
            # the intrinsic side and subdivision take positions in any R^d
            probes.append(Probe(f"{tag}:V of shape (nv, 4)", _bind(f, np.c_[V, V[:, :1]], F), names=(r"shape",),
                                expect="finite_or_raises" if name in ("laplace_beltrami", "subdivide") else "raises"))
            probes.append(Probe(f"{tag}:V 1-D", _bind(f, V.ravel(), F), names=(r"shape",)))
            probes.append(Probe(f"{tag}:F of shape (nf, 2)", _bind(f, V, F[:, :2].copy())))  # 2-gons: any DDGError
            probes.append(Probe(f"{tag}:empty F", _bind(f, V, np.zeros((0, 3), int)), names=(r"empty", r"no face", r"0 faces")))
            probes.append(Probe(f"{tag}:F as strings", _bind(f, V, F.astype(str)), names=(r"integer", r"dtype", r"F")))
            # a degenerate face: vertex 0 of face 5 moved onto the midpoint of its opposite side
            V2 = V.copy()
            a, b, c = F[5]
            V2[a] = 0.5 * (V[b] + V[c])
            expect = "raises" if _angle_based(name) else "finite_or_raises"
            probes.append(Probe(f"{tag}:face 5 collinear", _bind(f, V2, F), expect=expect, names=FACE + (r"vert",), inputs=(V2,)))
            V2 = V.copy()
            V2[a] = V[b]
            probes.append(Probe(f"{tag}:face 5 two coincident vertices", _bind(f, V2, F), expect=expect,
                                names=FACE + (r"vert", r"edge"), inputs=(V2,)))
            for s in (1e-150, 2.0**-400, 1e-100, 1e-80, 1e80, 1e100, 2.0**400, 1e150):
                Vs = V * s
                probes.append(Probe(f"{tag}:scale {s:.0e}", _bind(f, Vs, F), expect="value",
                                    expected=_scaled(f, V, F, s, p), rtol=1e-9, inputs=(Vs,)))
            shift = np.array([1e3, -2e3, 5e2])
            Vs = V * 3.0 + shift
            expected = _scaled(f, V, F, 3.0, p)
            if name == "subdivide":
                expected = (lambda e=expected: e() + shift)
            probes.append(Probe(f"{tag}:translated", _bind(f, Vs, F), expect="value",
                                expected=expected, rtol=1e-7, inputs=(Vs,)))
    return probes


def _bind(f, *args, **kwargs):
    return lambda: f(*args, **kwargs)


def _scaled(f, V, F, s, p):
    import scipy.sparse as sp

    def expected():
        r = f(V, F)
        if sp.issparse(r):
            return r * (s**p)
        return _tree_scale(r, s**p)

    return expected


def _tree_scale(r, factor):
    if isinstance(r, tuple):
        return tuple(_tree_scale(x, factor) for x in r)
    if isinstance(r, dict):
        return {k: _tree_scale(v, factor) for k, v in r.items()}
    return np.asarray(r, float) * factor


def topology_probes() -> list[Probe]:
    from ddgjax import mesh

    V, F = probe_meshes()["closed"]
    probes = []
    for name in ("euler_characteristic", "is_orientable", "boundary_loops", "genus", "classify"):
        f = getattr(mesh, name)
        tag = f"topology:{name}"
        probes.append(Probe(f"{tag}:empty F", _bind(f, np.zeros((0, 3), int)), names=(r"empty", r"no face"),
                            expect="raises" if name in ("genus", "classify") else "finite_or_raises"))
        F2 = F.copy()
        F2[5, 0] = -1
        probes.append(Probe(f"{tag}:face 5 index -1", _bind(f, F2), names=FACE, inputs=(F2,)))
        F2 = F.copy()
        F2[5, 1] = F2[5, 0]
        probes.append(Probe(f"{tag}:face 5 repeats a vertex", _bind(f, F2), names=FACE, inputs=(F2,)))
        F2 = np.r_[F, F[:1]]
        probes.append(Probe(f"{tag}:a face twice (edge on 4 faces)", _bind(f, F2), names=(r"edge", r"face", r"manifold")))
        probes.append(Probe(f"{tag}:F of shape (nf, 2)", _bind(f, F[:, :2].copy())))  # 2-gons: any DDGError
        probes.append(Probe(f"{tag}:F float NaN", _bind(f, np.where(F == F[5, 0], np.nan, F.astype(float))),
                            names=(r"face", r"integer", r"nan")))
    return probes


# ---------------------------------------------------------------------------------- intrinsic


def intrinsic_probes() -> list[Probe]:
    from ddgjax import intrinsic, mesh

    V, F = probe_meshes()["closed"]
    L = np.asarray(mesh.edge_lengths(V, F), float)
    fns = {
        "flip_to_delaunay": lambda F, L, **k: _flip_summary(intrinsic.flip_to_delaunay(F, L, **k)),
        "is_delaunay": intrinsic.is_delaunay,
        "harmonic_index": lambda F, L, **k: intrinsic.harmonic_index(F, L),
        "laplace_beltrami_from_lengths": intrinsic.laplace_beltrami_from_lengths,
    }
    E = np.asarray(mesh.edges(F))
    key = {tuple(sorted(e)): i for i, e in enumerate(E.tolist())}
    a, b, c = F[5]
    e_bc, e_ca, e_ab = key[tuple(sorted((b, c)))], key[tuple(sorted((c, a)))], key[tuple(sorted((a, b)))]
    EDGE = (rf"edge\D{{0,30}}{e_bc}\b", r"face\D{0,30}5\b", rf"\b{e_bc}\b")
    probes = []
    for name, f in fns.items():
        tag = f"intrinsic:{name}"
        for label, bad in (("nan", np.nan), ("inf", np.inf), ("negative", -0.1), ("zero", 0.0)):
            L2 = L.copy()
            L2[e_bc] = bad
            probes.append(Probe(f"{tag}:length of edge {e_bc} {label}", _bind(f, F, L2), names=EDGE, inputs=(L2,)))
        L2 = L.copy()
        L2[e_bc] = L2[e_ca] + L2[e_ab]
        probes.append(Probe(f"{tag}:face 5 on the triangle inequality", _bind(f, F, L2), names=FACE + EDGE, inputs=(L2,)))
        L2 = L.copy()
        L2[e_bc] = 3 * (L2[e_ca] + L2[e_ab])
        probes.append(Probe(f"{tag}:face 5 violates the triangle inequality", _bind(f, F, L2), names=FACE + EDGE, inputs=(L2,)))
        probes.append(Probe(f"{tag}:lengths of shape (ne, 2)", _bind(f, F, np.c_[L, L]), names=(r"shape",)))
        probes.append(Probe(f"{tag}:lengths of the wrong count", _bind(f, F, L[:-1].copy()), names=(r"shape", r"edge", r"length")))
        probes.append(Probe(f"{tag}:lengths 0-d", _bind(f, F, np.float64(1.0)), names=(r"shape", r"edge", r"length")))
        if name != "harmonic_index":
            for tol in (np.nan, np.inf, -1.0, 0.0):
                probes.append(Probe(f"{tag}:tol {tol}", _bind(f, F, L, tol=tol), names=(r"tol",)))
        for s in (1e-150, 1e-100, 1e100, 1e150):
            Ls = L * s
            p = 1 if name == "flip_to_delaunay" else 0
            probes.append(Probe(f"{tag}:scale {s:.0e}", _bind(f, F, Ls), expect="value",
                                expected=_scaled_lengths(f, F, L, s, p), rtol=1e-9, inputs=(Ls,)))
    return probes


def _flip_summary(result):
    return (result.lengths, np.asarray(result.n_flips, float))


def _scaled_lengths(f, F, L, s, p):
    import scipy.sparse as sp

    def expected():
        r = f(F, L)
        if sp.issparse(r):
            return r
        if isinstance(r, (bool, np.bool_)):
            return float(r)
        if isinstance(r, tuple):  # flip summary: lengths scale, the flip count does not
            return (np.asarray(r[0]) * s**p, r[1])
        return np.asarray(r, float) * s**p

    return expected


# ---------------------------------------------------------------------------------- curves


def _test_curve(closed: bool, planar: bool = False) -> np.ndarray:
    """An equilateral polygon (arc-length parametrised, Def 1.2): a helix when open, a regular
    12-gon in a tilted plane when closed; (N, 2) in the plane if `planar`."""
    n = 12
    t = np.linspace(0, 2 * np.pi, n, endpoint=not closed)
    g = np.stack([np.cos(t), np.sin(t), (0.0 if closed or planar else 0.2) * t], axis=1)
    if planar:
        return g[:, :2].copy()
    if closed:
        c, s = np.cos(0.4), np.sin(0.4)
        g = g @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return g


def curve_probes() -> list[Probe]:
    from ddgjax import curves

    fns = [
        ("tangents", lambda g, c: curves.tangents(g, closed=c), 0, False),
        ("turning_angles", lambda g, c: curves.turning_angles(g, closed=c), 0, False),
        ("curvature vertex", lambda g, c: curves.curvature(g, "vertex", closed=c), -1, False),
        ("curvature edge", lambda g, c: curves.curvature(g, "edge", closed=c), -1, True),
        ("curvature arclength", lambda g, c: curves.curvature(g, "arclength", closed=c), -1, False),
        ("edge_lengths", lambda g, c: curves.edge_lengths(g, closed=c), 1, False),
        ("tangent_flow", lambda g, c: curves.tangent_flow(g, closed=c), 0, False),
        ("heisenberg_flow", lambda g, c: curves.heisenberg_flow(g, closed=c), 0, False),
    ]
    probes = []
    for name, f, p, planar in fns:
        for closed in (False, True):
            g = _test_curve(closed, planar)
            tag = f"curves:{name}:{'closed' if closed else 'open'}"
            for label, bad in (("nan", np.nan), ("inf", np.inf)):
                g2 = g.copy()
                g2[3, 0] = bad
                probes.append(Probe(f"{tag}:vertex 3 {label}", _bind(f, g2, closed), names=VERTEX + (r"3",), inputs=(g2,)))
            g2 = g.copy()
            g2[4] = g2[3]
            probes.append(Probe(f"{tag}:vertices 3 and 4 coincide", _bind(f, g2, closed),
                                expect="finite_or_raises" if name == "edge_lengths" else "raises",
                                names=(r"\b3\b", r"\b4\b"), inputs=(g2,)))
            g2 = g.copy()
            g2[4] = g2[2]  # edge 3 runs straight back along edge 2: a turn by π at vertex 3
            probes.append(Probe(f"{tag}:a turn by pi at vertex 3", _bind(f, g2, closed),
                                expect="finite_or_raises" if name in ("edge_lengths", "tangents", "turning_angles") else "raises",
                                names=(r"\b[34]\b",), inputs=(g2,)))
            probes.append(Probe(f"{tag}:gamma of shape (n, 4)", _bind(f, np.c_[g, g[:, :1]], closed), names=(r"shape",)))
            probes.append(Probe(f"{tag}:gamma 1-D", _bind(f, g.ravel(), closed), names=(r"shape",)))
            probes.append(Probe(f"{tag}:one vertex", _bind(f, g[:1].copy(), closed), names=(r"vert", r"point", r"at least", r"shape")))
            probes.append(Probe(f"{tag}:empty", _bind(f, np.zeros((0, g.shape[1])), closed),
                                names=(r"vert", r"point", r"at least", r"empty", r"shape")))
            for s in (1e-150, 1e-100, 1e100, 1e150):
                gs = g * s
                flow_p = {"tangent_flow": 0, "heisenberg_flow": 0}.get(name, p)
                probes.append(Probe(f"{tag}:scale {s:.0e}", _bind(f, gs, closed), expect="value",
                                    expected=_scaled_curve(f, g, closed, s, flow_p), rtol=1e-9, inputs=(gs,)))
    return probes


def _scaled_curve(f, g, closed, s, p):
    return lambda: np.asarray(f(g, closed), float) * s**p


# ---------------------------------------------------------------------------------- catalogue


def catalogue_probes() -> list[Probe]:
    from energies import area, dirichlet, elastica, heisenberg, pendulum, rod, willmore

    from ddgjax.quaternion import from_axis_angle

    e1, e2, e3 = np.eye(3)
    base_el = dict(chord=(0.5, 0.2, 0.0), t_start=(1.0, 0, 0), t_end=(0, 1.0, 0))
    probes = []

    def el(label, names=(), **kw):
        args = {**base_el, **kw}
        n = args.pop("n", 16)
        probes.append(Probe(f"catalogue:elastica.clamped:{label}", lambda: elastica.clamped(n, **args), names=names))

    for n in (0, 1, 2, -5, 2.5, np.nan, "8"):
        el(f"n = {n!r}", names=(r"\bn\b",), n=n)
    for chord, why in (((np.nan, 0, 0), "chord nan"), ((np.inf, 0, 0), "chord inf"), ((0.5, 0.2), "chord shape (2,)"),
                       ((1.0, 0.0, 0.0), "|chord| = length"), ((2.0, 0, 0), "|chord| > length"), (np.nan, "chord 0-d nan")):
        el(why, names=(r"chord",), chord=chord)
    for t, why in (((0, 0, 0), "t_start zero"), ((np.nan, 1, 0), "t_start nan"), ((1, 0), "t_start shape (2,)")):
        el(why, names=(r"t_start",), t_start=t)
    for length in (0.0, -1.0, np.nan, np.inf):
        el(f"length {length}", names=(r"length",), length=length)
    el("clamp bogus", names=(r"clamp",), clamp="middle")
    el("x0 of the wrong shape", names=(r"x0", r"shape"), x0=np.ones((15, 3)))
    el("x0 with nan", names=(r"x0",), x0=np.full((16, 3), np.nan))

    for length in (0.0, -1.0, np.nan, np.inf):
        probes.append(Probe(f"catalogue:elastica.closed:length {length}",
                            _bind(elastica.closed, 16, length=length, x0=_circle_tangents(16)), names=(r"length",)))
    probes.append(Probe("catalogue:elastica.closed:x0 not unit", _bind(elastica.closed, 16, x0=2 * _circle_tangents(16)),
                        expect="finite_or_raises"))
    probes.append(Probe("catalogue:elastica.closed:n = 2", _bind(elastica.closed, 2, x0=_circle_tangents(2)), names=(r"\bn\b",)))

    q0 = np.asarray(from_axis_angle(np.array([0, 0, 1.0]), 0.3))
    q1 = np.asarray(from_axis_angle(np.array([0, 0, 1.0]), -0.3))
    base_rod = dict(alpha=0.7, chord=(0.6, 0, 0), frame_start=q0, frame_end=q1)

    def rd(label, names=(), **kw):
        args = {**base_rod, **kw}
        n = args.pop("n", 12)
        probes.append(Probe(f"catalogue:rod.clamped:{label}", lambda: rod.clamped(n, **args), names=names))

    for alpha in (0.0, -1.0, np.nan, np.inf):
        rd(f"alpha {alpha}", names=(r"alpha", r"α"), alpha=alpha)
    rd("frame_start not unit", names=(r"frame_start",), frame_start=2 * q0)
    rd("frame_start nan", names=(r"frame_start",), frame_start=np.full(4, np.nan))
    rd("frame_start shape (3,)", names=(r"frame_start", r"shape"), frame_start=q0[:3])
    rd("chord longer than the rod", names=(r"chord",), chord=(1.5, 0, 0))
    rd("bending negative", names=(r"bending", r"stiffness"), bending=(1.0, -1.0))
    rd("bending nan", names=(r"bending",), bending=(1.0, np.nan))
    rd("n = 2", names=(r"\bn\b",), n=2)

    base_p = dict(a=(0.0, 0.0, -1.0), T_first=(1.0, 0, 0), T_last=(0, 1.0, 0))
    for label, kw, names in (("a nan", dict(a=(np.nan, 0, 0)), (r"\ba\b", r"load")), ("T_first zero", dict(T_first=(0, 0, 0)), (r"T_first",)),
                             ("T_last shape (2,)", dict(T_last=(1, 0)), (r"T_last", r"shape")), ("n = 1", dict(n=1), (r"\bn\b",))):
        args = {**base_p, **kw}
        n = args.pop("n", 12)
        probes.append(Probe(f"catalogue:pendulum.action:{label}", (lambda n=n, args=args: pendulum.action(n, **args)), names=names))
    probes.append(Probe("catalogue:pendulum.step:T_prev = −T_curr",
                        _bind(pendulum.step, np.array([1.0, 0, 0]), np.array([-1.0, 0, 0]), np.array([0, 0, -1.0])),
                        expect="finite_or_raises"))
    probes.append(Probe("catalogue:pendulum.step:nan load",
                        _bind(pendulum.step, np.array([1.0, 0, 0]), np.array([0.0, 1, 0]), np.array([np.nan, 0, 0])),
                        names=(r"\ba\b", r"load", r"nan")))

    probes.append(Probe("catalogue:heisenberg.hamiltonian:kind bogus", _bind(heisenberg.hamiltonian, "classical"), names=(r"kind",)))
    probes.append(Probe("catalogue:heisenberg.hamiltonian:J nan", _bind(heisenberg.hamiltonian, "naive", J=np.nan), names=(r"\bJ\b",)))
    S = np.tile(e3, (6, 1))
    S[3] = -e3
    H = heisenberg.hamiltonian("integrable")
    probes.append(Probe("catalogue:heisenberg integrable:antiparallel spins 2, 3", _bind(H, S), names=(r"\b[23]\b",)))
    S2 = np.tile(e3, (6, 1))
    S2[3] = 2 * e3
    probes.append(Probe("catalogue:heisenberg integrable:spin 3 not unit", _bind(H, S2), expect="finite_or_raises"))

    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]])
    w = np.ones(5)

    def dg_(label, names, *args, **kw):
        probes.append(Probe(f"catalogue:dirichlet.graph:{label}", _bind(dirichlet.graph, *args, **kw), names=names))

    dg_("edge 2 to a missing vertex", (r"edge\D{0,20}2\b", r"vert"), np.array([[0, 1], [1, 2], [2, 9], [3, 0]]), np.ones(4), [0], [1.0], n_vertices=4)
    dg_("negative vertex index", (r"edge",), np.array([[0, 1], [1, -2]]), np.ones(2), [0], [1.0])
    dg_("weight nan", (r"weight",), edges, np.where(np.arange(5) == 2, np.nan, w), [0], [1.0])
    dg_("weights of the wrong count", (r"weight", r"shape"), edges, w[:4], [0], [1.0])
    dg_("boundary vertex out of range", (r"boundary",), edges, w, [0, 7], [1.0, 2.0])
    dg_("boundary and values differ in length", (r"boundary", r"values"), edges, w, [0, 1], [1.0])
    dg_("value nan", (r"value",), edges, w, [0, 1], [1.0, np.nan])
    dg_("repeated boundary vertex", (r"boundary", r"repeat", r"twice"), edges, w, [0, 0], [1.0, 2.0])

    V, F = probe_meshes()["open"]
    bd = np.asarray(__import__("ddgjax").mesh.boundary_vertices(F))
    probes.append(Probe("catalogue:dirichlet.cotan:values nan", _bind(dirichlet.cotan, V, F, bd, np.full(len(bd), np.nan)), names=(r"value",)))
    probes.append(Probe("catalogue:dirichlet.cotan:boundary out of range", _bind(dirichlet.cotan, V, F, np.r_[bd, len(V)], np.ones(len(bd) + 1)),
                        names=(r"boundary", r"vert")))
    probes.append(Probe("catalogue:area.simplicial:boundary out of range", _bind(area.simplicial, V, F, np.r_[bd, len(V) + 3]),
                        names=(r"boundary", r"vert")))
    V2 = V.copy()
    V2[3] = np.nan
    probes.append(Probe("catalogue:area.simplicial:vertex 3 nan", _bind(area.simplicial, V2, F, bd), names=VERTEX))
    Vc, Fc = probe_meshes()["closed"]
    for vol in (0.0, -1.0, np.nan, np.inf):
        probes.append(Probe(f"catalogue:area.with_volume:volume {vol}", _bind(area.with_volume, Vc, Fc, vol), names=(r"volume",)))
    for label, kw, names in (("kappa nan", dict(kappa=np.nan), (r"kappa",)), ("kappa negative", dict(kappa=-1.0), (r"kappa",)),
                             ("H0 nan", dict(H0=np.nan), (r"H0",)), ("area negative", dict(area=-1.0), (r"area",)),
                             ("volume nan", dict(volume=np.nan), (r"volume",))):
        probes.append(Probe(f"catalogue:willmore.helfrich:{label}", _bind(willmore.helfrich, Vc, Fc, **kw), names=names))
    Vn = Vc.copy()
    Vn[3, 0] = np.nan
    probes.append(Probe("catalogue:willmore.conformal:vertex 3 nan", _bind(willmore.conformal, Vn, Fc), names=VERTEX))
    probes.append(Probe("catalogue:willmore.helfrich:open mesh", _bind(willmore.helfrich, V, F), expect="finite_or_raises"))
    for value, why in ((np.nan, "nan"), (np.inf, "inf")):
        probes.append(Probe(f"catalogue:elastica.loaded:load {why}", _bind(elastica.loaded, 8, load=value), names=(r"load",)))
        probes.append(Probe(f"catalogue:rod.loaded:twist {why}", _bind(rod.loaded, 8, alpha=1.0, twist=value), names=(r"twist",)))
        probes.append(Probe(f"catalogue:rod.loaded:load {why}", _bind(rod.loaded, 8, alpha=1.0, load=value), names=(r"load",)))
    probes.append(Probe("catalogue:elastica.loaded:load shape (2,)", _bind(elastica.loaded, 8, load=[1.0, 2.0]), names=(r"load",)))
    probes.append(Probe("catalogue:rod.loaded:twist shape (2,)", _bind(rod.loaded, 8, alpha=1.0, twist=[1.0, 2.0]),
                        names=(r"twist",)))
    for n in (0, 2, 2.5, np.nan):
        probes.append(Probe(f"catalogue:elastica.loaded:n = {n!r}", _bind(elastica.loaded, n), names=(r"\bn\b",)))
        probes.append(Probe(f"catalogue:rod.loaded:n = {n!r}", _bind(rod.loaded, n, alpha=1.0), names=(r"\bn\b",)))
    for d, why in (((0, 0, 0), "zero"), ((np.nan, 1, 0), "nan"), ((1, 0), "shape (2,)")):
        probes.append(Probe(f"catalogue:elastica.loaded:direction {why}", _bind(elastica.loaded, 8, direction=d),
                            names=(r"direction",)))
    Vb, Fb, Cb = __import__("ddgjax").mesh.double_bubble(12, 3, 2)
    for vols, why, names in (([1.0, np.nan], "volume nan", (r"volumes\[1\]",)), ([1.0, -1.0], "volume negative", (r"volumes\[1\]",)),
                             ([1.0], "one volume for two chambers", (r"volumes",))):
        probes.append(Probe(f"catalogue:area.with_volumes:{why}", _bind(area.with_volumes, Vb, Fb, Cb, vols), names=names))
    probes.append(Probe("catalogue:area.with_volumes:chambers reversed", _bind(area.with_volumes, Vb, Fb, -Cb, [1.0, 1.0]),
                        names=(r"chamber 0",)))
    probes.append(Probe("catalogue:area.with_volumes:chambers shape", _bind(area.with_volumes, Vb, Fb, Cb[:-1], [1.0, 1.0]),
                        names=(r"chambers",)))
    Vbn = Vb.copy()
    Vbn[3, 1] = np.nan
    probes.append(Probe("catalogue:area.with_volumes:vertex 3 nan", _bind(area.with_volumes, Vbn, Fb, Cb, [1.0, 1.0]), names=VERTEX))
    return probes


def _circle_tangents(n):
    t = 2 * np.pi * (np.arange(n) + 0.5) / n
    return np.stack([-np.sin(t), np.cos(t), np.zeros(n)], axis=1)


# ---------------------------------------------------------------------------------- solve


def solve_probes() -> list[Probe]:
    import jax
    import jax.numpy as jnp
    from energies import elastica
    from solvers import solve

    import ddgjax as dg

    sphere = dict(energy=lambda x, p: jnp.sum(jnp.array([3.0, 1.0, 2.0]) * x * x),
                  constraints=lambda x, p: jnp.array([x @ x - 1.0]))
    x0 = np.array([0.3, 1.0, 0.2])

    def P(**kw):
        args = {**sphere, "x0": x0, **kw}
        return dg.Problem(args.pop("energy"), args.pop("x0"), **args)

    probes = []

    def sp(label, call, names=(), expect="raises", expected=None, error=None):
        probes.append(Probe(f"solve:{label}", call, names=names, expect=expect, expected=expected, error=error))

    sp("x0 with nan at 1", lambda: solve(P(x0=np.array([0.3, np.nan, 0.2]))), names=(r"x0", r"\b1\b"))
    sp("x0 a 0-d nan", lambda: solve(dg.Problem(lambda x, p: (x - 1.0) ** 2, np.float64(np.nan))), names=(r"x0",))
    sp("params a 0-d nan", lambda: solve(dg.Problem(lambda x, p: (x - p) ** 2, np.array([0.0]), params=np.float64(np.nan))),
       names=(r"params",))
    sp("params with inf", lambda: solve(dg.Problem(lambda x, p: jnp.sum((x - p) ** 2), np.zeros(2), params=np.array([1.0, np.inf]))),
       names=(r"params",))
    sp("energy not scalar", lambda: solve(dg.Problem(lambda x, p: x * x, np.ones(3))), names=(r"scalar", r"shape"))
    sp("energy nan at x0", lambda: solve(dg.Problem(lambda x, p: jnp.sum(jnp.log(x)), np.array([1.0, -1.0]))), names=(r"energy", r"x0", r"start"))
    sp("energy nan beyond x0", lambda: solve(dg.Problem(lambda x, p: jnp.sum(jnp.sqrt(1.0 - x) + (x - 3.0) ** 2), np.array([0.5, 0.5]))),
       names=(r"energy", r"finite", r"converge", r"nan"))
    for tol in (0.0, -1e-10, np.nan, np.inf):
        sp(f"tol {tol}", lambda tol=tol: solve(P(), tol=tol), names=(r"tol",))
    for ms in (-1, 1.5, np.nan):
        sp(f"max_steps {ms}", lambda ms=ms: solve(P(), max_steps=ms), names=(r"max_steps",))
    sp("method bogus", lambda: solve(P(), method="cholesky"), names=(r"method",))
    sp("linear_solver bogus", lambda: solve(P(), linear_solver="klu"), names=(r"linear_solver",))
    sp("warm_start bogus", lambda: solve(P(), warm_start="yes"), names=(r"warm_start",))
    sp("fixed of the wrong shape", lambda: solve(P(fixed=np.array([True, False]))), names=(r"fixed", r"shape"))
    sp("constraints nan at x0", lambda: solve(P(constraints=lambda x, p: jnp.array([jnp.log(x[0] - 1.0)]))), names=(r"constraint", r"x0", r"start"))
    sp("constraints not 1-D", lambda: solve(P(constraints=lambda x, p: jnp.stack([x, x]))), expect="finite_or_raises")
    sp("infeasible constraints", lambda: solve(P(constraints=lambda x, p: jnp.array([x @ x + 1.0]))), names=(r"converge", r"residual", r"feasib"))
    sp("unbounded energy", lambda: solve(dg.Problem(lambda x, p: jnp.sum(x), np.zeros(3))), names=(r"converge", r"residual", r"critical", r"singular"))
    sp("more independent constraints than unknowns",
       lambda: solve(P(constraints=lambda x, p: jnp.array([x[0] - 0.1, x[1] - 0.2, x[2] - 0.3, x @ x - 1.0]))),
       names=(r"constraint", r"converge", r"overconstrained", r"unknowns"))
    sp("throw=False on an infeasible problem: converged is False",
       lambda: _not_converged_flag(solve(P(constraints=lambda x, p: jnp.array([x @ x + 1.0])), throw=False)),
       expect="value", expected=lambda: 0.0)
    sp("grad through a solve that did not converge is nan",
       lambda: _finite_fraction(jax.grad(lambda p: solve(dg.Problem(lambda x, p: jnp.sum(x) * p, np.zeros(2), params=p),
                                                       throw=False).energy)(1.0)),
       expect="value", expected=lambda: 0.0)
    sp("rod from zero frames", lambda: solve(_rod_with_x0(np.zeros((8, 4)))), names=(r"x0", r"frame", r"converge", r"unit", r"zero", r"singular"))
    sp("elastica with length inf", lambda: solve(elastica.clamped(8, length=np.inf, chord=(0.5, 0, 0), t_start=(1.0, 0, 0), t_end=(0, 1.0, 0))),
       names=(r"length",))
    sp("elastica Euler buckling start (t_start = t_end ∥ chord)",
       lambda: _residual(solve(elastica.clamped(16, chord=(0.9, 0, 0), t_start=(1.0, 0, 0), t_end=(1.0, 0, 0)))),
       expect="value", expected=lambda: 0.0, )
    sp("rod from zero frames, throw=False", lambda: _not_converged_flag(solve(_rod_with_x0(np.zeros((8, 4))), throw=False)),
       names=(r"x0", r"frame", r"converge", r"unit", r"zero", r"singular"), expect="raises")
    for method in ("dense", "sparse", "krylov"):
        sp(f"elastica from a nan start, method={method}",
           lambda method=method: solve(elastica.clamped(8, chord=(0.5, 0.2, 0), t_start=(1.0, 0, 0), t_end=(0, 1.0, 0),
                                                        x0=np.where(np.arange(8)[:, None] == 3, np.nan, 1.0) * np.ones((8, 3))),
                                       method=method), names=(r"x0", r"\b3\b"))
    x0_kept = np.array([0.3, 1.0, 0.2])
    probes.append(Probe("solve:x0 is not modified", lambda: _residual(solve(P(x0=x0_kept))), expect="value",
                        expected=lambda: 0.0, inputs=(x0_kept,)))
    sp("multipliers0 of the wrong shape", lambda: solve(P(), multipliers0=np.zeros(3)), names=(r"multipliers0", r"shape"))
    sp("multipliers0 nan", lambda: solve(P(), multipliers0=np.array([np.nan])), names=(r"multipliers",))
    sp("x0 integer dtype", lambda: _residual(solve(dg.Problem(lambda x, p: jnp.sum((x - 0.5) ** 2), np.array([1, 2, 3])))),
       expect="value", expected=lambda: 0.0)
    sp("energy with a huge scale 1e150", lambda: _rel_x(solve(dg.Problem(lambda x, p: 1e150 * jnp.sum((x - 0.5) ** 2), np.zeros(3), )), 0.5),
       expect="value", expected=lambda: 0.0)
    # the stopping test is absolute (|∇E − Jᵀλ| ≤ tol): a tiny energy scale is declared by residual_scale
    sp("energy with a tiny scale 1e-150 and its residual_scale", lambda: _rel_x(solve(dg.Problem(
        lambda x, p: 1e-150 * jnp.sum((x - 0.5) ** 2), np.zeros(3), residual_scale=(1e150, 1.0))), 0.5),
       expect="value", expected=lambda: 0.0)
    sp("diagonal quadratic, condition 1e14", lambda: _rel_x(solve(dg.Problem(
        lambda x, p: 0.5 * jnp.sum(jnp.array([1.0, 1e-7, 1e-14]) * x * x) - jnp.sum(jnp.array([1.0, 1e-7, 1e-14]) * x), np.zeros(3))), 1.0),
       expect="value", expected=lambda: 0.0)
    return probes


def _not_converged_flag(sol):
    return float(bool(sol.converged))


def _finite_fraction(g):
    return float(np.mean(np.isfinite(np.asarray(g))))


def _residual(sol):
    return 0.0 if float(sol.residual) <= 1e-10 and bool(sol.converged) else float(sol.residual) + 1.0


def _rel_x(sol, want):
    x = np.asarray(sol.x, float)
    return float(np.max(np.abs(x - want)) / abs(want)) if np.max(np.abs(x - want)) > 1e-9 * abs(want) else 0.0


def _rod_with_x0(x0):
    from energies import rod

    from ddgjax.quaternion import from_axis_angle

    q0 = np.asarray(from_axis_angle(np.array([0, 0, 1.0]), 0.3))
    q1 = np.asarray(from_axis_angle(np.array([0, 0, 1.0]), -0.3))
    x0 = x0.copy()
    x0[0], x0[-1] = q0, q1
    return rod.clamped(8, alpha=0.7, chord=(0.6, 0, 0), frame_start=q0, frame_end=q1, x0=x0)


# ---------------------------------------------------------------------------------- flows


def flow_probes() -> list[Probe]:
    import jax.numpy as jnp

    import ddgjax as dg

    problem = dg.Problem(lambda x, p: jnp.sum(x**2), np.ones(3), constraints=lambda x, p: jnp.array([x @ x - 3.0]))
    f = dg.gradient_flow(problem)
    probes = [
        Probe("flows:gradient_flow:x of the wrong shape", _bind(f, np.ones(4)), names=(r"shape",)),
        Probe("flows:gradient_flow:x with nan", _bind(f, np.array([1.0, np.nan, 1.0])), expect="finite_or_raises"),
    ]
    g = lambda x: -x  # noqa: E731
    for label, kw, names in (("t1 nan", dict(t1=np.nan), (r"t1",)), ("t1 inf", dict(t1=np.inf), (r"t1",)),
                             ("steps 0", dict(t1=1.0, steps=0), (r"steps",)), ("steps -3", dict(t1=1.0, steps=-3), (r"steps",)),
                             ("rtol nan", dict(t1=1.0, rtol=np.nan), (r"rtol",)), ("rtol 0", dict(t1=1.0, rtol=0.0), (r"rtol",)),
                             ("x0 nan", dict(t1=1.0, x0=np.array([np.nan, 1.0])), (r"x0",)),
                             ("method bogus", dict(t1=1.0, method="euler-ish"), (r"method",)),
                             ("saves 0", dict(t1=1.0, saves=0), (r"saves",))):
        x0 = kw.pop("x0", np.ones(2))
        probes.append(Probe(f"flows:integrate:{label}", (lambda x0=x0, kw=kw: dg.integrate(g, x0, **kw)), names=names))
    S = np.tile(np.eye(3)[2], (5, 1))
    probes.append(Probe("flows:spin_poisson:spins of shape (5, 2)",
                        _bind(lambda: dg.hamiltonian_flow(lambda S: jnp.sum(S[:-1] * S[1:]), dg.spin_poisson)(S[:, :2])),
                        names=(r"shape",)))
    return probes


# ---------------------------------------------------------------------------------- quaternions


def quaternion_probes() -> list[Probe]:
    from ddgjax import quaternion as qt

    return [
        Probe("quaternion:from_axis_angle:zero axis", _bind(qt.from_axis_angle, np.zeros(3), 0.3), names=(r"axis",)),
        Probe("quaternion:from_axis_angle:nan angle", _bind(qt.from_axis_angle, np.array([0, 0, 1.0]), np.nan), names=(r"angle",)),
        Probe("quaternion:inv:zero", _bind(qt.inv, np.zeros(4)), names=(r"zero", r"q", r"invert")),
        Probe("quaternion:from_matrix:not a rotation", _bind(qt.from_matrix, 2 * np.eye(3)), names=(r"rotation", r"orthogonal", r"R")),
        Probe("quaternion:from_matrix:a reflection", _bind(qt.from_matrix, np.diag([1.0, 1.0, -1.0])), names=(r"rotation", r"det", r"R")),
        Probe("quaternion:from_matrix:nan", _bind(qt.from_matrix, np.full((3, 3), np.nan)), names=(r"nan", r"finite", r"R")),
        Probe("quaternion:rotate:v of shape (2,)", _bind(qt.rotate, np.array([1.0, 0, 0, 0]), np.ones(2)), names=(r"shape",)),
        Probe("quaternion:mul:shape (3,)", _bind(qt.mul, np.ones(3), np.ones(4)), names=(r"shape",)),
    ]


# ---------------------------------------------------------------------------------- files


def file_probes(folder: Path) -> list[Probe]:
    from ddgjax import mesh

    def write(name, content):
        p = folder / name
        p.write_bytes(content if isinstance(content, bytes) else content.encode())
        return p

    tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n"
    cases = {
        "obj": {
            "empty": "", "no faces": "v 0 0 0\nv 1 0 0\n", "index out of range": tri + "f 1 2 9\n",
            "index zero": tri + "f 0 1 2\n", "nan coordinate": tri.replace("v 1 0 0", "v nan 0 0"),
            "text in a coordinate": tri.replace("v 1 0 0", "v one 0 0"), "two-vertex face": tri + "f 1 2\n",
            "binary garbage": bytes(range(256)) * 4, "truncated vertex": "v 0 0 0\nv 1 0\nf 1 2 1\n",
        },
        "off": {
            "empty": "", "huge counts": "OFF\n3000000000 1 0\n0 0 0\n", "truncated": "OFF\n4 4 0\n0 0 0\n1 0 0\n",
            "negative count": "OFF\n-4 1 0\n", "index out of range": "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
            "nan coordinate": "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "not a header": "OF\n3 1 0\n",
            "face count mismatch": "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "binary garbage": bytes(range(256)) * 4,
        },
        "ply": {
            "empty": "", "huge vertex count": "ply\nformat ascii 1.0\nelement vertex 3000000000\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
            "truncated binary": "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\x00\x00",
            "index out of range": "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
            "garbage header": "ply\nformat ascii 1.0\nelement vertex three\nend_header\n", "binary garbage": b"ply\n" + bytes(range(256)) * 4,
        },
        "stl": {
            "empty": "", "huge binary count": b"\x00" * 80 + (3_000_000_000).to_bytes(4, "little") + b"\x00" * 50,
            "truncated ascii": "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n",
            "nan ascii": "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n",
            "binary garbage": bytes(range(256)) * 4,
        },
        "vtk": {
            "empty": "", "huge points": "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3000000000 float\n0 0 0\n",
            "truncated": "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0\n",
            "index out of range": "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
            "POLYGONS 1 4\n3 0 1 9\n",
            "binary garbage": b"# vtk DataFile Version 3.0\n" + bytes(range(256)) * 4,
        },
    }
    probes = []
    for ext, files in cases.items():
        for label, content in files.items():
            path = write(f"{label.replace(' ', '_')}.{ext}", content)
            probes.append(Probe(f"files:{ext}:{label}", _bind(mesh.read, str(path)), names=(re.escape(path.name),)))
    probes.append(Probe("files:missing file", _bind(mesh.read, str(folder / "nope.obj")), names=(r"nope\.obj",)))
    probes.append(Probe("files:a folder", _bind(mesh.read, str(folder)), names=(re.escape(folder.name),)))
    probes.append(Probe("files:unknown extension", _bind(mesh.read, str(write("mesh.xyz", "1 2 3\n"))), names=(r"mesh\.xyz",)))
    obj_vt = ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
              "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/1/1\nf 1//1 4//1 2//1\nf 2/2 4/1 3/3\n")
    path = write("textured.obj", obj_vt)
    probes.append(Probe("files:obj with texture and normal indices", _bind(_faces_of, path), expect="value",
                        expected=lambda: np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]], float)))
    path = write("mixed.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\nf 1 2 3 4\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n")
    probes.append(Probe("files:mixed triangles and a quad, triangulated", _bind(_triangle_count, path), expect="value",
                        expected=lambda: 6.0))
    return probes


def _faces_of(path):
    from ddgjax import mesh

    return np.asarray(mesh.read(str(path))[1], float)


def _triangle_count(path):
    from ddgjax import mesh

    V, F = mesh.read(str(path))
    return float(len(mesh.triangulate(F)))


# ---------------------------------------------------------------------------------- command line


def cli_probes(folder: Path) -> list[Probe]:
    bad_mesh = folder / "bad.off"
    bad_mesh.write_text("OFF\n3 1 0\n0 0 0\n")
    cases = {
        "unknown command": ["frobnicate"],
        "solve unknown object": ["solve", "teapot"],
        "solve elastica --n -3": ["solve", "elastica", "--n", "-3"],
        "solve elastica --n abc": ["solve", "elastica", "--n", "abc"],
        "verify --jobs 0": ["verify", "--quick", "--jobs", "0"],
        "verify --only nothing-matches": ["verify", "--only", "no-such-check-xyz"],
        "verify --out /proc/x": ["verify", "--quick", "--only", "gauss_bonnet", "--out", "/proc/x"],
        "a malformed --mesh": ["solve", "minimal-surface", "--mesh", str(bad_mesh)],
        "a missing --mesh": ["solve", "minimal-surface", "--mesh", str(folder / "missing.obj")],
        "sweep with a bad --param": ["sweep", "elastica", "--param", "chord=a:b:c", "--out", str(folder / "s.h5")],
        "sweep-plot of a missing file": ["sweep-plot", str(folder / "none.h5")],
    }
    return [Probe(f"cli:{label}", _bind(_cli_exit, args), expect="value", expected=lambda: 2.0) for label, args in cases.items()]


def _cli_exit(args) -> float:
    """2.0 when the command exits with code 2 and one line of error (no traceback), else a
    code that says what went wrong (1000 + exit code, or −lines printed to stderr)."""
    out = subprocess.run([sys.executable, "-m", "ddgjax", *args], capture_output=True, text=True, timeout=TIME_LIMIT_S,
                         env={**os.environ, "DDGJAX_COMPILE_CACHE": os.environ.get("DDGJAX_COMPILE_CACHE", "off")})
    lines = [l for l in out.stderr.splitlines() if l.strip()]
    if out.returncode != 2:
        return 1000.0 + out.returncode
    if len(lines) != 1 or "Traceback" in out.stderr:
        return -float(len(lines))
    return 2.0


# ---------------------------------------------------------------------------------- all of them

FAMILIES = ("mesh", "topology", "intrinsic", "curves", "catalogue", "solve", "flows", "quaternion", "files", "cli")


def all_probes(folder: Path) -> list[Probe]:
    makers = {"mesh": mesh_probes, "topology": topology_probes, "intrinsic": intrinsic_probes, "curves": curve_probes,
              "catalogue": catalogue_probes, "solve": solve_probes, "flows": flow_probes, "quaternion": quaternion_probes,
              "files": lambda: file_probes(folder), "cli": lambda: cli_probes(folder)}
    probes = [p for name in FAMILIES for p in makers[name]()]
    ids = [p.id for p in probes]
    assert len(ids) == len(set(ids)), [i for i in ids if ids.count(i) > 1][:5]
    return probes


def _peak_rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM"):
                return int(line.split()[1]) / 1024
    return 0.0


def _reset_peak():
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


def _worker(folder: str):
    """Read probe ids from stdin, print one JSON line per probe."""
    probes = {p.id: p for p in all_probes(Path(folder))}
    print(json.dumps({"ready": True}), flush=True)
    for line in sys.stdin:
        pid = line.rstrip("\n")
        if pid == "__exit__":  # the control of crash detection (tests/test_probes.py)
            os._exit(3)
        _reset_peak()
        base = _peak_rss_mb()
        t0 = time.perf_counter()
        outcome, detail = judge(probes[pid])
        grown = _peak_rss_mb() - base
        if outcome == "ok" and grown > MEMORY_MB:
            outcome, detail = "memory", f"peak resident memory grew by {grown:.0f} MB"
        print(json.dumps({"id": pid, "outcome": outcome, "detail": detail, "s": time.perf_counter() - t0}), flush=True)


class _Isolated:
    """One worker process; a probe that kills it or overruns the time limit is recorded as such."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.proc = None

    def start(self):
        self.proc = subprocess.Popen([sys.executable, __file__, "--worker", str(self.folder)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, bufsize=1)
        assert json.loads(self.proc.stdout.readline()).get("ready")

    def run(self, pid: str) -> dict:
        import selectors

        if self.proc is None or self.proc.poll() is not None:
            self.start()
        self.proc.stdin.write(pid + "\n")
        self.proc.stdin.flush()
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        if not sel.select(TIME_LIMIT_S):
            self.proc.kill()
            self.proc.wait()
            self.proc = None
            return {"id": pid, "outcome": "hang", "detail": f"no answer in {TIME_LIMIT_S} s"}
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            self.proc = None
            return {"id": pid, "outcome": "crash", "detail": f"the process ended with code {code}"}
        return json.loads(line)


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default="", help="run the probes whose id contains this")
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--in-process", action="store_true", help="no worker process (no crash/hang/memory detection)")
    ap.add_argument("--worker", metavar="FOLDER")
    ap.add_argument("--json", metavar="FILE", help="write every outcome to FILE")
    args = ap.parse_args(argv)
    if args.worker:
        _worker(args.worker)
        return 0
    with tempfile.TemporaryDirectory(prefix="ddgjax-probes-") as tmp:
        folder = Path(tmp)
        probes = [p for p in all_probes(folder) if args.only in p.id]
        if args.list:
            for p in probes:
                print(p.id)
            return 0
        runner = None if args.in_process else _Isolated(folder)
        results = []
        t0 = time.perf_counter()
        for p in probes:
            if runner is None:
                outcome, detail = judge(p)
                r = {"id": p.id, "outcome": outcome, "detail": detail}
            else:
                r = runner.run(p.id)
            r["family"] = p.family
            results.append(r)
            if r["outcome"] != "ok":
                print(f"  {r['outcome']:8s} {r['id']}: {r['detail']}", flush=True)
        if runner is not None and runner.proc is not None:
            runner.proc.kill()
    _table(results, time.perf_counter() - t0)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0 if all(r["outcome"] == "ok" for r in results) else 1


def _table(results, seconds):
    outcomes = ("ok", "silent", "wrong", "foreign", "unnamed", "mutated", "crash", "hang", "memory")
    print(f"\n| family | probes | {' | '.join(outcomes)} |")
    print("|---|---:|" + "---:|" * len(outcomes))
    for fam in FAMILIES + ("all",):
        rows = [r for r in results if fam == "all" or r["family"] == fam]
        if rows:
            counts = [sum(r["outcome"] == o for r in rows) for o in outcomes]
            print(f"| {fam} | {len(rows)} | " + " | ".join(str(c) for c in counts) + " |")
    print(f"\n{len(results)} probes in {seconds:.0f} s")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    sys.exit(main())
