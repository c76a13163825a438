"""Solver programs kept across processes: the lowered solver exported to disk, keyed by content.

`Program` (and the decorator `programs`) compiles a function of a declaration, `fn(spec, ...)`:
`solve`'s Newton solver, and the continuation, stability and `minimize` programs.

JAX's persistent compilation cache (`ddgjax.compile_cache`) saves XLA's compilation, but a new
process still traces and lowers the whole Newton solver (second derivatives, line search,
linear algebra) before it can look the program up: most of a cold solve.  Here the lowered
solver is exported (`jax.export`), serialised into the folder `FOLDER_ENV` names (set by
`ddgjax.compile_cache.enable()`), and called by later processes (`Exported.call`) after tracing
only the energy and the constraints; XLA's program for the call then comes from the
compilation cache.

The file's name is the SHA-256 of everything the solver's trace reads (`program_key`):
- the energy's and the constraints' jaxprs at the arguments' shapes, with the bytes of every
  constant and literal in them (a jaxpr names a custom derivative rule or a host callback
  without its code, so a function with one is never exported);
- the declaration's locality (stencils, cell data, reductions, groups), the layout of the
  unknowns, the constraints' structure, and the bound linear solver's static part (its
  sparsity pattern by value);
- the solve's options and the arguments' tree, shapes, dtypes and weak types;
- the library's own source below its application layer (`APPLICATION`), the versions of JAX
  and of the libraries traced into the solver, the backend and JAX's tracing flags.

Beside each exported program, its compiled executable is kept (`jax.experimental.
serialize_executable`), under the program's key and `executable_digest()`: the XLA flags, the
backend's platform version and the host's processor.  A later process with a file for both keys
loads the executable directly: no export to read, no call to lower, no compilation-cache key to
compute, only XLA's own deserialisation.  A different flag or machine compiles the exported
program anew (through the compilation cache) and keeps its executable beside the first.  An
executable XLA:CPU loaded from the compilation cache serialises without its kernels, so a
process that finds the call there (its executable removed) compiles it once more, outside
that cache, to keep it (`_compiled_here`).

An input the key cannot describe by value (a Python function, an unknown type) sends the solve
down the ordinary path (`NotDescribed`): a key that missed an input would return a stale
program, i.e. a wrong answer.  Only concrete calls on one device are exported (under `jit`,
`vmap` or `grad` the solver is traced as usual, which keeps its implicit derivatives), and only
programs without host callbacks (`SparseDirect`'s factorisations cannot be serialised; its
programs that only assemble the KKT matrix can).
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import hashlib
import os
import pickle
import platform
import types
import uuid
import zlib
from pathlib import Path
from typing import Callable

import jax
import numpy as np

from ddgjax.locality import Local, Term

from ._cache import LRU, cleared_by_jax
from ._dense import DenseLU
from ._direct import SparseDirect
from ._kkt import Spec
from ._klu import KLU, ffi_targets
from ._linear import LinearSolver
from ._sparse import PatternKey, SparsePattern

FOLDER_ENV = "DDGJAX_SOLVER_CACHE"
"""The folder of the exported programs (`ddgjax.compile_cache.enable()` sets it beside the
compilation cache unless it is `off`); unset or `off`, nothing is exported."""

FORMAT = b"ddgjax exported solver 1\n"
"""The first bytes of every file, and of every key: a new format never reads an old file."""

EXPORTABLE = (DenseLU, KLU, SparseDirect)
"""The linear solvers whose static part the key describes by value.  A program with a host
callback (`SparseDirect`'s factorisations) cannot be exported: the first process records that
in the program's file (`NOT_EXPORTABLE`), and later ones trace it as usual at once."""

NOT_EXPORTABLE = b"not exportable\n"
"""The content of a program's file, after `FORMAT`, when the program could not be exported."""

TRACED_LIBRARIES = ("jax", "jaxlib", "numpy", "klujax", "equinox", "lineax", "optimistix", "jaxopt")
"""Distributions whose code runs while the solver is traced (their versions are in the key)."""

TRACING_FLAGS = ("jax_enable_x64", "jax_default_matmul_precision", "jax_numpy_rank_promotion",
                 "jax_numpy_dtype_promotion", "jax_enable_checks", "jax_default_prng_impl")
"""JAX's flags that change what a trace produces (in the key)."""

NOT_DESCRIBED_BY_VALUE = {Term: ("fn",), Local: ("hash_value",), SparsePattern: ("key",)}
"""Fields left out of the structural description: a term's density is described by the
energy's jaxpr, a declaration's hash and a pattern's key by the declaration itself."""

RULES = ("custom_jvp_call", "custom_vjp_call", "custom_vjp_call_jaxpr", "custom_lin", "pure_callback",
         "io_callback", "debug_callback")
"""Primitives that run Python code (derivative rules, host callbacks) a jaxpr does not show."""

JAX_SOURCE = Path(jax.__file__).resolve().parent
"""JAX's package folder: derivative rules defined there are described by JAX's version."""

FUNCTIONS = (types.FunctionType, types.MethodType, types.BuiltinFunctionType, functools.partial)
"""Python code in an equation's parameters (which a jaxpr prints by name only)."""


class NotDescribed(Exception):
    """An input of the solver that the key cannot describe by value."""


# --- the key -------------------------------------------------------------------------------------


def _feed(h, obj) -> None:
    """Add a description of `obj` by value to the hash `h`, or raise `NotDescribed`."""
    if obj is None or isinstance(obj, (bool, int, float, complex, str)):
        h.update(f"{type(obj).__name__}:{obj!r};".encode())
    elif isinstance(obj, bytes):
        h.update(b"bytes:%d:" % len(obj) + obj)
    elif isinstance(obj, jax.core.Tracer):
        raise NotDescribed("a traced value")
    elif isinstance(obj, (np.ndarray, np.generic, jax.Array)):
        a = np.ascontiguousarray(np.asarray(obj))
        h.update(f"array:{a.dtype.str}:{a.shape}:".encode())
        h.update(a.tobytes())
    elif isinstance(obj, (tuple, list)):
        h.update(f"{type(obj).__name__}[{len(obj)}](".encode())
        for item in obj:
            _feed(h, item)
        h.update(b")")
    elif isinstance(obj, dict):
        h.update(f"dict[{len(obj)}](".encode())
        for k in sorted(obj, key=repr):
            _feed(h, k)
            _feed(h, obj[k])
        h.update(b")")
    elif isinstance(obj, jax.tree_util.PyTreeDef):
        _feed_treedef(h, obj)
    elif isinstance(obj, type):
        h.update(f"type:{obj.__module__}.{obj.__qualname__};".encode())
    elif isinstance(obj, np.dtype):
        h.update(f"dtype:{obj.str};".encode())
    elif isinstance(obj, enum.Enum):
        _feed(h, type(obj))
        _feed(h, obj.name)
    elif isinstance(obj, PatternKey):
        _feed(h, obj.pattern)
    elif isinstance(obj, jax.ShapeDtypeStruct):
        _feed(h, (obj.shape, np.dtype(obj.dtype), bool(obj.weak_type)))
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        _feed(h, type(obj))
        skipped = NOT_DESCRIBED_BY_VALUE.get(type(obj), ())
        for f in dataclasses.fields(obj):
            if f.name not in skipped:
                _feed(h, f.name)
                _feed(h, getattr(obj, f.name))
    else:
        raise NotDescribed(f"{type(obj).__module__}.{type(obj).__qualname__}")


def _feed_treedef(h, treedef) -> None:
    """A tree structure: every node's type and static data, depth first."""
    node = treedef.node_data()
    if node is None:
        h.update(b"*")
        return
    kind, aux = node
    _feed(h, kind)
    _feed(h, aux)
    children = treedef.children()
    h.update(b"<%d" % len(children))
    for child in children:
        _feed_treedef(h, child)
    h.update(b">")


def _feed_jaxpr(h, closed) -> None:
    """A closed jaxpr: its text, and the bytes of its constants and literals at every depth."""
    h.update(str(closed.jaxpr).encode())
    _feed_values(h, closed)


def _feed_values(h, closed) -> None:
    for const in closed.consts:
        _feed(h, const)
    _feed_equations(h, closed.jaxpr)


def _feed_equations(h, jaxpr) -> None:
    from jax.extend.core import ClosedJaxpr, Jaxpr, Literal

    def param(value):
        if isinstance(value, ClosedJaxpr):
            _feed_values(h, value)
        elif isinstance(value, Jaxpr):
            _feed_equations(h, value)
        elif isinstance(value, (tuple, list)):
            for item in value:
                param(item)
        elif isinstance(value, FUNCTIONS):
            raise NotDescribed(f"a Python function in the jaxpr ({value!r})")

    for eqn in jaxpr.eqns:
        if eqn.primitive.name in RULES and not _rule_of_jax(eqn):
            raise NotDescribed(f"Python code in a {eqn.primitive.name}")
        for var in eqn.invars:
            if isinstance(var, Literal):
                _feed(h, np.asarray(var.val))
        for value in eqn.params.values():
            param(value)


def _rule_of_jax(eqn) -> bool:
    """Whether `eqn` is a `custom_jvp_call` whose derivative rule is JAX's own code (e.g.
    `jnp.frexp`'s), which JAX's version in the key describes; the rule's source file is read
    from its debug information."""
    if eqn.primitive.name != "custom_jvp_call":
        return False
    info = getattr(eqn.params.get("jvp_jaxpr_fun"), "debug_info", None)
    where = getattr(info, "func_src_info", None) or ""
    path = where.rpartition(" at ")[2].rpartition(":")[0]
    return bool(path) and Path(path).resolve().is_relative_to(JAX_SOURCE)


def _abstract(leaf) -> jax.ShapeDtypeStruct:
    aval = jax.typeof(leaf)
    return jax.ShapeDtypeStruct(aval.shape, aval.dtype, weak_type=aval.weak_type)


def _feed_function(h, fn: Callable, *args) -> None:
    """`fn`'s jaxpr at the shapes of `args` (pytrees of `jax.ShapeDtypeStruct`), and, for a
    declaration of locality, its structure."""
    _feed_jaxpr(h, jax.make_jaxpr(fn)(*args))
    if isinstance(fn, Local):
        _feed(h, fn)


APPLICATION = ("ddgjax/verify", "ddgjax/plot", "ddgjax/cli.py", "ddgjax/sweep.py", "ddgjax/__main__.py")
"""The application layer, above the solvers (connectivity → geometry → energies → solvers →
verify, plots, command line), left out of `source_digest`: the solvers never import it, so its
code reaches a solver's trace only as an energy or a constraint, which the key describes by its
jaxpr.  Editing a check of `verify` or the command line keeps the exported programs."""


@functools.lru_cache(maxsize=None)
def source_digest(root: Path | None = None) -> bytes:
    """SHA-256 of the library's source below the application layer: every `.py` file of
    `ddgjax`, `energies` and `solvers` under `root` (this library's folder by default) except
    those of `APPLICATION`."""
    h = hashlib.sha256()
    root = Path(__file__).resolve().parent.parent if root is None else Path(root)
    for package in ("ddgjax", "energies", "solvers"):
        for path in sorted((root / package).rglob("*.py")):
            name = path.relative_to(root).as_posix()
            if any(name == part or name.startswith(part + "/") for part in APPLICATION):
                continue
            h.update(name.encode() + b"\0")
            h.update(path.read_bytes())
    return h.digest()


@functools.lru_cache(maxsize=None)
def environment_digest() -> bytes:
    """The library's source, the versions of what the solver's trace runs, the backend and
    JAX's tracing flags."""
    from importlib.metadata import PackageNotFoundError, version

    h = hashlib.sha256(FORMAT + source_digest())
    for name in TRACED_LIBRARIES:
        try:
            _feed(h, (name, version(name)))
        except PackageNotFoundError:
            _feed(h, (name, None))
    device = jax.devices()[0]
    _feed(h, (jax.default_backend(), device.platform, device.device_kind))
    _feed(h, tuple((flag, str(getattr(jax.config, flag))) for flag in TRACING_FLAGS))
    return h.digest()


def program_key(spec: Spec, static: dict, treedef, avals: tuple) -> str:
    """The hex key of the program of `spec` with options `static` on arguments of structure
    `treedef` and shapes `avals` (module docstring): `(linear solver, z0, params, ...)` or
    `(z0, params, ...)`, z0 the flat unknowns; raises `NotDescribed`."""
    h = hashlib.sha256(environment_digest())
    _feed(h, sorted(static.items()))
    _feed(h, treedef)
    _feed(h, avals)
    layout = spec.layout
    _feed(h, (layout.treedef, layout.shapes, layout.free))
    _feed(h, spec.constraint_structure)
    _feed(h, (spec.is_local, spec.has_scale))
    args = jax.tree_util.tree_unflatten(treedef, avals)
    first = 1 if isinstance(args[0], LinearSolver) else 0
    z0, params = args[first : first + 2]
    x = jax.tree_util.tree_unflatten(layout.treedef, [jax.ShapeDtypeStruct(s, z0.dtype) for s in layout.shapes])
    _feed_function(h, spec.energy, x, params)
    if spec.constraints is not None:
        _feed_function(h, spec.constraints, x, params)
    return h.hexdigest()


# --- export, store, load -------------------------------------------------------------------------


def _exported(impl: functools.partial, treedef, leaves: list, targets: tuple[str, ...]):
    """`(exported, out_tree)`: `impl` on the flattened arguments, exported (under `impl`'s
    function's name), with the custom calls `targets` allowed."""
    out_tree = []

    def flat(*flat_args):
        out = impl(*jax.tree_util.tree_unflatten(treedef, flat_args))
        leaves_out, tree = jax.tree_util.tree_flatten(out)
        out_tree.append(tree)
        return leaves_out

    flat.__name__ = flat.__qualname__ = impl.func.__name__

    allowed = [jax.export.DisabledSafetyCheck.custom_call(name) for name in targets]
    exported = jax.export.export(jax.jit(flat), disabled_checks=allowed)(*leaves)
    return exported, out_tree[0]


def _write(path: Path, body: Callable[[], bytes]) -> None:
    """Write `FORMAT + body()` to `path` atomically (a partly written file is never read: another
    process may be reading); a body that cannot be made or written is left unsaved."""
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        data = FORMAT + body()
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_bytes(data)
        os.replace(tmp, path)
    except Exception:  # a full disk, no flatbuffers, a tree that does not pickle: run it unsaved
        tmp.unlink(missing_ok=True)


def _read(path: Path) -> bytes | None:
    """The body of the file at `path` after `FORMAT`, or None if it is absent or foreign."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    return data[len(FORMAT):] if data.startswith(FORMAT) else None


def _store(path: Path, exported=None, out_tree=None) -> None:
    """Write the program (`NOT_EXPORTABLE` without one)."""
    _write(path, lambda: NOT_EXPORTABLE if exported is None else pickle.dumps((bytes(exported.serialize()), out_tree)))


def _load(path: Path):
    """`(exported, out_tree)` from `path`, `NOT_EXPORTABLE`, or None if it is absent or unreadable."""
    body = _read(path)
    if body is None or body == NOT_EXPORTABLE:
        return None if body is None else NOT_EXPORTABLE
    try:
        serialized, out_tree = pickle.loads(body)
        return jax.export.deserialize(bytearray(serialized)), out_tree
    except Exception:  # a truncated or foreign file: export anew and overwrite it
        return None


@functools.lru_cache(maxsize=None)
def executable_digest() -> str:
    """What an executable depends on beyond its program's key: the XLA flags of this process,
    the backend's platform version and the host's processor (its model and instruction set,
    which XLA:CPU compiles for)."""
    h = hashlib.sha256(FORMAT)
    backend = jax.devices()[0].client
    _feed(h, (os.environ.get("XLA_FLAGS", ""), backend.platform, backend.platform_version, platform.machine()))
    try:
        cpu = Path("/proc/cpuinfo").read_text().split("\n\n")[0]  # the first processor's block
        _feed(h, tuple(line for line in cpu.splitlines() if line.split(":")[0].strip() in ("model name", "flags")))
    except OSError:
        _feed(h, platform.processor())
    return h.hexdigest()[:16]


_HITS = [0]


@functools.lru_cache(maxsize=None)
def _count_cache_hits() -> None:
    """Count the compilation cache's hits in `_HITS` from now on (registered once)."""

    def count(event: str, **_) -> None:
        if event == "/jax/compilation_cache/cache_hits":
            _HITS[0] += 1

    jax.monitoring.register_event_listener(count)


def _cache_hits() -> int:
    """The compilation cache's hits so far in this process (counted from the first call).

    An executable XLA:CPU loaded from the cache serialises without its compiled kernels (a
    process that loads it fails with "Function ... not found"): one found there is compiled once
    more in this process (`_compiled_here`) to be kept."""
    _count_cache_hits()
    return _HITS[0]


def _compiled_here(call: Callable, avals: tuple):
    """`call` at `avals` compiled in this process, bypassing JAX's compilation cache: under a
    module name of its own (the cache's key includes it) and not written there.  The
    executable of a program whose compilation-cache entry outlived its kept executable (a file
    removed, or written by an older library) is thus kept again once, not loaded from the cache
    in every later process."""
    from jax._src import config

    def fresh(*args):
        return call(*args)

    fresh.__name__ = fresh.__qualname__ = f"call_{uuid.uuid4().hex}"
    with config.persistent_cache_min_compile_time_secs(float("inf")):
        return jax.jit(fresh).lower(*avals).compile()


def _store_executable(path: Path, compiled, out_tree) -> None:
    """Write `compiled` (a `jax.stages.Compiled` of the flat program) serialised and compressed,
    with the tree of the outputs `out_tree`."""
    from jax.experimental.serialize_executable import serialize

    _write(path, lambda: zlib.compress(pickle.dumps((*serialize(compiled), out_tree)), 1))


def _load_executable(path: Path):
    """`(compiled, out_tree)` stored at `path`, or None if it is absent or unreadable."""
    from jax.experimental.serialize_executable import deserialize_and_load

    body = _read(path)
    if body is None:
        return None
    try:
        # LAPACK's kernels (LU, eigh) are bound when JAX lowers a call to them, which a loaded
        # program skips: bind them now, or the program calls null pointers
        from jax._src.lax.linalg import initialize_lapack

        initialize_lapack()
        payload, in_tree, flat_out_tree, out_tree = pickle.loads(zlib.decompress(body))
        return deserialize_and_load(payload, in_tree, flat_out_tree, execution_devices=jax.devices()[:1]), out_tree
    except Exception:  # truncated (zlib's checksum), foreign, or from another JAX: compile anew
        return None


def solver_dir(environ=os.environ) -> Path | None:
    """The folder of the exported programs (`FOLDER_ENV`), or None."""
    value = environ.get(FOLDER_ENV, "").strip()
    return Path(value) if value and value.lower() not in ("off", "0", "false", "no") else None


# --- the programs --------------------------------------------------------------------------------


DEBUGGING = ("jax_disable_jit", "jax_debug_nans", "jax_debug_infs")
"""JAX's flags under which programs run as `jax.jit` runs them (op by op), never exported."""


def _exportable(args, leaves) -> bool:
    """Concrete arguments, one device, no linear solver outside `EXPORTABLE`, no debugging flag."""
    return (jax.device_count() == 1 and not any(isinstance(leaf, jax.core.Tracer) for leaf in leaves)
            and all(isinstance(a, EXPORTABLE) for a in args if isinstance(a, LinearSolver))
            and not any(getattr(jax.config, flag) for flag in DEBUGGING))


class Program:
    """`fn(spec, *args, **static)` for one declaration `spec` and options `static`, compiled:
    through `jax.jit`, or, for concrete arguments while `solver_dir()` is set,
    through a program exported to that folder (module docstring), one per argument signature."""

    def __init__(self, fn: Callable, spec: Spec, static: dict):
        self.spec = spec
        self.static = {"function": f"{fn.__module__}.{fn.__qualname__}", **static}
        self.impl = functools.partial(fn, spec, **static)
        self.jitted = jax.jit(self.impl)
        self.calls: dict = {}  # argument signature -> the exported program's call, or None

    def __call__(self, *args):
        folder = solver_dir()
        leaves, treedef = jax.tree_util.tree_flatten(args)
        if folder is None or not _exportable(args, leaves):
            return self.jitted(*args)
        avals = tuple(_abstract(leaf) for leaf in leaves)
        signature = (treedef, avals)
        if signature not in self.calls:
            self.calls[signature] = self._call(folder, treedef, avals, leaves)
        call = self.calls[signature]
        return self.jitted(*args) if call is None else call(leaves)

    def _call(self, folder: Path, treedef, avals, leaves):
        try:
            key = program_key(self.spec, self.static, treedef, avals)
        except NotDescribed:
            return None
        path = folder / f"{key}.program"
        targets = ffi_targets()  # registered before a loaded program calls them
        executable = folder / f"{key}-{executable_digest()}.executable"
        stored = _load_executable(executable)
        if stored is not None:
            return _unflattened(*stored)
        loaded = _load(path)
        if loaded is None:
            try:
                loaded = _exported(self.impl, treedef, leaves, targets)
            except Exception:  # a host callback, an argument jax.export does not take (float0)
                _store(path)
                return None
            _store(path, *loaded)
        if loaded is NOT_EXPORTABLE:
            return None
        exported, out_tree = loaded
        hits = _cache_hits()
        compiled = jax.jit(exported.call).lower(*avals).compile()
        if _cache_hits() != hits:  # loaded from JAX's cache, which XLA:CPU cannot serialise again
            compiled = _compiled_here(exported.call, avals)
        _store_executable(executable, compiled, out_tree)
        return _unflattened(compiled, out_tree)

    def _cache_size(self) -> int:
        """Executables held: the jitted function's and one per exported signature."""
        return self.jitted._cache_size() + sum(call is not None for call in self.calls.values())


def _unflattened(compiled, out_tree) -> Callable:
    """The flat program `compiled` as a function of the flat arguments returning the outputs' tree."""
    return lambda flat: jax.tree_util.tree_unflatten(out_tree, compiled(*flat))


def programs(fn: Callable, size: int = 32) -> Callable:
    """`fn(spec, *args, **static)` compiled per declaration and options (`Program`, exported
    across processes), the `size` used last kept: a drop-in for `jax.jit` with `spec` and the
    keyword options static.  `args` are `(linear solver, z0, params, ...)` or `(z0, params,
    ...)` (`program_key`)."""
    held = cleared_by_jax(LRU(size), f"compiled {fn.__qualname__}")

    @functools.wraps(fn)
    def call(spec: Spec, *args, **static):
        return held.get((spec, tuple(sorted(static.items()))), lambda: Program(fn, spec, static))(*args)

    call.held = held
    call._cache_size = lambda: sum(program._cache_size() for program in held._items.values())  # as jax.jit's
    return call
