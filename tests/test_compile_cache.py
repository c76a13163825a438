"""`solve_batch` compiles once per structure, and keeps at most `COMPILED_BATCH_SOLVERS` programs.

The problem: critical points of `|x − target|² + weight·Σx⁴` on the unit sphere in Rⁿ; the
energy counts its calls, so a call that traces (and compiles) shows in the count.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from solvers import _batch, solve_batch
from solvers._cache import LRU

CALLS = {"energy": 0}


def pulled_to_target(x, p):
    CALLS["energy"] += 1
    return jnp.sum((x - p["target"]) ** 2) + p["weight"] * jnp.sum(x**4)


def on_sphere(x, p):
    return jnp.array([jnp.sum(x**2) - 1.0])


def _problem(n: int, weight: float = 0.1) -> dg.Problem:
    x0 = jnp.ones(n) / jnp.sqrt(n)
    return dg.Problem(pulled_to_target, x0, constraints=on_sphere, params={"target": jnp.zeros(n), "weight": weight})


def _targets(n: int, batch: int = 3):
    return jnp.asarray(np.random.default_rng(n).uniform(0.5, 1.5, (batch, n)))


def _solve(problem: dg.Problem, targets):
    """The batch solve, and the energy's calls during it."""
    before = CALLS["energy"]
    sol = solve_batch(problem, {"target": targets}, method="dense")
    return sol, CALLS["energy"] - before


@pytest.fixture(autouse=True)
def empty_cache(monkeypatch):
    """An empty `PROGRAMS` with its counts at 0, and JAX's trace caches emptied, so that a
    compile traces the energy anew (JAX keeps traces of `solve`'s inner `jit` by structure).
    No exported programs: a program exported by an earlier run would be called untraced
    (`tests/test_compile_cache_persistent.py` tests that)."""
    from solvers._exported import FOLDER_ENV

    monkeypatch.setenv(FOLDER_ENV, "off")
    monkeypatch.setattr(_batch.PROGRAMS, "size", _batch.COMPILED_BATCH_SOLVERS)
    jax.clear_caches()
    _batch.PROGRAMS.cache_clear()
    yield
    _batch.PROGRAMS.cache_clear()


def test_second_call_on_a_problem_declared_alike_reuses_the_executable():
    """A new `Problem` with the same functions, shapes and options: no trace, no compile, the
    same result to 1e-12.  Another value of a shared parameter (weight 0.7) is an argument of
    the executable, not a constant in it: the result satisfies Lagrange's condition for 0.7."""
    targets = _targets(3)
    first, traced = _solve(_problem(3), targets)
    assert traced > 0 and _batch.PROGRAMS.cache_info()[:2] == (0, 1)
    again, traced = _solve(_problem(3), targets)
    assert traced == 0 and _batch.PROGRAMS.cache_info()[:2] == (1, 1)
    for a, b in zip(jax.tree_util.tree_leaves(first), jax.tree_util.tree_leaves(again)):
        np.testing.assert_allclose(np.asarray(a, float), np.asarray(b, float), rtol=0, atol=1e-12)  # history: NaN after the last step

    heavier = _problem(3, weight=0.7)
    other, traced = _solve(heavier, targets)
    assert traced == 0 and _batch.PROGRAMS.cache_info()[:2] == (2, 1)
    assert float(jnp.max(jnp.abs(other.x - first.x))) > 1e-3
    # Lagrange's condition for weight 0.7: 2(x − t) + 4·0.7·x³ = 2λx, and |x| = 1
    x, lam, t = np.asarray(other.x), np.asarray(other.multipliers)[:, :1], np.asarray(targets)
    assert np.max(np.abs(2 * (x - t) + 2.8 * x**3 - 2 * lam * x)) <= 1e-9
    assert np.max(np.abs(np.sum(x**2, axis=1) - 1)) <= 1e-12


def test_a_changed_structure_compiles_anew_and_the_cache_holds_at_most_its_bound(monkeypatch):
    """Bound 2: n = 2, 3, 4 each trace and compile, and the cache never holds more than 2 (n = 2
    is evicted).  Control, the bound raised to 8: n = 2 compiles again (a miss; its trace JAX
    still holds), n = 3, 4 are found without a trace, and the cache holds all three."""
    monkeypatch.setattr(_batch.PROGRAMS, "size", 2)
    for misses, n in enumerate((2, 3, 4), start=1):
        sol, traced = _solve(_problem(n), _targets(n))
        assert traced > 0 and _batch.PROGRAMS.cache_info().misses == misses
        assert len(_batch.PROGRAMS) <= 2
        assert sol.x.shape == (3, n) and bool(np.all(sol.converged))
    assert len(_batch.PROGRAMS) == 2

    monkeypatch.setattr(_batch.PROGRAMS, "size", 8)
    traced = [_solve(_problem(n), _targets(n))[1] for n in (2, 3, 4)]
    assert traced[1:] == [0, 0]
    assert len(_batch.PROGRAMS) == 3 and _batch.PROGRAMS.cache_info()[:2] == (2, 4)


def test_lru_evicts_the_least_recently_used():
    cache = LRU(2)
    cache.get("a", lambda: 1)
    cache.get("b", lambda: 2)
    cache.get("a", lambda: None)
    cache.get("c", lambda: 3)
    assert cache.cache_keys() == ["a", "c"] and cache.cache_info() == (1, 3, 2, 2)


def test_jax_clear_caches_empties_the_cache():
    _batch.PROGRAMS.get("placeholder", lambda: 0)
    jax.clear_caches()
    assert len(_batch.PROGRAMS) == 0


def test_solve_keeps_a_bounded_number_of_compiled_solvers(monkeypatch):
    """Fresh lambda energies (a new declaration each): `solve` compiles each, keeps at most
    `COMPILED_SOLVERS` of them, and answers right (x = a for ½(x − a)²)."""
    import solvers._solve as S

    monkeypatch.setattr(S.JITTED, "size", 3)
    for k in range(6):
        problem = dg.Problem(energy=lambda x, p, k=k: 0.5 * jnp.sum((x - k) ** 2), x0=jnp.zeros(2))
        assert float(jnp.max(jnp.abs(S.solve(problem).x - k))) == 0.0
        assert len(S.JITTED) <= 3
    assert S.compiled_solver_count() <= 3
