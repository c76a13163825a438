"""Derivatives through `solve` tell the truth: forward mode equals reverse mode (the implicit
function theorem's tangent and its transpose), a solve that did not converge has NaN
derivatives, `converged` needs a finite energy, and `throw=True` raises also when traced."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from energies import dirichlet, elastica
from solvers import DenseLU, KLU, SparseDirect, solve

ENDS = dict(t_start=(1, 0, 0), t_end=(0, 1, 0))
CHORD = jnp.array([0.5, 0.2, 0.0])


def elastica_x(chord, linear_solver):
    return solve(elastica.clamped(16, chord=chord, **ENDS), linear_solver=linear_solver).x


@pytest.mark.parametrize("linear_solver", [DenseLU(), KLU()], ids=repr)
def test_jacfwd_equals_jacrev_on_the_elastica(linear_solver):
    """d(solution)/d(chord): forward (jacfwd, K⁻¹ on tangents) and reverse (jacrev, K⁻ᵀ on
    cotangents) agree to 1e-10; and both equal a central difference to 1e-6."""
    forward = jax.jacfwd(lambda c: elastica_x(c, linear_solver))(CHORD)
    reverse = jax.jacrev(lambda c: elastica_x(c, linear_solver))(CHORD)
    assert float(jnp.max(jnp.abs(reverse))) > 1.0  # a derivative that is not trivially zero
    assert float(jnp.max(jnp.abs(forward - reverse))) <= 1e-10
    e, h = jnp.array([1.0, 0.0, 0.0]), 1e-5
    fd = (elastica_x(CHORD + h * e, linear_solver) - elastica_x(CHORD - h * e, linear_solver)) / (2 * h)
    assert float(jnp.max(jnp.abs(fd - forward[..., 0]))) <= 1e-6 * float(jnp.max(jnp.abs(fd)))


def test_jvp_is_the_transpose_of_vjp_on_a_mesh_problem():
    """The cotan Dirichlet problem (Thm 6.6) on a disk through `SparseDirect` (a host
    factorisation): ⟨v, J u⟩ = ⟨Jᵀ v, u⟩ for the derivative of f with respect to the boundary
    values, to 1e-12 relative; a wrong transpose (J u paired with another v) does not pass."""
    V, F = dg.mesh.disk(4)
    boundary = np.unique(np.concatenate(dg.mesh.boundary_loops(F)))
    c0 = jnp.asarray(np.cos(np.arange(len(boundary))))

    def f_of(c):
        return solve(dirichlet.cotan(V, F, boundary, c), linear_solver=SparseDirect(factoriser="superlu")).x

    rng = np.random.default_rng(0)
    u = jnp.asarray(rng.normal(size=c0.shape))
    v = jnp.asarray(rng.normal(size=(len(V),)))
    _, Ju = jax.jvp(f_of, (c0,), (u,))
    _, vjp = jax.vjp(f_of, c0)
    (JTv,) = vjp(v)
    lhs, rhs = float(v @ Ju), float(JTv @ u)
    assert abs(lhs - rhs) <= 1e-12 * max(abs(lhs), 1.0)
    other = jnp.asarray(rng.normal(size=(len(V),)))
    assert abs(float(other @ Ju) - rhs) > 1e-3  # negative control


@pytest.mark.parametrize("linear_solver", [DenseLU(), KLU()], ids=repr)
def test_hessian_of_the_solved_energy_is_symmetric_and_matches_finite_differences(linear_solver):
    """Forward over reverse (`jax.hessian`) through `solve`: d²E*/dchord² equals the finite
    difference of the gradient (dE*/dc = the chord multiplier's negative, Hellmann–Feynman)."""

    def energy(c):
        return solve(elastica.clamped(16, chord=c, **ENDS), linear_solver=linear_solver).energy

    H = jax.hessian(energy)(CHORD)
    assert float(jnp.max(jnp.abs(H - H.T))) <= 1e-8 * float(jnp.max(jnp.abs(H)))
    grad, h = jax.grad(energy), 1e-5
    fd = (grad(CHORD + jnp.array([h, 0, 0])) - grad(CHORD - jnp.array([h, 0, 0]))) / (2 * h)
    assert float(jnp.max(jnp.abs(fd - H[:, 0]))) <= 1e-5 * float(jnp.max(jnp.abs(H)))


def test_a_solve_that_did_not_converge_has_nan_derivatives():
    """After one Newton step (not converged) grad, jacfwd and jvp are NaN; converged: finite."""

    def energy(c, steps):
        return solve(elastica.clamped(16, chord=c, **ENDS), max_steps=steps, throw=False).energy

    assert np.all(np.isnan(np.asarray(jax.grad(lambda c: energy(c, 1))(CHORD))))
    assert np.all(np.isnan(np.asarray(jax.jacfwd(lambda c: energy(c, 1))(CHORD))))
    assert np.all(np.isfinite(np.asarray(jax.grad(lambda c: energy(c, 100))(CHORD))))


def test_converged_needs_a_finite_energy():
    """E = ½(x − 2)² + 0·log(x − 2.5): finite at x0 = 3, NaN at the critical point x = 2 where
    the gradient is 0.  Newton lands there in one step (residual ~1e-15), but it is not a
    converged solution: `converged` False, status 3 (non-finite), `ConvergenceError` with throw."""
    problem = dg.Problem(energy=lambda x, p: 0.5 * jnp.sum((x - 2.0) ** 2) + 0.0 * jnp.sum(jnp.log(x - 2.5)),
                         x0=jnp.array([3.0]))
    sol = solve(problem, throw=False)
    assert float(sol.residual) <= 1e-10 and np.isnan(float(sol.energy))
    assert not bool(sol.converged) and int(sol.status) == 3
    with pytest.raises(dg.errors.ConvergenceError, match="energy nan"):
        solve(problem)
    finite = dg.Problem(energy=lambda x, p: 0.5 * jnp.sum((x - 2.0) ** 2), x0=jnp.array([3.0]))
    assert bool(solve(finite).converged)  # negative control


def test_throw_raises_inside_jit():
    """x⁴ − a x after one Newton step has not converged: with throw=True the compiled
    computation raises (naming the cause); with throw=False it returns converged=False."""
    problem = dg.Problem(energy=lambda x, a: jnp.sum(x**4) - a * jnp.sum(x), x0=jnp.array([1.0]), params=jnp.array(1.0))
    with pytest.raises(Exception, match="solve did not converge"):
        jax.block_until_ready(jax.jit(lambda a: solve(problem.with_params(a), max_steps=1).x)(jnp.array(3.0)))
    ok = jax.jit(lambda a: solve(problem.with_params(a), max_steps=1, throw=False).converged)(jnp.array(3.0))
    assert not bool(ok)
    x = jax.jit(lambda a: solve(problem.with_params(a)).x)(jnp.array(4.0))  # converges: no error
    assert abs(float(x[0]) - 1.0) <= 1e-12


def test_a_failed_linear_solve_is_a_convergence_error_also_without_throw():
    """A singular sparse KKT matrix at x0 (a rod started from all-zero frames) is reported as
    `ConvergenceError`, never as a raw `JaxRuntimeError`, with throw=False too."""
    from energies import rod

    p = rod.clamped(8, alpha=1.0, chord=(0.5, 0.2, 0.1), frame_start=(1.0, 0, 0, 0), frame_end=(1.0, 0, 0, 0))
    zero = dg.Problem(energy=p.energy, constraints=p.constraints, x0=jax.tree_util.tree_map(jnp.zeros_like, p.x0),
                      params=p.params, fixed=p.fixed)
    with pytest.raises(dg.errors.ConvergenceError, match="linear solve failed"):
        solve(zero, method="sparse", throw=False)


def test_second_derivative_of_a_constrained_optimum_is_exact():
    """Nearest point of the circle |x| = r to c = (3, 4): E*(r) = (|c| − r)²/2, so dE*/dr = r − 5
    and d²E*/dr² = 1 (forward over reverse and reverse over reverse); the solution's second
    derivative d²x*/dr² = 0."""
    c = jnp.array([3.0, 4.0])
    problem = dg.Problem(energy=lambda x, r: 0.5 * jnp.sum((x - c) ** 2), constraints=lambda x, r: jnp.array([x @ x - r**2]),
                         x0=jnp.array([0.6, 0.8]), params=jnp.array(1.0))

    def energy(r):
        return solve(problem.with_params(r)).energy

    r = jnp.array(2.0)
    assert abs(float(jax.grad(energy)(r)) + 3.0) <= 1e-10
    assert abs(float(jax.hessian(energy)(r)) - 1.0) <= 1e-10
    assert abs(float(jax.jacrev(jax.grad(energy))(r)) - 1.0) <= 1e-10
    d2x = jax.jacfwd(jax.jacfwd(lambda r: solve(problem.with_params(r)).x))(r)
    assert float(jnp.max(jnp.abs(d2x))) <= 1e-10
