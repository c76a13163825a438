"""The trust audit (`tests/probes.py`) as tests: every probe of bad or extreme input ends as the
API promises (a `DDGError` naming the element, or the right answer; inputs unchanged).

The solver and command-line probes compile solvers or start processes (about a minute
together) and run with `make test-all`; `python tests/probes.py` runs all of them, each in a
worker process that may crash or hang without taking the run with it.
"""

import atexit
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

import probes as P
from ddgjax.errors import InvalidInputError

SLOW_FAMILIES = ("solve", "cli")


def _probes():
    folder = Path(tempfile.mkdtemp(prefix="ddgjax-probes-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return P.all_probes(folder)


PROBES = {p.id: p for p in _probes()}


@pytest.mark.parametrize(
    "probe_id",
    [pytest.param(i, marks=pytest.mark.slow) if p.family in SLOW_FAMILIES else i for i, p in PROBES.items()],
)
def test_probe(probe_id):
    outcome, detail = P.judge(PROBES[probe_id])
    assert outcome == "ok", f"{probe_id}: {outcome}: {detail}"


def test_there_are_probes_of_every_family_and_kind():
    families = {p.family for p in PROBES.values()}
    assert families == set(P.FAMILIES)
    assert {p.expect for p in PROBES.values()} == set(P.KINDS)
    assert len(PROBES) >= 700


def _raise_unnamed():
    raise InvalidInputError("something is wrong")


def _raise_foreign():
    raise TypeError("raw")


def _mutate(a):
    a[0] = 1.0
    return a


@pytest.mark.parametrize(
    "probe, outcome",
    [
        (P.Probe("control:returns", lambda: np.zeros(3)), "silent"),
        (P.Probe("control:nan", lambda: np.array([np.nan]), expect="finite_or_raises"), "silent"),
        (P.Probe("control:unnamed", _raise_unnamed, names=(r"vertex 3",)), "unnamed"),
        (P.Probe("control:foreign", _raise_foreign), "foreign"),
        (P.Probe("control:wrong", lambda: np.ones(3), expect="value", expected=lambda: np.ones(3) * (1 + 1e-6)), "wrong"),
        (P.Probe("control:raises on valid input", _raise_unnamed, expect="value", expected=lambda: 1.0), "wrong"),
        (P.Probe("control:nan where finite", lambda: np.array([np.nan, 1.0]), expect="value",
                 expected=lambda: np.array([0.0, 1.0])), "wrong"),
    ],
    ids=lambda v: v.id if isinstance(v, P.Probe) else v,
)
def test_the_judge_sees_each_kind_of_failure(probe, outcome):
    """Negative controls: a probe that returns where it must raise, returns NaN, raises an
    unnamed or a foreign error, or returns a wrong number, is not judged `ok`."""
    assert P.judge(probe)[0] == outcome


def test_the_judge_sees_a_mutated_input():
    a = np.zeros(3)
    probe = P.Probe("control:mutates", lambda: _mutate(a), expect="finite_or_raises", inputs=(a,))
    assert P.judge(probe)[0] == "mutated"


def test_an_isolated_probe_that_ends_its_process_is_a_crash(tmp_path, monkeypatch):
    """The worker process of `python tests/probes.py`: a probe that calls `os._exit` (as a
    reader calling `sys.exit` would) is recorded as a crash, and the next probe still runs."""
    runner = P._Isolated(tmp_path)
    monkeypatch.setattr(P, "TIME_LIMIT_S", 60)
    try:
        crashed = runner.run("__exit__")
        after = runner.run("files:missing file")
    finally:
        if runner.proc is not None:
            runner.proc.kill()
    assert crashed["outcome"] == "crash"
    assert after["outcome"] == "ok"
