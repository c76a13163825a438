"""Importing ddgjax is cheap: heavy dependencies load where they are used.

`import ddgjax` loads JAX and nothing heavy; the names of the package load on first use
(PEP 562).  Declaring and solving an elastica needs neither the ODE, optimisation, plotting,
mesh-file nor console libraries.  Each case runs in a fresh interpreter.
"""

import json
import subprocess
import sys

import pytest

# (bare `scipy` is not here: jaxlib loads scipy.linalg for its LAPACK kernels on the first solve)
HEAVY = ("diffrax", "optimistix", "jaxopt", "matplotlib", "meshio", "rich", "scipy.optimize", "scipy.sparse",
         "scipy.special", "numba", "equinox", "pyamg")


def loaded_after(code: str) -> list[str]:
    """The HEAVY modules in `sys.modules` after running `code` in a fresh interpreter."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("code", [
    "import ddgjax",
    "import ddgjax as dg; dg.Problem; dg.errors; dg.euler_lagrange",
    "from energies import elastica\nfrom solvers import solve\n"
    "solve(elastica.clamped(8, chord=(0.5, 0.2, 0), t_start=(1, 0, 0), t_end=(0, 1, 0)))",
])
def test_light_imports_load_no_heavy_dependency(code):
    assert loaded_after(code) == []


def test_the_probe_sees_heavy_imports():
    """Negative control: the probe reports a heavy module that the code does load."""
    assert "diffrax" in loaded_after("import ddgjax as dg; dg.flows.integrate; import diffrax")


def test_lazy_names_are_the_module_attributes():
    import ddgjax as dg
    from ddgjax import flows, problem
    from ddgjax.smooth import top

    assert dg.Problem is problem.Problem and dg.gradient_flow is flows.gradient_flow and dg.top is top
    assert {"Problem", "mesh", "plot_surface", "kirchhoff"} <= set(dir(dg))
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        dg.nonexistent
