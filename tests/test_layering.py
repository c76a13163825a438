"""The layers of the product import only downwards (../shared/STYLE.md, "Our layout").

Every `import` statement of every module is read from its syntax tree, including imports inside
functions (a lazy import is still a dependency), and resolved to the module it names.

    language (problem, locality, flows, limits, errors)  <  geometry (curves, quaternion, frames,
    mesh, intrinsic, laplace)  <  smooth references  <  output (plot; the package facade
    `import ddgjax`, which loads the layers up to here)  <  application (verify, cli)

`energies/` sees every layer of `ddgjax` but the application; `solvers/` sees only the language
(it knows nothing of curves or meshes) and never `energies/`.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

LANGUAGE, GEOMETRY, SMOOTH, OUTPUT, APPLICATION, SOLVERS, ENERGIES = range(7)
LAYER_NAMES = ["language", "geometry", "smooth reference", "output", "application", "solvers", "energies"]

# Module prefixes, longest match wins.
LAYER_OF_PREFIX = {
    "ddgjax.problem": LANGUAGE,
    "ddgjax.locality": LANGUAGE,
    "ddgjax.flows": LANGUAGE,
    "ddgjax.limits": LANGUAGE,
    "ddgjax.errors": LANGUAGE,
    "ddgjax._checks": LANGUAGE,
    "ddgjax._flat": LANGUAGE,
    "ddgjax._host": LANGUAGE,
    "ddgjax.curves": GEOMETRY,
    "ddgjax.quaternion": GEOMETRY,
    "ddgjax.frames": GEOMETRY,
    "ddgjax.mesh": GEOMETRY,
    "ddgjax.intrinsic": GEOMETRY,
    "ddgjax.laplace": GEOMETRY,
    "ddgjax.csr_assembly": GEOMETRY,
    "ddgjax.smooth": SMOOTH,
    "ddgjax.plot": OUTPUT,
    "ddgjax.verify": APPLICATION,
    "ddgjax.cli": APPLICATION,
    "ddgjax.sweep": APPLICATION,
    "ddgjax.compile_cache": APPLICATION,
    "ddgjax.__main__": APPLICATION,
    "ddgjax": OUTPUT,  # the package facade: imports the language, geometry, smooth and output layers
    "solvers": SOLVERS,
    "energies": ENERGIES,
}

# What each layer may import (besides third-party packages).
ALLOWED = {
    LANGUAGE: {LANGUAGE},
    GEOMETRY: {LANGUAGE, GEOMETRY},
    SMOOTH: {LANGUAGE, GEOMETRY, SMOOTH},
    OUTPUT: {LANGUAGE, GEOMETRY, SMOOTH, OUTPUT},
    APPLICATION: {LANGUAGE, GEOMETRY, SMOOTH, OUTPUT, APPLICATION, SOLVERS, ENERGIES},
    SOLVERS: {LANGUAGE, SOLVERS},
    ENERGIES: {LANGUAGE, GEOMETRY, SMOOTH, OUTPUT, SOLVERS, ENERGIES},
}

# Justified exceptions: (importing module, imported module) -> why.
EXCEPTIONS = {
    # `ConvergenceTable.plot(path)` is public API (../shared/API.md); the figure is drawn by the
    # output layer, loaded only when called.
    ("ddgjax.limits", "ddgjax.plot.lines"): "ConvergenceTable.plot delegates to the output layer",
    # `import ddgjax` in solvers switches on float64 before anything is traced; it is the
    # package's only global setting, not a use of any layer.
    ("solvers", "ddgjax"): "float64 switch",
}


def layer_of(module: str) -> int | None:
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        prefix = ".".join(parts[:k])
        if prefix in LAYER_OF_PREFIX:
            return LAYER_OF_PREFIX[prefix]
    return None


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in the file, relative ones resolved; for
    `from pkg import name` both `pkg.name` (if it is a module of ours) and `pkg` count."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                is_module = (ROOT / Path(*sub.split("."))).is_dir() or (ROOT / Path(*sub.split("."))).with_suffix(".py").exists()
                out.append((node.lineno, sub if is_module else target))
    return out


def violations(path: Path) -> list[str]:
    me = module_name(path)
    mine = layer_of(me)
    found = []
    for line, target in imported_modules(path):
        theirs = layer_of(target)
        if theirs is None or theirs in ALLOWED[mine]:
            continue
        if any(me.startswith(a) and target == b for a, b in EXCEPTIONS):
            continue
        found.append(f"{path.relative_to(ROOT)}:{line}: {me} ({LAYER_NAMES[mine]}) imports {target} ({LAYER_NAMES[theirs]})")
    return found


def product_files() -> list[Path]:
    return sorted(p for package in ("ddgjax", "energies", "solvers") for p in (ROOT / package).rglob("*.py"))


def test_every_product_module_has_a_layer():
    assert [str(p) for p in product_files() if layer_of(module_name(p)) is None] == []


def test_layers_import_only_downwards():
    assert [v for p in product_files() for v in violations(p)] == []


@pytest.mark.parametrize(
    "module, source",
    [
        ("ddgjax/mesh/_probe.py", "from energies import elastica\n"),
        ("ddgjax/intrinsic/_probe.py", "def f():\n    from solvers import solve\n"),
        ("ddgjax/_probe_geometry.py", "from . import plot\n"),
        ("ddgjax/laplace_probe.py", "import solvers._krylov\n"),
        ("solvers/_probe.py", "from ddgjax.mesh import icosphere\n"),
        ("solvers/_probe.py", "from energies.area import simplicial\n"),
    ],
)
def test_negative_control_an_upward_import_is_reported(tmp_path, monkeypatch, module, source):
    """A geometry module importing energies or solvers (even lazily), or solvers importing a
    mesh or the catalogue, is a violation."""
    fake_root = tmp_path
    path = fake_root / module
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(source)
    monkeypatch.setitem(globals(), "ROOT", fake_root)
    if module == "ddgjax/_probe_geometry.py":  # classify the probe as geometry
        monkeypatch.setitem(LAYER_OF_PREFIX, "ddgjax._probe_geometry", GEOMETRY)
    if module == "ddgjax/laplace_probe.py":
        monkeypatch.setitem(LAYER_OF_PREFIX, "ddgjax.laplace_probe", GEOMETRY)
    (fake_root / "ddgjax" / "plot").mkdir(parents=True, exist_ok=True)
    assert len(violations(path)) == 1
