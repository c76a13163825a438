"""JAX's persistent compilation cache, on by default for the command line and `verify`.

A cold process still traces each solver, but loads the compiled program from disk instead of
running XLA again.  The folder is `$DDGJAX_COMPILE_CACHE` when that is a path, otherwise
`ddgjax/jax` in the user's cache directory (`$XDG_CACHE_HOME`, else `~/.cache`);
`DDGJAX_COMPILE_CACHE=off` (or `0`, `false`, `no`) switches it off.  Library users opt in with
`enable()` (a library does not write to the user's disk unasked).  `enable()` also switches on
the exported solvers (`solvers/_exported.py`: a later process calls the solver without tracing
it) in the folder beside, `<folder>-solvers`, unless `DDGJAX_SOLVER_CACHE=off`.  The folders
are not bounded (JAX's default): delete them to reclaim the space.

JAX keys each entry by the lowered program, the compile options and the jaxlib version, so a
hit is the same program; the keys are stable across processes only while the traced programs
contain no process-dependent constants (an address, a process id).  JAX does not write programs
with host callbacks (`SparseDirect`'s factorisations), so those compile in every process.

`fast_compile_xla_flags()` trades run time for compile time, for processes that compile many
small programs once each (the test suite, `verify`'s workers).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["ENV", "cache_dir", "enable", "fast_compile_xla_flags"]

ENV = "DDGJAX_COMPILE_CACHE"
OFF = {"off", "0", "false", "no"}


FUSION_EMITTERS_FLAG_JAXLIB = ((0, 10), (0, 11))
"""The jaxlib versions [from, to) known to accept `--xla_cpu_use_fusion_emitters` (XLA aborts the
process on a flag it does not know, so the flag is only passed to these)."""


def fast_compile_xla_flags(jaxlib_version: str | None = None) -> str:
    """`XLA_FLAGS` for processes that compile many small programs and run each briefly (the test
    suite, the workers of `verify`): LLVM's backend optimisation off, and XLA:CPU's elemental
    emitters instead of its MLIR fusion emitters.  Together they compile a Newton solver in
    about half the time of XLA's defaults (`python benchmarks/compile_size.py`); the programs run
    slower, which matters only for long runs.  Set before the JAX backend starts (the first
    computation), e.g. `os.environ.setdefault("XLA_FLAGS", fast_compile_xla_flags())`."""
    if jaxlib_version is None:
        from importlib.metadata import PackageNotFoundError, version

        try:
            jaxlib_version = version("jaxlib")
        except PackageNotFoundError:
            jaxlib_version = "0"
    major_minor = tuple(int(part) for part in (jaxlib_version.split(".") + ["0"])[:2] if part.isdigit())
    lo, hi = FUSION_EMITTERS_FLAG_JAXLIB
    flags = ["--xla_backend_optimization_level=0"]
    if lo <= major_minor < hi:
        flags.append("--xla_cpu_use_fusion_emitters=false")
    return " ".join(flags)


def cache_dir(environ=os.environ) -> Path | None:
    """The cache folder this environment asks for, or None when it is switched off."""
    value = environ.get(ENV, "").strip()
    if value.lower() in OFF:
        return None
    if value:
        return Path(value).expanduser()
    base = environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "ddgjax" / "jax"


def enable(path: str | os.PathLike | None = None) -> Path | None:
    """Switch JAX's persistent compilation cache on in this process and in processes it spawns.

    `path` defaults to `cache_dir()`; returns the folder used, or None when the environment
    switches the cache off (or the folder cannot be created: compiling without a cache is
    always correct).  Every program is cached, however short its compilation.
    """
    folder = Path(path) if path is not None else cache_dir()
    if folder is None:
        return None
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    import jax

    settings = {
        "jax_compilation_cache_dir": str(folder),
        "jax_persistent_cache_min_compile_time_secs": 0.0,
        "jax_persistent_cache_min_entry_size_bytes": 0,
    }
    for name, value in settings.items():
        jax.config.update(name, value)
        os.environ[name.upper()] = str(value)  # spawned workers (`verify --jobs`) read these
    from solvers._exported import FOLDER_ENV

    if os.environ.get(FOLDER_ENV, "").strip().lower() not in OFF:
        os.environ[FOLDER_ENV] = str(folder.with_name(f"{folder.name}-solvers"))
    return folder
