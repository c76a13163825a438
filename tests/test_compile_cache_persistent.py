"""The persistent compilation cache (`ddgjax.compile_cache`): where it lives, how it is switched
off, and that a second process loads the solver the first compiled instead of compiling it.

A program hits only if its lowered text is the same in every process: the KLU analysis' address
is therefore an argument of the solver, not a constant (`solvers/_klu.py`), in `solve` and in
`solve_batch` alike.  The negative control
bakes a process-dependent constant into a program and sees it miss.  Programs with host callbacks
(the `SparseDirect` factorisations) are never cached: they neither hit nor miss, they compile
(`compiles` counts XLA's compilations).

The solver itself is exported by the first process (`solvers/_exported.py`), into the folder
beside the cache's, and called by the second without being traced again.

The cases run as the sections of one probe, in a first and a second process on the same empty
cache folder (two interpreters for all cases, not two per case); each section's events are
counted apart.  Sections compile disjoint programs, and run in the same order in both processes.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ddgjax import compile_cache

SECTIONS = {
    "solve": """
from energies import elastica
from solvers import solve, KLU
result = solve(elastica.clamped(12, chord=(0.5, 0.2, 0), t_start=(1, 0, 0), t_end=(0, 1, 0)), linear_solver=KLU())
""",
    "dense": """
from energies import elastica
from solvers import solve
result = solve(elastica.clamped(9, chord=(0.5, 0.2, 0), t_start=(1, 0, 0), t_end=(0, 1, 0)), method="dense")
""",
    "solve_batch": """
import numpy as np
from energies import elastica
from solvers import solve_batch
problem = elastica.clamped(10, chord=(0.5, 0.2, 0), t_start=(1, 0, 0), t_end=(0, 1, 0))
result = solve_batch(problem, {"chord": np.array([[0.5, 0.2, 0.0], [0.55, 0.2, 0.1]])}, method="sparse")
""",
    "klu_inside_jit": """
import jax, jax.numpy as jnp
from energies import elastica
from solvers import solve, KLU
problem = elastica.clamped(8, chord=(0.5, 0.2, 0), t_start=(1, 0, 0), t_end=(0, 1, 0))
energy = jax.jit(lambda c: solve(problem.with_params({**problem.params, "chord": c}), linear_solver=KLU(),
                                 throw=False).energy)
result = energy(jnp.array([0.45, 0.2, 0.0]))
""",
    "process_dependent": """
import os, jax, jax.numpy as jnp
jax.jit(lambda x: x + os.getpid())(jnp.zeros(3)).block_until_ready()
""",
    "no_steps": """
import ddgjax as dg
from energies import area
from solvers import solve, SparseDirect
V, F = dg.mesh.disk(1, 6)
solve(area.simplicial(V + [0, 0, 0.1] * (V[:, :1] > 0), F), linear_solver=SparseDirect(), max_steps=0, throw=False)
""",
    "host_callback": """
import jax, jax.numpy as jnp, numpy as np
jax.jit(lambda x: jax.pure_callback(np.sin, x, x))(jnp.zeros(4)).block_until_ready()
""",
}

PROBE = """
import hashlib, json, sys
import numpy as np
import jax
from jax._src import compiler, monitoring
events, lowered = [], []
monitoring.register_event_listener(lambda event, **kw: events.append(event))
monitoring.register_event_duration_secs_listener(
    lambda event, duration, **kw: lowered.append(kw.get("fun_name")) if event.endswith("jaxpr_to_mlir_module_duration") else None)
_compile = compiler.backend_compile_and_load
def counted(*args, **kwargs):
    events.append("compile")
    return _compile(*args, **kwargs)
compiler.backend_compile_and_load = counted
from ddgjax import compile_cache
compile_cache.enable(sys.argv[1])
counts = {}
for name, code in json.loads(sys.argv[2]).items():
    del events[:], lowered[:]
    scope = {}
    exec(code, scope)
    leaves = [np.asarray(leaf) for leaf in jax.tree_util.tree_leaves(scope.get("result"))]
    counts[name] = {"hits": events.count("/jax/compilation_cache/cache_hits"),
                    "misses": events.count("/jax/compilation_cache/cache_misses"),
                    "compiles": events.count("compile"), "lowered": sorted(lowered),
                    "result": hashlib.sha256(b"".join(leaf.tobytes() for leaf in leaves)).hexdigest()}
print(json.dumps(counts))
"""


def cache_events(cache: Path) -> dict:
    """`{section: {"hits", "misses", "compiles"}}` of one process running every section."""
    out = subprocess.run([sys.executable, "-c", PROBE, str(cache), json.dumps(SECTIONS)], capture_output=True,
                         text=True, timeout=300, env={k: v for k, v in os.environ.items() if k != compile_cache.ENV})
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def processes(tmp_path_factory) -> tuple[dict, dict]:
    """The events of a first and a second process on the same (initially empty) cache folder."""
    cache = tmp_path_factory.mktemp("jax-cache")
    return cache_events(cache), cache_events(cache)


def test_a_second_process_loads_what_the_first_compiled_and_exported(processes):
    """One test for the sections of the two processes (pytest-xdist would otherwise run the
    module fixture, two interpreters, once per worker that takes a part of the module):
    - a solve: the second process loads every compiled program, misses none, compiles none;
    - the solver itself (`solvers/_exported.py`): the first process traces and lowers it once
      (its export) and compiles its call; the second loads the executable kept beside it,
      neither tracing nor lowering the solver, and the solutions agree bit for bit;
    - a dense solve: the same, with LAPACK's LU in the loaded executable (bound before it runs);
    - a batch solve: the same; its program is exported by the first process and loaded
      untraced by the second, and the KLU analysis' address is its argument (the bound linear
      solver's leaf), not a constant;
    - a KLU solve inside the caller's own `jit` (with `throw=False`: no host callback): the
      second process loads the caller's program; KLU analyses the pattern inside it, as the
      analysis' address would be a constant of it;
    - negative control: a program with a process-dependent constant misses;
    - `max_steps=0` (the hand-off of `minimize`) compiles only the KKT residual at x0: no
      factorisation, so no host callback, which JAX never caches: the second process loads it;
    - control (what a `SparseDirect` factorisation is): a host callback is neither a hit nor a
      miss but a compilation, in every process."""
    first, second = processes
    solve_1, solve_2 = first["solve"], second["solve"]
    assert solve_1["misses"] > 0
    assert {k: solve_2[k] for k in ("misses", "compiles")} == {"misses": 0, "compiles": 0}
    assert "jit(_solve_impl)" in solve_1["lowered"] and "jit(call)" in solve_1["lowered"]
    assert "jit(_solve_impl)" not in solve_2["lowered"] and "jit(call)" not in solve_2["lowered"]
    assert solve_2["result"] == solve_1["result"]
    dense_1, dense_2 = first["dense"], second["dense"]
    assert dense_1["misses"] > 0 and {k: dense_2[k] for k in ("misses", "compiles")} == {"misses": 0, "compiles": 0}
    assert "jit(call)" not in dense_2["lowered"] and dense_2["result"] == dense_1["result"]
    batch_1, batch_2 = first["solve_batch"], second["solve_batch"]
    assert batch_1["misses"] > 0 and "jit(_batch_impl)" in batch_1["lowered"]
    assert {k: batch_2[k] for k in ("misses", "compiles")} == {"misses": 0, "compiles": 0}
    assert "jit(_batch_impl)" not in batch_2["lowered"] and "jit(call)" not in batch_2["lowered"]
    assert batch_2["result"] == batch_1["result"]
    jitted_1, jitted_2 = first["klu_inside_jit"], second["klu_inside_jit"]
    assert jitted_1["misses"] > 0 and {k: jitted_2[k] for k in ("misses", "compiles")} == {"misses": 0, "compiles": 0}
    assert jitted_2["result"] == jitted_1["result"]
    assert second["process_dependent"]["misses"] >= 1
    assert first["no_steps"]["misses"] > 0 and second["no_steps"]["compiles"] == 0
    assert second["host_callback"]["misses"] == 0 and second["host_callback"]["compiles"] == 1


@pytest.mark.parametrize("value", ["off", "0", "False", " no "])
def test_the_environment_switches_it_off(value):
    assert compile_cache.cache_dir({compile_cache.ENV: value}) is None


def test_the_folder_is_the_environment_path_or_the_user_cache(tmp_path):
    assert compile_cache.cache_dir({compile_cache.ENV: str(tmp_path / "c")}) == tmp_path / "c"
    assert compile_cache.cache_dir({"XDG_CACHE_HOME": str(tmp_path)}) == tmp_path / "ddgjax" / "jax"
    assert compile_cache.cache_dir({}) == Path.home() / ".cache" / "ddgjax" / "jax"


def test_an_unwritable_folder_leaves_the_cache_off(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert compile_cache.enable(blocker / "cache") is None


@pytest.mark.parametrize("version, emitters_flag", [("0.10.2", True), ("0.10.0rc1", True), ("0.9.9", False),
                                                    ("0.11.0", False), ("1.0", False)])
def test_fast_compile_flags_pass_the_emitter_flag_only_to_jaxlibs_known_to_accept_it(version, emitters_flag):
    """XLA aborts the process on an unknown flag: the flag goes only to the tested jaxlib range."""
    flags = compile_cache.fast_compile_xla_flags(version).split()
    assert "--xla_backend_optimization_level=0" in flags
    assert ("--xla_cpu_use_fusion_emitters=false" in flags) is emitters_flag


def test_enable_puts_the_exported_solvers_beside_the_cache_unless_they_are_switched_off(tmp_path, monkeypatch):
    import jax
    from solvers._exported import FOLDER_ENV, solver_dir

    monkeypatch.setattr(jax.config, "update", lambda *args: None)  # this process keeps its cache
    for name in ("JAX_COMPILATION_CACHE_DIR", "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS",
                 "JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES", FOLDER_ENV):
        monkeypatch.setenv(name, os.environ.get(name, ""))
    compile_cache.enable(tmp_path / "c")
    assert solver_dir() == tmp_path / "c-solvers"
    monkeypatch.setenv(FOLDER_ENV, "off")
    compile_cache.enable(tmp_path / "c")
    assert solver_dir() is None
