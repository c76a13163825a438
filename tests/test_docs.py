"""The documentation site (mkdocs.yml, docs/) builds, and its code runs.

(a) `mkdocs build --strict` succeeds: every page, link, anchor and API identifier resolves, and
    the API reference (mkdocstrings, from the docstrings) holds the public names of the library.
    Negative controls: a copy of the configuration building one page with a link to a missing
    page, or with a reference to a missing API identifier, fails.  Skipped when mkdocs is not
    installed (`pip install -e '.[docs]'`).
(b) Every ```python block of docs/ runs against the library: the blocks of a page in order, in
    one namespace (a page reads like one session), in a scratch directory.  A block preceded by
    the line `<!-- docs-test: skip -->` is illustrative only (a multi-host run) and not run.

The blocks run in one child process (`python tests/test_docs.py RESULTS.json [PAGE ...]`, which
also runs by hand), page after page, so that the pages share JAX's compiled solvers.  It
inherits this process's environment (XLA_FLAGS and the compilation-cache settings of
conftest.py) and runs with JAX_DISABLE_MOST_OPTIMIZATIONS=1: compilation, not execution, is most
of the time of such small problems, and the numbers asserted do not depend on it (the blocks
also pass with XLA's default optimisations).  The child reports, per page, the blocks run, the
seconds taken, and the first failure with its traceback.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
import textwrap
import time
import traceback
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
CONFIG = ROOT / "mkdocs.yml"
SKIP = "<!-- docs-test: skip -->"
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<info>[^\n`]*)\n(?P<body>.*?)^(?P=indent)```[ \t]*$", re.MULTILINE | re.DOTALL)
CHILD_SECONDS = 600  # the child's limit; it takes about 85 s on 2 cores, 35 s with a warm compilation cache


def python_blocks(page: Path) -> list[tuple[int, str, bool]]:
    """`(line, code, skipped)` for every ```python block of a Markdown page, in order."""
    text = page.read_text()
    blocks = []
    for match in FENCE.finditer(text):
        if (match["info"].split() or [""])[0] != "python":
            continue
        line = text.count("\n", 0, match.start()) + 1
        before = text[: match.start()].rstrip().rsplit("\n", 1)[-1].strip()
        blocks.append((line, textwrap.dedent(match["body"]), before == SKIP))
    return blocks


def pages_with_code() -> list[Path]:
    return sorted(p for p in DOCS.rglob("*.md") if any(not skipped for *_, skipped in python_blocks(p)))


def run_page(page: Path, name: str) -> dict:
    """Run the blocks of `page` in a fresh namespace: `{"blocks", "seconds", "error"}`."""
    namespace = {"__name__": f"docs:{name}"}
    start, ran, error = time.perf_counter(), 0, None
    for line, code, skipped in python_blocks(page):
        if skipped:
            continue
        try:
            exec(compile(code, f"docs/{name}:{line}", "exec"), namespace)  # noqa: S102
            ran += 1
        except BaseException:  # noqa: BLE001 — reported to the test, which fails
            error = f"the block at docs/{name}:{line} failed:\n{traceback.format_exc()}"
            break
    return {"blocks": ran, "seconds": time.perf_counter() - start, "error": error}


def _child(results: Path, pages: list[Path]) -> None:
    os.environ.setdefault("MPLBACKEND", "Agg")
    with tempfile.TemporaryDirectory() as scratch:  # the blocks may write files
        os.chdir(scratch)
        outcome = {page.relative_to(DOCS).as_posix(): run_page(page, page.relative_to(DOCS).as_posix())
                   for page in pages}
    results.write_text(json.dumps(outcome, indent=1))
    for name, r in outcome.items():
        print(f"{r['seconds']:6.1f} s  {r['blocks']:3d} blocks  {name}  {'FAILED' if r['error'] else 'ok'}")
        if r["error"]:
            print(r["error"])


if __name__ == "__main__":
    _child(Path(sys.argv[1]).resolve(), [DOCS / p for p in sys.argv[2:]] or pages_with_code())
    sys.exit(0)


import pytest  # noqa: E402  (below the child's entry point, which does not need it)

# ---------------------------------------------------------------------------------------------
# (b) the code blocks


def test_every_code_block_runs(tmp_path):
    """One test, not one per page: under pytest-xdist (`make test`) the pages must not be split
    over workers, each of which would start its own child and compile the same solvers."""
    results = tmp_path / "results.json"
    env = dict(os.environ, JAX_DISABLE_MOST_OPTIMIZATIONS="1", MPLBACKEND="Agg",
               PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, __file__, str(results)], env=env, capture_output=True, text=True,
                          timeout=CHILD_SECONDS, check=False)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    outcome = json.loads(results.read_text())
    pages = [p.relative_to(DOCS).as_posix() for p in pages_with_code()]
    assert sorted(outcome) == pages
    failures = [r["error"] for r in outcome.values() if r["error"]]
    assert not failures, "\n\n".join(failures)
    for page in pages:
        assert outcome[page]["blocks"] == sum(not skipped for *_, skipped in python_blocks(DOCS / page)), page


def test_every_page_has_run_code_and_few_blocks_are_skipped():
    """The extractor finds the blocks (a broken pattern would let (b) pass vacuously): every
    tutorial and guide runs code, and skipped blocks stay the exception."""
    blocks = [b for page in DOCS.rglob("*.md") for b in python_blocks(page)]
    assert len(blocks) >= 30 and sum(skipped for *_, skipped in blocks) <= 2
    guides = {"index.md", "custom-energy.md", "solver.md", "derivatives.md", "verify.md", "tutorials/curves.md",
              "tutorials/rods.md", "tutorials/surfaces.md", "tutorials/delaunay.md", "tutorials/spin-chains.md"}
    assert guides <= {p.relative_to(DOCS).as_posix() for p in pages_with_code()}


def test_the_extractor_runs_blocks_in_order_and_reports_the_failing_line(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("Text.\n\n```python\nx = 1\n```\n\n" + SKIP + "\n```python\nraise SystemExit\n```\n\n"
                    "- a list item:\n\n    ```python\n    y = x + 1\n    ```\n\n```bash\nexit 1\n```\n\n"
                    "```python\nassert y == 3, y\n```\n")
    assert [(line, skipped) for line, _, skipped in python_blocks(page)] == [(3, False), (8, True), (14, False), (22, False)]
    result = run_page(page, "page.md")
    assert result["blocks"] == 2
    assert "docs/page.md:22" in result["error"] and "AssertionError: 2" in result["error"]


# ---------------------------------------------------------------------------------------------
# (a) the strict build

# The public API (../shared/API.md) as rendered identifiers: the re-exported names
# (`dg.Problem`, `dg.mesh.genus`) are documented where they are defined.
API = [
    "ddgjax.problem.Problem", "ddgjax.problem.Problem.with_params", "ddgjax.problem.euler_lagrange",
    "ddgjax.locality.local_sum", "ddgjax.locality.local_map", "ddgjax.locality.concat",
    "ddgjax.flows.gradient_flow", "ddgjax.flows.hamiltonian_flow", "ddgjax.flows.spin_poisson",
    "ddgjax.flows.lie_bracket", "ddgjax.flows.integrate",
    "ddgjax.limits.convergence", "ddgjax.limits.ConvergenceTable",
    "ddgjax.errors.DDGError", "ddgjax.errors.ConvergenceError",
    "solvers.solve", "solvers.Solution", "solvers.minimize", "solvers.solve_batch", "solvers.LinearSolver",
    "solvers.DenseLU", "solvers.KLU", "solvers.SparseDirect", "solvers.Krylov", "solvers.stability",
    "solvers.Stability", "solvers.continuation", "solvers.Branch",
    *(f"ddgjax.curves.{f}" for f in ("tangents", "turning_angles", "curvature", "from_tangents", "tangent_flow",
                                     "heisenberg_flow")),
    *(f"ddgjax.quaternion.{f}" for f in ("mul", "conj", "inv", "rotate", "from_axis_angle", "to_matrix", "from_matrix")),
    *(f"ddgjax.mesh.topology.{f}" for f in ("euler_characteristic", "is_orientable", "boundary_loops", "genus",
                                            "classify")),
    *(f"ddgjax.mesh.curvature.{f}" for f in ("angle_defect", "edge_mean_curvature", "total_mean_curvature")),
    "ddgjax.laplace.cotan_weights", "ddgjax.laplace.cotan_laplacian",
    "ddgjax.intrinsic.delaunay.flip_to_delaunay", "ddgjax.intrinsic.delaunay.is_delaunay",
    "ddgjax.intrinsic.laplace_beltrami.laplace_beltrami",
    "energies.elastica.clamped", "energies.elastica.closed", "energies.elastica.bending_energy",
    "energies.pendulum.action", "energies.pendulum.step", "energies.rod.clamped", "energies.heisenberg.hamiltonian",
    "energies.dirichlet.graph", "energies.dirichlet.cotan", "energies.area.simplicial", "energies.area.minimal_surface",
    "energies.area.with_volume", "energies.willmore.helfrich", "energies.willmore.conformal",
    "ddgjax.mesh.subdivision.subdivide",
    "ddgjax.verify.check", "ddgjax.verify.verify",
]


def mkdocs_build(config: Path, site: Path) -> subprocess.CompletedProcess:
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings_handlers.python")
    pytest.importorskip("material")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)],
                          cwd=config.parent, env=env, capture_output=True, text=True, timeout=600, check=False)


def inventory(site: Path) -> set[str]:
    """The identifiers in the site's objects.inv (Sphinx inventory v2: 4 header lines, zlib)."""
    body = (site / "objects.inv").read_bytes().split(b"\n", 4)[4]
    return {line.split(" ", 1)[0] for line in zlib.decompress(body).decode().splitlines()}


def test_mkdocs_build_strict(tmp_path):
    """The build works offline: no plugin that downloads at build time (material's social cards,
    privacy or optimize plugins); MathJax is loaded by the reader's browser."""
    yaml = pytest.importorskip("yaml")
    plugins = {p if isinstance(p, str) else next(iter(p)) for p in yaml.safe_load(CONFIG.read_text())["plugins"]}
    assert not plugins & {"social", "privacy", "optimize"}, plugins
    proc = mkdocs_build(CONFIG, tmp_path / "site")
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    for page in ("index.html", "tutorials/curves/index.html", "api/solvers/index.html", "figures/fig_7_26.png"):
        assert (tmp_path / "site" / page).is_file(), page
    missing = sorted(set(API) - inventory(tmp_path / "site"))
    assert not missing, f"not in the API reference: {missing}"


def one_page_config(tmp_path: Path, text: str) -> Path:
    """A copy of mkdocs.yml building the single page `text` from tmp_path/docs."""
    yaml = pytest.importorskip("yaml")
    config = yaml.safe_load(CONFIG.read_text())
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text(text)
    config.update(docs_dir=str(tmp_path / "docs"), nav=[{"Home": "index.md"}], extra_javascript=[])
    config.pop("watch", None)  # paths relative to the repository
    for plugin in config["plugins"]:
        if isinstance(plugin, dict) and "mkdocstrings" in plugin:
            python = plugin["mkdocstrings"]["handlers"]["python"]
            python["paths"] = [str(ROOT)]
            python["options"]["extensions"] = [str(ROOT / e) for e in python["options"]["extensions"]]
    path = tmp_path / "mkdocs.yml"
    path.write_text(yaml.safe_dump(config, allow_unicode=True))
    return path


PAGE = """# One page

::: ddgjax.problem
    options:
      members: [Problem, euler_lagrange]

[`Problem`][ddgjax.problem.Problem] and [`euler_lagrange`][ddgjax.problem.euler_lagrange] on [this page](index.md).
"""


@pytest.mark.parametrize("broken, named", [
    ("", None),
    ("See [the missing page](no-such-page.md).", "no-such-page.md"),
    ("See [`missing`][ddgjax.problem.no_such_function].", "ddgjax.problem.no_such_function"),
], ids=["control", "missing page", "missing identifier"])
def test_strict_build_fails_on_a_broken_reference(tmp_path, broken, named):
    """The control page builds (so the copied configuration is sound and a failure is the broken
    reference's); with a link to a missing page or an unknown API identifier it does not."""
    proc = mkdocs_build(one_page_config(tmp_path, PAGE + broken + "\n"), tmp_path / "site")
    output = proc.stdout + proc.stderr
    if named is None:
        assert proc.returncode == 0, output[-3000:]
    else:
        assert proc.returncode != 0 and named in output, output[-3000:]
