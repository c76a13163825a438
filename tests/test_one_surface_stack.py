"""One surface stack: one connectivity type, and no cotangent formula typed into the library:
the Laplacians are derived from the Dirichlet energy by autodiff (Thm 6.6), the flip loop's
angle criterion from the same energy by polarisation (`lengths.polarised_cotangents`).

Read from the syntax trees and the source of `ddgjax/`, `energies/` and `solvers/`."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted(p for package in ("ddgjax", "energies", "solvers") for p in (ROOT / package).rglob("*.py"))

# b² + c² − a² written out, in any of the usual spellings
LAW_OF_COSINES = re.compile(r"\w+2 \+ \w+2 - \w+2|\w+ \* \w+ \+ \w+ \* \w+ - \w+ \* \w+|\w+\*\*2 \+ \w+\*\*2 - \w+\*\*2")
ALLOWED = {
    ("ddgjax/mesh/lengths.py", "dirichlet_form"),  # Sec 6.3: the Gram matrix of the edges, e1·e2 from lengths
    ("ddgjax/intrinsic/geometry.py", "apex"),  # Lemma 5.8: unfolding a triangle into the plane
}


def connectivity_classes(path: Path) -> list[str]:
    """Classes that hold halfedge gluing arrays as their own fields (`twin` or `halfedges`)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ClassDef):
            fields = {s.target.id for s in node.body if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)}
            if fields & {"twin", "halfedges", "next"}:
                found.append(node.name)
    return found


def law_of_cosines_sites(path: Path) -> list[tuple[str, str]]:
    """(file, enclosing function) of every line that writes out b² + c² − a²."""
    source = path.read_text()
    functions = [n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.FunctionDef)]
    sites = []
    for number, line in enumerate(source.splitlines(), start=1):
        code = line.split("#")[0]
        if LAW_OF_COSINES.search(code) and not code.strip().startswith(('"', "cot", "h(")):
            owner = min((f for f in functions if f.lineno <= number <= f.end_lineno),
                        key=lambda f: f.end_lineno - f.lineno, default=None)
            sites.append((str(path.relative_to(ROOT)), owner.name if owner else "<module>"))
    return sites


def test_one_connectivity_type():
    # the flip loop works on the flat arrays of one `Halfedges` and turns them back into one
    # (`triangulation.of_arrays`); it has no class of its own
    assert sorted(c for p in SOURCES for c in connectivity_classes(p)) == ["Halfedges"]


def test_no_cotangent_formula_in_the_library():
    sites = {s for p in SOURCES for s in law_of_cosines_sites(p)}
    assert sites <= ALLOWED, sites - ALLOWED


def test_negative_controls(tmp_path, monkeypatch):
    """A second halfedge class and a typed-in cotan weight are both found."""
    monkeypatch.setitem(globals(), "ROOT", tmp_path)
    path = tmp_path / "probe.py"
    path.write_text("class Mesh:\n    twin: object\n\n\ndef w(a, b, c, A):\n    return (b * b + c * c - a * a) / (8 * A)\n")
    assert connectivity_classes(path) == ["Mesh"]
    assert law_of_cosines_sites(path) == [("probe.py", "w")]
