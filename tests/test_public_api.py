"""Every entry point of `../shared/API.md` exists where the document says, also after modules moved
into the layered subpackages; the old module names of moved modules still resolve."""

from __future__ import annotations

import importlib

import pytest

import ddgjax as dg

API = {
    "ddgjax": ["Problem", "euler_lagrange", "gradient_flow", "hamiltonian_flow", "spin_poisson", "lie_bracket",
               "integrate", "local_sum", "local_map", "concat", "errors", "limits", "curves", "quaternion", "mesh",
               "laplace", "intrinsic", "plot"],
    "ddgjax.errors": ["DDGError", "ConvergenceError"],
    "ddgjax.limits": ["convergence", "ConvergenceTable"],
    "ddgjax.curves": ["tangents", "turning_angles", "curvature", "from_tangents", "tangent_flow", "heisenberg_flow"],
    "ddgjax.quaternion": ["mul", "conj", "inv", "rotate", "from_axis_angle", "to_matrix", "from_matrix"],
    "ddgjax.mesh": ["euler_characteristic", "is_orientable", "boundary_loops", "genus", "classify", "angle_defect",
                    "edge_mean_curvature", "total_mean_curvature"],
    "ddgjax.laplace": ["cotan_weights", "cotan_laplacian"],
    "ddgjax.intrinsic": ["flip_to_delaunay", "is_delaunay", "laplace_beltrami"],
    "solvers": ["solve", "solve_batch", "Solution"],
    "energies.elastica": ["clamped", "closed", "bending_energy"],
    "energies.pendulum": ["action", "step"],
    "energies.rod": ["clamped"],
    "energies.heisenberg": ["hamiltonian"],
    "energies.dirichlet": ["graph", "cotan"],
    "energies.area": ["simplicial", "minimal_surface"],
}

MOVED = {  # old name -> new module
    "elastica_exact": "ddgjax.smooth.elastica",
    "kirchhoff": "ddgjax.smooth.kirchhoff",
    "top": "ddgjax.smooth.top",
    "plot_surface": "ddgjax.plot.surface",
    "plot_laplace": "ddgjax.plot.laplace",
}


@pytest.mark.parametrize("module, names", list(API.items()), ids=list(API))
def test_api_names_exist(module, names):
    mod = importlib.import_module(module)
    assert [n for n in names if not hasattr(mod, n)] == []


@pytest.mark.parametrize("old, new", list(MOVED.items()))
def test_moved_modules_keep_their_old_names(old, new):
    assert getattr(dg, old) is importlib.import_module(new)


def test_an_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'no_such_module'"):
        dg.no_such_module  # noqa: B018
