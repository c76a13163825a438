"""Issue 9 (scale): batches of parameters over devices, declared locality of every catalogue
problem (the sparse KKT matrix assembled from local blocks equals the dense autodiff one), and
the sparse, Krylov and dense solves agreeing."""

import os
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import tree_max_abs_diff

import ddgjax as dg
from ddgjax import quaternion as qt
from energies import area, dirichlet, elastica, pendulum, rod
from solvers import solve, solve_batch
from solvers._kkt import KKT, spec_of
from solvers._dense import DenseLU
from solvers._klu import KLU
from solvers._sparse import cached_pattern

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _elastica(n=10, chord=(0.6, 0.2, 0.0)):
    return elastica.clamped(n, chord=chord, t_start=(1, 0, 0), t_end=(0, 1, 0))


def _chords(batch):
    return jnp.stack([jnp.array([0.5 + 0.2 * k / batch, 0.2, 0.05 * np.sin(k)]) for k in range(batch)])


@pytest.mark.parametrize("method", ["sparse", pytest.param("dense", marks=pytest.mark.slow)])
def test_batch_of_1000_elastica_equals_a_loop(method):
    """One call solves 1,000 clamped elastica with different chords; members equal single solves."""
    problem, chords = _elastica(), _chords(1000)
    batch = solve_batch(problem, {"chord": chords}, method=method)
    assert batch.x.shape == (1000, 10, 3)
    assert bool(np.all(batch.converged)) and float(jnp.max(batch.residual)) <= 1e-10
    for k in (0, 377, 999):
        single = solve(problem.with_params({**problem.params, "chord": chords[k]}), method="dense")
        assert float(jnp.max(jnp.abs(batch.x[k] - single.x))) <= 1e-10
        member = jax.tree_util.tree_map(lambda a, k=k: a[k], batch.multipliers)
        assert tree_max_abs_diff(member, single.multipliers) <= 1e-8
    # the chord constraint h Σ T_k = c holds member by member
    assert float(jnp.max(jnp.abs(0.1 * batch.x.sum(axis=1) - chords))) <= 1e-12


def test_batch_errors():
    problem = _elastica()
    with pytest.raises(dg.errors.ShapeError):
        solve_batch(problem, {"chord": jnp.zeros((3, 3)), "h": jnp.zeros((2,))})
    with pytest.raises(dg.errors.InvalidInputError):
        solve_batch(problem, {"chord": _chords(2)}, method="lbfgs")


@pytest.mark.slow
def test_batch_raises_naming_the_member_that_did_not_converge():
    problem = _elastica()
    with pytest.raises(dg.errors.ConvergenceError, match="member 0"):
        solve_batch(problem, {"chord": _chords(2)}, max_steps=1)


SHARDED = textwrap.dedent(
    """
    import jax, jax.numpy as jnp, numpy as np
    from energies import elastica
    from solvers import solve_batch
    assert len(jax.devices()) == 2, jax.devices()
    problem = elastica.clamped(10, chord=(0.6, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))
    for method, size in (("sparse", 5), ("dense", 4), ("krylov", 4)):
        chords = jnp.stack([jnp.array([0.5 + 0.04 * k, 0.2, 0.0]) for k in range(size)])
        plain = solve_batch(problem, {"chord": chords}, method=method)
        shared = solve_batch(problem, {"chord": chords}, method=method, devices="all")
        if size % 2 == 0:
            assert len(shared.x.sharding.device_set) == 2, shared.x.sharding
        print(method, float(jnp.max(jnp.abs(plain.x - shared.x))), bool(np.all(shared.converged)))
    """
)


@pytest.mark.slow
def test_batch_sharded_over_two_cpu_devices_equals_unsharded():
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2", JAX_PLATFORMS="cpu")
    out = subprocess.run([sys.executable, "-c", SHARDED], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    lines = dict(line.split(" ", 1) for line in out.stdout.strip().splitlines())
    for method in ("sparse", "dense", "krylov"):
        diff, converged = lines[method].split()
        assert float(diff) <= 1e-12 and converged == "True"


# ---- declared locality of the catalogue: sparse KKT matrix == dense KKT matrix ----------------

START = qt.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi / 2)
END = qt.from_axis_angle(np.array([0.0, 0.0, 1.0]), -np.pi / 2)


def _saddle_disk():
    V, F = dg.mesh.disk(2, 8)
    V = np.array(V, dtype=float)
    V[:, 2] = 0.3 * (V[:, 0] ** 2 - V[:, 1] ** 2) + 0.02 * np.random.default_rng(0).normal(size=len(V))
    return V, F


def _graph():
    rng = np.random.default_rng(3)
    edges = np.array([[k, k + 1] for k in range(11)] + [[0, 5], [2, 9], [3, 11], [1, 7]])
    return dirichlet.graph(edges, rng.uniform(0.5, 2.0, len(edges)), [0, 11], [0.0, 1.0])


def _cotan():
    V, F = dg.mesh.disk(2, 8)
    b = dg.mesh.boundary_vertices(F, len(V))
    return dirichlet.cotan(np.asarray(V, float), F, b, np.cos(3 * np.arange(len(b))))


CATALOGUE = {
    "elastica edge clamp": lambda: _elastica(9),
    "elastica vertex clamp": lambda: elastica.clamped(9, chord=(0.5, 0.3, 0.1), t_start=(1, 0, 0), t_end=(0, 1, 0), clamp="vertex"),
    "rod": lambda: rod.clamped(8, alpha=0.7, chord=[0.6, 0, 0], frame_start=START, frame_end=END),
    "pendulum action": lambda: pendulum.action(9, a=[0.0, 0.0, -2.0], T_first=[1.0, 0.2, 0.0], T_last=[-0.2, 1.0, 0.4]),
    "graph dirichlet": _graph,
    "cotan dirichlet": _cotan,
    "simplicial area": lambda: area.simplicial(*_saddle_disk()),
}


def _dense_from_coo(pattern, values):
    size = pattern.n + pattern.m
    return np.asarray(jnp.zeros((size, size)).at[pattern.rows, pattern.cols].add(values))


@pytest.mark.parametrize("name", CATALOGUE)
def test_catalogue_is_local_and_sparse_kkt_equals_dense(name):
    problem = CATALOGUE[name]()
    assert problem.is_local, f"{name}: energy/constraints not declared with dg.local_sum/local_map"
    spec = spec_of(problem)
    kkt = KKT(spec, spec.layout.ravel(problem.x0), problem.params)
    rng = np.random.default_rng(7)
    u = kkt.spec.layout.ravel(problem.x0)[spec.layout.free] + 0.01 * rng.normal(size=spec.n)
    w = jnp.concatenate([u, jnp.asarray(rng.normal(size=spec.m))])
    sparse = KLU(cached_pattern(spec, problem.x0, problem.params))
    K_sparse = _dense_from_coo(sparse.pattern, jax.jit(lambda w: sparse.matrix(kkt, w))(w))
    K_dense = np.asarray(jax.jit(lambda w: DenseLU().matrix(kkt, w))(w))
    assert np.max(np.abs(K_sparse - K_dense)) <= 1e-12 * max(1.0, np.max(np.abs(K_dense)))


FAST = ("simplicial area", "elastica vertex clamp")


@pytest.mark.parametrize("name", [n if n in FAST else pytest.param(n, marks=pytest.mark.slow) for n in CATALOGUE])
def test_catalogue_sparse_krylov_and_dense_solves_agree(name):
    """Issue 9: the three linear-algebra paths reach the same critical point and multipliers."""
    problem = CATALOGUE[name]()
    dense = solve(problem, method="dense", tol=1e-11)
    for method in ("sparse", "krylov"):
        other = solve(problem, method=method, tol=1e-11)
        assert float(jnp.max(jnp.abs(other.x - dense.x))) <= 1e-10, method
        assert abs(float(other.energy) - float(dense.energy)) <= 1e-10 * max(1.0, abs(float(dense.energy))), method
        if problem.n_constraints:
            assert tree_max_abs_diff(other.multipliers, dense.multipliers) <= 1e-10, method
