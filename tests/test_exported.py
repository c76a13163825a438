"""Exported programs (`solvers/_exported.py`): their key describes everything the solver's trace
reads, so a program found on disk is the program the declaration would trace.

Each negative control changes one input the trace reads (a constant, a literal, the fixed mask,
a constraint, the linear solver, an option, an argument's type, a stencil, the library's source)
and sees the key change; a declaration the key cannot describe (Python derivative rules, host
callbacks) is not exported.  End to end: two declarations alike but for a constant each get
their own solution, a second "process" (JAX's caches cleared) loads the program without
tracing it, and a corrupt file is replaced.
"""

import time

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from conftest import lowered
from energies import elastica
from solvers import _exported, solve
from solvers._kkt import spec_of
from solvers._solve import linear_solver_of, residual_weights

TARGET = np.array([1.0, -2.0, 0.5, 3.0])


def key(problem: dg.Problem, method: str = "dense", **static) -> str:
    """The key of `solve`'s program for `problem` (the arguments `solve` passes)."""
    spec = spec_of(problem)
    args = (linear_solver_of(problem, spec, method, None), spec.layout.ravel(problem.x0), problem.params, None,
            residual_weights(problem, spec))
    leaves, treedef = jax.tree_util.tree_flatten(args)
    avals = tuple(_exported._abstract(leaf) for leaf in leaves)
    return _exported.program_key(spec, {"function": "solve", "tol": 1e-10, **static}, treedef, avals)


def quadratic(target=TARGET, scale=2.0, fixed=None, constraints=None, params=None) -> dg.Problem:
    """`scale · |x − target|²` (a fresh function object per call), optionally constrained."""
    target = np.asarray(target)
    return dg.Problem(lambda x, p: scale * jnp.sum((x - target) ** 2), np.zeros(4), fixed=fixed,
                      constraints=constraints, params=params)


def clamped(n: int = 12):
    return elastica.clamped(n, chord=[0.5, 0.0, 0.0], t_start=[0.0, 1.0, 0.0], t_end=[0.0, -1.0, 0.0])


def test_a_declaration_built_twice_has_one_key():
    """Positive control: new function objects of the same code and constants share the key."""
    assert key(quadratic()) == key(quadratic())
    assert key(clamped(), "sparse") == key(clamped(), "sparse")


@pytest.mark.parametrize("other", [
    lambda: quadratic(target=TARGET + np.array([0.0, 0.0, 0.0, 1e-15])),  # a constant's last bit
    lambda: quadratic(scale=2.0000000000000004),  # a literal's last bit
    lambda: quadratic(fixed=np.array([True, False, False, False])),
    lambda: quadratic(constraints=lambda x, p: jnp.sum(x) - 1.0),
    lambda: quadratic(params={"k": 1.0}),
], ids=["constant", "literal", "fixed", "constraint", "params"])
def test_every_input_of_the_trace_changes_the_key(other):
    assert key(other()) != key(quadratic())


def test_which_entries_are_fixed_changes_the_key():
    """The same number of unknowns (the same argument shapes), another entry fixed."""
    assert key(quadratic(fixed=np.array([True, False, False, False]))) != key(
        quadratic(fixed=np.array([False, True, False, False])))


def test_the_options_the_linear_solver_and_argument_types_change_the_key():
    problem = clamped()
    base = key(problem, "sparse")
    assert key(problem, "dense") != base
    assert key(problem, "sparse", max_steps=7) != base
    assert key(quadratic(params={"k": 1.0})) != key(quadratic(params={"k": np.float64(1.0)}))  # weak type


def test_a_stencil_of_the_same_shape_changes_the_key():
    def bend(x_local, p):
        return jnp.sum((x_local[1] - x_local[0]) ** 2)

    def problem(stencil):
        return dg.Problem(dg.local_sum(bend, np.array(stencil)), np.arange(8.0).reshape(4, 2),
                          fixed=np.array([[True, True], [False, False], [False, False], [True, True]]))

    assert key(problem([[0, 1], [1, 2], [2, 3]]), "sparse") != key(problem([[0, 1], [1, 3], [2, 3]]), "sparse")
    assert key(problem([[0, 1], [1, 2], [2, 3]]), "sparse") == key(problem([[0, 1], [1, 2], [2, 3]]), "sparse")


def test_the_library_source_is_in_the_key(monkeypatch):
    base = key(quadratic())
    monkeypatch.setattr(_exported, "source_digest", lambda: b"edited")
    _exported.environment_digest.cache_clear()
    try:
        assert key(quadratic()) != base
    finally:
        monkeypatch.undo()
        _exported.environment_digest.cache_clear()
    assert key(quadratic()) == base


def test_the_source_digest_covers_the_layers_up_to_the_solvers_and_not_the_application(tmp_path):
    """An edit of the solvers, the language or an energy changes the digest (and so every key); an
    edit of a check of `verify`, a plot or the command line does not (`_exported.APPLICATION`)."""
    files = ["solvers/_newton.py", "ddgjax/locality.py", "energies/rod.py", "ddgjax/verify/checks/sec1_curves.py",
             "ddgjax/plot/lines.py", "ddgjax/cli.py", "ddgjax/sweep.py", "ddgjax/verifying.py"]
    for name in files:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(f"# {name}\n")
    base = _exported.source_digest(tmp_path)
    for name in files:
        (tmp_path / name).write_text("# edited\n")
        changed = _exported.source_digest.__wrapped__(tmp_path) != base
        (tmp_path / name).write_text(f"# {name}\n")
        assert changed == (name in ("solvers/_newton.py", "ddgjax/locality.py", "energies/rod.py",
                                    "ddgjax/verifying.py")), name


def test_python_derivative_rules_and_host_callbacks_are_not_exported():
    @jax.custom_jvp
    def soft(x):
        return jnp.sum(x**2)

    soft.defjvp(lambda primals, tangents: (soft(primals[0]), 2.0 * jnp.dot(primals[0], tangents[0])))
    with pytest.raises(_exported.NotDescribed, match="custom_jvp_call"):
        key(dg.Problem(lambda x, p: soft(x), np.ones(3)))
    with pytest.raises(_exported.NotDescribed, match="pure_callback"):
        key(dg.Problem(lambda x, p: jax.pure_callback(np.sum, jax.ShapeDtypeStruct((), x.dtype), x**2), np.ones(3)))
    # JAX's own rules are described by its version (jnp.frexp is a custom_jvp)
    assert len(key(dg.Problem(lambda x, p: jnp.sum(jnp.frexp(x)[0] ** 2), np.ones(3)))) == 64


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """Exported programs in an empty folder; JAX's (and the solver's) in-memory caches cleared
    before and after, as in a new process."""
    monkeypatch.setenv(_exported.FOLDER_ENV, str(tmp_path))
    jax.clear_caches()
    yield tmp_path
    jax.clear_caches()


def test_declarations_alike_but_for_a_constant_get_their_own_solutions(folder):
    a = solve(quadratic())
    jax.clear_caches()
    b = solve(quadratic(target=2.0 * TARGET))
    np.testing.assert_allclose(np.asarray(a.x), TARGET, atol=1e-12)
    np.testing.assert_allclose(np.asarray(b.x), 2.0 * TARGET, atol=1e-12)
    assert len(list(folder.glob("*.program"))) == 2


def unseen() -> dg.Problem:
    """A quadratic whose target has a constant unique to this run: JAX's compilation cache,
    shared by the suite's runs, cannot hold its program, which this process compiles."""
    return quadratic(target=TARGET + time.time_ns() % 10**9 * 1e-12)


def test_a_new_process_loads_the_executable_without_tracing_or_lowering_the_solver(folder):
    problem = unseen()
    first, names = lowered(lambda: solve(problem))
    assert "jit(_solve_impl)" in names and "jit(call)" in names  # exported, then its call compiled
    (executable,) = folder.glob("*.executable")
    assert executable.name.endswith(f"-{_exported.executable_digest()}.executable")
    jax.clear_caches()
    second, names = lowered(lambda: solve(problem))
    assert "jit(_solve_impl)" not in names and "jit(call)" not in names
    for a, b in zip(jax.tree_util.tree_leaves(first), jax.tree_util.tree_leaves(second), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_a_corrupt_or_missing_executable_is_compiled_here_and_kept_again(folder):
    """A truncated executable (or one for other XLA flags: another `executable_digest`) is not
    loaded: the exported program's call is lowered (the solver is not traced again).  Its entry
    in JAX's compilation cache cannot be kept (XLA:CPU serialises a loaded executable without
    its kernels), so the call is compiled once more here, outside that cache, and kept: the
    next process loads it without lowering anything.  The same holds for a removed file."""
    problem = unseen()
    first = solve(problem)
    (executable,) = folder.glob("*.executable")
    for damage in (lambda: executable.write_bytes(_exported.FORMAT + b"truncated"), executable.unlink):
        damage()
        jax.clear_caches()
        second, names = lowered(lambda: solve(problem))
        assert "jit(_solve_impl)" not in names and "jit(call)" in names
        assert any(name.startswith("jit(call_") for name in names)  # compiled here, under a name of its own
        assert _exported._load_executable(executable) is not None
        jax.clear_caches()
        third, names = lowered(lambda: solve(problem))
        assert "jit(_solve_impl)" not in names and "jit(call)" not in names and not names
        for a, b, c in zip(*map(jax.tree_util.tree_leaves, (first, second, third)), strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
            np.testing.assert_array_equal(np.asarray(a), np.asarray(c))


def test_a_corrupt_file_is_exported_anew(folder):
    """A corrupt exported program (its executable gone: otherwise that is loaded, and the
    program never read) is exported again."""
    solve(quadratic())
    (path,) = folder.glob("*.program")
    path.write_bytes(_exported.FORMAT + b"not a pickle")
    for executable in folder.glob("*.executable"):
        executable.unlink()
    jax.clear_caches()
    sol = solve(quadratic())
    np.testing.assert_allclose(np.asarray(sol.x), TARGET, atol=1e-12)
    assert _exported._load(path) is not None


def test_traced_calls_and_debugging_flags_are_not_exported(folder):
    """Under `grad` the solver is traced as usual (its implicit derivative: d Σx/dt = 4 for
    x = t·1 in R⁴); under `disable_jit` it runs op by op."""
    problem = dg.Problem(lambda x, p: jnp.sum((x - p["t"]) ** 2), np.zeros(4), params={"t": 1.0})
    derivative = jax.grad(lambda t: jnp.sum(solve(problem.with_params({"t": t})).x))(2.0)
    assert float(derivative) == pytest.approx(4.0, abs=1e-12)
    with jax.disable_jit():
        solve(quadratic(scale=3.0))
    assert list(folder.glob("*")) == []
    solve(quadratic())  # control: the same solve outside them is exported
    assert len(list(folder.glob("*.program"))) == 1


def test_a_program_with_a_host_callback_is_recorded_and_not_exported_again(folder):
    """`SparseDirect`'s factorisations are host callbacks: the first process tries the export
    once (and traces the program as usual), later ones trace it at once; its solve without steps
    has no factorisation and is exported."""
    from energies import area
    from solvers import SparseDirect

    def problem():
        V, F = dg.mesh.disk(1, 6)
        return area.simplicial(V + [0, 0, 0.1] * (V[:, :1] > 0), F)

    _, first = lowered(lambda: solve(problem(), linear_solver=SparseDirect()))
    assert first.count("jit(_solve_impl)") == 2  # the export tried, then the program traced
    (path,) = folder.glob("*.program")
    assert path.read_bytes() == _exported.FORMAT + _exported.NOT_EXPORTABLE
    jax.clear_caches()
    sol, second = lowered(lambda: solve(problem(), linear_solver=SparseDirect()))
    assert second.count("jit(_solve_impl)") == 1 and sol.residual <= 1e-10
    solve(problem(), linear_solver=SparseDirect(), max_steps=0, throw=False, warm_start=None)
    assert len([p for p in folder.glob("*.program") if _exported._load(p) is not _exported.NOT_EXPORTABLE]) == 1
