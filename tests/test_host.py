"""The bookkeeping around a solve compiles nothing of its own (`ddgjax/_host.py`).

Outside `jit`, each `jax.numpy` operation on a new shape is an XLA program of its own; the
bookkeeping of `solve` (flattening x0, weights, the history) runs in NumPy on concrete values.
So a solve of a size not seen before lowers exactly the solver and KLU's symbolic analysis, and
the same functions give the same numbers when traced.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from conftest import lowered
from ddgjax._flat import layout_of
from ddgjax._host import namespace, on_device
from energies import elastica
from solvers import _exported, solve
from solvers._kkt import scaled_residual

def _elastica(n: int) -> dg.Problem:
    return elastica.clamped(n, chord=[0.5, 0.0, 0.0], t_start=[0.0, 1.0, 0.0], t_end=[0.0, -1.0, 0.0])


@pytest.mark.parametrize("exported", [False, True])
def test_a_solve_of_a_new_size_lowers_only_the_solver_and_the_klu_analysis(exported, tmp_path, monkeypatch):
    """Without exported solvers: the solver and KLU's analysis.  With them (into an empty
    folder, `solvers/_exported.py`): the solver once more for its export, and the call of the
    exported program; where the suite's compilation cache held that call already (a run before
    this one), it is compiled once more under a name of its own to be kept (`_compiled_here`)."""
    monkeypatch.setenv(_exported.FOLDER_ENV, str(tmp_path) if exported else "off")
    solve(_elastica(41))  # what any size shares (scalar programs) is built here (a size of its own:
    # a pattern cached by an earlier test would skip that)
    problem = _elastica(53 if exported else 47)  # sizes no other test uses
    sol, names = lowered(lambda: solve(problem))
    assert sol.residual <= 1e-10
    kept = [name for name in names if name.startswith("jit(call_")]
    assert len(kept) <= int(exported)
    assert sorted(set(names) - set(kept)) == (["jit(_solve_impl)", "jit(call)", "jit(ffi_call)"] if exported
                                              else ["jit(_solve_impl)", "jit(ffi_call)"])
    assert len(names) == len(set(names))
    _, again = lowered(lambda: solve(problem))
    assert again == []


def test_negative_control_eager_jax_numpy_on_a_new_shape_is_counted():
    x = jnp.ones(43)
    _, names = lowered(lambda: jnp.concatenate([jnp.ravel(x), jnp.zeros(3)]))
    assert len(names) >= 1


def test_the_numpy_and_the_traced_bookkeeping_agree():
    x0 = {"a": np.arange(6.0).reshape(2, 3), "b": np.array([7.0, 8.0])}
    problem = dg.Problem(lambda x, p: jnp.sum(x["a"] ** 2) + jnp.sum(x["b"] ** 2), x0,
                         fixed={"a": np.array([[True, False, False], [False, False, True]]), "b": np.array([False, True])})
    layout = layout_of(problem)
    z = layout.ravel(problem.x0)
    assert isinstance(z, jax.Array)
    np.testing.assert_array_equal(np.asarray(z), np.asarray(jax.jit(layout.ravel)(problem.x0)))
    u = np.array([-1.0, -2.0, -3.0, -4.0, -5.0])
    eager = layout.x_of(z, u)
    traced = jax.jit(layout.x_of)(z, u)
    for key in x0:
        assert isinstance(eager[key], jax.Array)
        np.testing.assert_array_equal(np.asarray(eager[key]), np.asarray(traced[key]))
    np.testing.assert_array_equal(np.asarray(eager["a"]), [[0.0, -1.0, -2.0], [-3.0, -4.0, 5.0]])
    R, weights = np.array([1.0, -4.0, 2.0]), (np.array([1.0, 0.5]), np.array([3.0]))
    assert scaled_residual(R, weights, 2) == 6.0
    assert float(jax.jit(scaled_residual, static_argnums=2)(R, weights, 2)) == 6.0


def test_namespace_is_numpy_for_concrete_values_and_jax_numpy_under_a_trace():
    seen = []
    jax.jit(lambda x: seen.append(namespace(x)) or x)(1.0)
    assert seen == [jnp]
    assert namespace(np.ones(2), jnp.ones(2), {"p": 1.0}) is np
    assert isinstance(on_device(np.ones(2)), jax.Array)
    assert on_device("not an array") == "not an array"
