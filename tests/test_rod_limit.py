"""Smooth limit of discrete elastic rods by shooting, the long study (make test-all): Thm 3.13.

The smooth reference is independent of the discrete energy: the clamped rod of Thm 3.13 is
computed as a motion of the Lagrange top (Kirchhoff analogy, Thm 3.11) by shooting
(`ddgjax.kirchhoff`); the discrete rod only supplies the starting guess.  The quick limits
(Thm 3.11, 3.13 and the coefficient c of Def 3.7, at n = 8, 16, 32, with a negative control)
are checks of `ddgjax verify` (`sec3_rod_limits`), which `tests/test_verify_checks.py` runs.
The last two tests (quick) check how the smooth rod is sampled: a program JAX can cache, and as
accurate as one integration saving at every arc length.
"""

import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax.smooth import kirchhoff
from ddgjax import quaternion as qt
from energies import rod
from solvers import solve

E1, E3 = jnp.array([1.0, 0.0, 0.0]), jnp.array([0.0, 0.0, 1.0])
ALPHA, CHORD = 0.6, jnp.array([0.5, 0.3, 0.15])
START = qt.from_axis_angle(E3, 0.0)
END = qt.mul(qt.from_axis_angle(E3, 2.0), qt.from_axis_angle(E1, 1.5))  # bent out of plane and twisted


def _discrete(n, clamp="vertex"):
    problem = rod.clamped(n, alpha=ALPHA, chord=CHORD, frame_start=START, frame_end=END, clamp=clamp)
    sol = solve(problem)
    assert float(sol.residual) <= 1e-10
    return problem, sol


@pytest.fixture(scope="module")
def rods():
    return {n: _discrete(n) for n in (16, 32)}  # two compilations; the slow study goes to n = 256


@pytest.fixture(scope="module")
def smooth(rods):
    """The smooth rod by shooting, started from the n = 32 discrete rod."""
    return kirchhoff.from_discrete(*rods[32])


@pytest.mark.slow  # the shooting reference compiles for ~50 s on 2 cores (make test-all)
def test_shooting_reference_meets_the_clamps(smooth):
    Phi, gamma = kirchhoff.sample(smooth, jnp.array([0.0, 1.0]))
    assert float(jnp.max(jnp.abs(gamma[1] - CHORD))) <= 1e-10
    assert min(float(jnp.max(jnp.abs(Phi[1] - END))), float(jnp.max(jnp.abs(Phi[1] + END)))) <= 1e-10
    assert abs(kirchhoff.torsion(smooth)) > 0.5  # a genuinely twisted rod


@pytest.mark.slow  # the shooting reference compiles for ~50 s on 2 cores (make test-all)
def test_vertex_clamped_discrete_rods_converge_at_order_two(rods, smooth):
    """Thm 3.13: centreline, load a and torsion τ of the discrete rods converge at O(h²)
    (n = 16, 32 here; n = 16 … 256 in the slow study)."""
    ns = sorted(rods)
    errors = np.array([list(kirchhoff.discrete_errors(*rods[n], smooth).values()) for n in ns])
    for column, name in enumerate(["position", "load", "twist"]):
        table = dg.limits.convergence(lambda n, c=column: errors[ns.index(n), c], ns)
        assert abs(table.fitted_order - 2.0) <= 0.3, (name, table.to_markdown())
    assert errors[-1, 0] <= 1e-3


@pytest.mark.slow
def test_smooth_limit_tables_edge_and_vertex_clamps(smooth):
    """The full study: vertex clamps O(h²), edge clamps (frames at s = h/2, L − h/2) only O(h)."""
    ns = [16, 32, 64, 128, 256]
    for clamp, order in (("vertex", 2.0), ("edge", 1.0)):
        table = dg.limits.convergence(lambda n: kirchhoff.discrete_errors(*_discrete(n, clamp), smooth)["position"], ns)
        print(clamp, table.to_markdown())
        assert abs(table.fitted_order - order) <= 0.3, table.to_markdown()


def test_sampling_a_smooth_rod_at_decreasing_arc_lengths_is_an_input_error():
    """The integrator saves along increasing s only: a decrease is named, not a raw runtime error."""
    from ddgjax.errors import InvalidInputError

    rod_ = kirchhoff.SmoothRod(jnp.array([1.0, 0, 0, 0]), jnp.array([2.4, 3.0, -1.0]), jnp.array([16.2, 15.9, 1.0]),
                               0.6, 1.0)
    with pytest.raises(InvalidInputError, match=r"s\[2\] = 0.1"):
        kirchhoff.sample(rod_, jnp.array([0.0, 0.5, 0.1]))


HOST_CALLBACK = "python_cpu_callback"  # the custom call of jax.pure_callback / diffrax's error_if on the CPU


def _top_motion():
    """The top motion of verify's quick rod limits (Thm 3.11: a smooth rod)."""
    return kirchhoff.SmoothRod(jnp.array([1.0, 0, 0, 0]), jnp.array([2.4, 3.0, -1.0]), jnp.array([16.2, 15.9, 1.0]),
                               0.6, 1.0)


def test_sampling_the_smooth_rod_compiles_without_host_callbacks():
    """Sampling and the shooting residual are programs without host callbacks, which JAX keeps in
    its persistent compilation cache (a program with one is compiled in every process).
    Negative control: diffrax with a traced end time inserts one (its input check)."""
    import diffrax
    import jax

    rod_ = _top_motion()
    s = jnp.linspace(0.0, 1.0, kirchhoff.SAMPLE_BUCKET)
    sampling = kirchhoff._integrate_jit.lower(rod_.Phi0, rod_.M0, rod_.a, rod_.alpha, s).as_text()
    shooting = kirchhoff._shoot.lower(jnp.zeros(6), rod_.Phi0, rod_.Phi0, CHORD, 0.6, 1.0).as_text()
    assert HOST_CALLBACK not in sampling and HOST_CALLBACK not in shooting

    def decay(t1):
        return diffrax.diffeqsolve(diffrax.ODETerm(lambda t, y, args: -y), diffrax.Tsit5(), 0.0, t1, 0.1,
                                   jnp.ones(2), throw=False).ys
    assert HOST_CALLBACK in jax.jit(decay).lower(1.0).as_text()


def test_sampling_gap_by_gap_equals_one_integration_saving_at_every_arc_length():
    """The top motion integrated from one sampled arc length to the next (`kirchhoff._flow`)
    equals one diffrax solve over [0, L] saving at the same arc lengths, to the integrators'
    tolerance (1e-13 relative): the two differ only in where the step-size control restarts."""
    import diffrax

    rod_ = _top_motion()
    s = np.concatenate([[0.0], (np.arange(32) + 0.5) / 32, [1.0]])
    Phi, gamma = kirchhoff.sample(rod_, s)

    def field(t, y, args):
        return kirchhoff._field(t, y, (rod_.alpha, rod_.a, 1.0))

    once = diffrax.diffeqsolve(
        diffrax.ODETerm(field), diffrax.Dopri8(), t0=0.0, t1=1.0, dt0=1.0 / 64, y0=(rod_.Phi0, rod_.M0, jnp.zeros(3)),
        saveat=diffrax.SaveAt(ts=jnp.asarray(s)),
        stepsize_controller=diffrax.PIDController(rtol=kirchhoff.RTOL, atol=kirchhoff.RTOL), max_steps=100_000)
    assert np.max(np.abs(np.asarray(Phi) - np.asarray(once.ys[0]))) <= 1e-10
    assert np.max(np.abs(np.asarray(gamma) - np.asarray(once.ys[2]))) <= 1e-10
