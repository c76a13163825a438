"""The gallery (examples/*.py) runs at tiny sizes and draws its figures; the custom-energy
example (README's "define a functional and call solve()") finds the regular polygon."""

import importlib
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
FAST = ["custom_energy", "gauss_bonnet", "heisenberg_chain", "elastica_family", "pendulum_shooting", "catenoid",
        "intrinsic_delaunay", "narrow_minimal_surface"]
# the rod's KKT system takes minutes to compile on 2 cores: run with `make test-all`
SLOW = ["twisted_rod"]


def load(name: str):
    sys.path.insert(0, str(EXAMPLES))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(EXAMPLES))


def test_every_example_is_tested():
    scripts = {p.stem for p in EXAMPLES.glob("*.py") if not p.stem.startswith("_")}
    assert scripts == set(FAST + SLOW)


@pytest.mark.parametrize("name", FAST + [pytest.param(n, marks=pytest.mark.slow) for n in SLOW])
def test_example_draws_its_figures(name, tmp_path):
    result = load(name).main(tmp_path, tiny=True)
    paths = result if isinstance(result, list) else [result]
    for path in paths:
        assert Path(path).parent == tmp_path and Path(path).stat().st_size > 2000


def test_custom_energy_finds_the_regular_polygon():
    """Dido's problem: area n h²/(4 tan(π/n)) and equal edge tensions −1/(4 tan(π/n)), h = 1/n
    (KKT residual ≤ 1e-10 bounds the area error by ~1e-11)."""
    n = 8
    sol, exact = load("custom_energy").dido(n)
    assert float(sol.residual) <= 1e-10
    assert abs(-float(sol.energy) - exact) <= 1e-11
    assert np.max(np.abs(np.asarray(sol.multipliers) + 1 / (4 * np.tan(np.pi / n)))) <= 1e-9


def test_output_directory_from_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("DDGJAX_EXAMPLES_OUT", str(tmp_path / "gallery"))
    assert load("_common").output_dir() == tmp_path / "gallery"
    assert (tmp_path / "gallery").is_dir()
