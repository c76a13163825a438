"""Properties of `solvers.solve` on random strictly convex QPs with linear equality constraints.

E(x) = ½ xᵀAx − bᵀx with A = MᵀM + cI (c ≥ 0.1), constraints g(x) = Cx − d with C of full row
rank.  The critical point is the unique solution of the KKT system

    [[A, Cᵀ], [C, 0]] [x; −λ] = [b; d]

in the library's sign convention `∇E(x) = Jg(x)ᵀ λ` (`Solution.multipliers`), so Ax − b = Cᵀλ.
It is linear in (b, d), so its derivative with respect to (b, d) is K⁻¹ itself.  Newton's
method on a QP is exact after one step: the answers agree to rounding (1e-10 relative).

Each (n, m) shape compiles a new solver, so the shapes are a few fixed pairs and the energy and
constraints are module-level functions reading their matrices from `params` (equal shapes reuse
the compiled solver); hypothesis draws a seed and the matrices come from `np.random.default_rng`.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import ddgjax as dg
from solvers import solve

SHAPES = [(3, 0), (3, 1), (6, 0), (6, 2)]
REL = 1e-10  # one Newton step on a system of condition ≲ 10⁴: rounding, far below this


def qp_energy(x, p):
    return 0.5 * x @ p["A"] @ x - p["b"] @ x


def qp_constraints(x, p):
    return p["C"] @ x - p["d"]


def qp_density(x_local, p):
    """The same energy as one dense cell of `dg.local_sum` (the stencil is every unknown)."""
    return qp_energy(x_local, p)


def qp_constraint_density(x_local, p):
    return qp_constraints(x_local, p)


@functools.cache
def local_declaration(n: int, constrained: bool):
    everything = np.arange(n)[None, :]
    energy = dg.local_sum(qp_density, everything)
    return energy, (dg.local_sum(qp_constraint_density, everything) if constrained else None)


def random_qp(seed: int, n: int, m: int, c: float) -> dict:
    """A = MᵀM + cI; C = U diag(σ) Vᵀ with σ ∈ [0.5, 2] (full row rank, bounded condition)."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n))
    qp = {"A": M.T @ M + c * np.eye(n), "b": rng.normal(size=n), "x0": rng.normal(size=n)}
    if m:
        U = np.linalg.qr(rng.normal(size=(m, m)))[0]
        V = np.linalg.qr(rng.normal(size=(n, m)))[0]
        qp.update(C=U @ np.diag(rng.uniform(0.5, 2.0, size=m)) @ V.T, d=rng.normal(size=m))
    return qp


def params_of(qp: dict) -> dict:
    return {k: v for k, v in qp.items() if k != "x0"}


def problem_of(qp: dict, params=None, local=False) -> dg.Problem:
    params = params_of(qp) if params is None else params
    constrained = "C" in qp
    if local:
        energy, constraints = local_declaration(len(qp["b"]), constrained)
    else:
        energy, constraints = qp_energy, (qp_constraints if constrained else None)
    return dg.Problem(energy=energy, constraints=constraints, x0=qp["x0"], params=params)


def kkt_matrix(qp: dict) -> np.ndarray:
    A = qp["A"]
    if "C" not in qp:
        return A
    C = qp["C"]
    return np.block([[A, C.T], [C, np.zeros((len(C), len(C)))]])


def closed_form(qp: dict) -> tuple[np.ndarray, np.ndarray]:
    """(x, λ) from K [x; −λ] = [b; d]."""
    n = len(qp["b"])
    rhs = np.concatenate([qp["b"], qp.get("d", np.zeros(0))])
    w = np.linalg.solve(kkt_matrix(qp), rhs)
    return w[:n], -w[n:]


def rel_err(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if b.size == 0:
        return 0.0 if a.size == 0 else np.inf
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


qps = st.builds(
    lambda seed, shape, c: (seed, *shape, c),
    st.integers(0, 2**31),
    st.sampled_from(SHAPES),
    st.floats(0.1, 10.0),
)


@settings(max_examples=15, deadline=None)
@given(qps, st.booleans())
def test_kkt_solution_of_a_convex_qp(case, local):
    """x and the multipliers equal the closed-form KKT solution to 1e-10 relative, on the dense
    path (plain functions, method="auto") and on the path of a problem declared local
    (`dg.local_sum`: method="auto" picks the sparse direct solve on the CPU)."""
    seed, n, m, c = case
    qp = random_qp(seed, n, m, c)
    sol = solve(problem_of(qp, local=local))
    x, lam = closed_form(qp)
    assert bool(sol.converged) and int(sol.steps) == 1  # Newton on a quadratic: one exact step
    assert rel_err(sol.x, x) <= REL
    assert np.shape(sol.multipliers) == (m,)
    if m:
        assert rel_err(sol.multipliers, lam) <= REL
    # the library's convention, ∇E(x) = Jg(x)ᵀ λ, at the solve's own answer
    grad = qp["A"] @ np.asarray(sol.x) - qp["b"]
    jt_lam = qp["C"].T @ np.asarray(sol.multipliers) if m else np.zeros(n)
    assert np.max(np.abs(grad - jt_lam)) <= REL * max(np.max(np.abs(qp["A"])) * np.max(np.abs(x)), 1.0)


def solution_of_rhs(qp: dict):
    """(b, d) ↦ (x, λ) through `solve`, with A, C fixed: the map whose derivative is K⁻¹."""

    def f(b, d):
        sol = solve(problem_of(qp, params=dict(params_of(qp), b=b, d=d)))
        return jnp.concatenate([sol.x, sol.multipliers])

    return f


@settings(max_examples=15, deadline=None)
@given(qps.filter(lambda case: case[2] > 0))
def test_jvp_vjp_are_transposes_and_equal_the_kkt_derivative(case):
    """J = ∂(x, λ)/∂(b, d): ⟨v, J u⟩ = ⟨Jᵀ v, u⟩ (jvp against vjp) to 1e-10 relative, and J
    column by column (jvp) and row by row (vjp) equals diag(I, −I) K⁻¹, the derivative of
    K⁻¹ [b; d] with λ's sign; K⁻¹ without the sign of the λ rows does not match.  (J is built
    from repeated jvp / vjp calls, not jacfwd / jacrev, which would compile two more programs.)"""
    seed, n, m, c = case
    qp = random_qp(seed, n, m, c)
    f = solution_of_rhs(qp)
    b, d = jnp.asarray(qp["b"]), jnp.asarray(qp["d"])
    rng = np.random.default_rng(seed + 1)
    u, v = rng.normal(size=n + m), rng.normal(size=n + m)

    def jvp(u):
        return np.asarray(jax.jvp(f, (b, d), (jnp.asarray(u[:n]), jnp.asarray(u[n:])))[1])

    _, pullback = jax.vjp(f, b, d)

    def vjp(v):
        return np.concatenate([np.asarray(t) for t in pullback(jnp.asarray(v))])

    Ju, JTv = jvp(u), vjp(v)
    lhs, rhs = float(v @ Ju), float(JTv @ u)
    assert abs(lhs - rhs) <= REL * np.linalg.norm(v) * np.linalg.norm(Ju)

    sign = np.concatenate([np.ones(n), -np.ones(m)])
    K_inv = np.linalg.inv(kkt_matrix(qp))
    J_closed = sign[:, None] * K_inv
    basis = np.eye(n + m)
    J_fwd = np.stack([jvp(e) for e in basis], axis=1)
    J_rev = np.stack([vjp(e) for e in basis], axis=0)
    assert rel_err(J_fwd, J_closed) <= REL
    assert rel_err(J_rev, J_closed) <= REL
    assert rel_err(Ju, J_closed @ u) <= REL
    assert rel_err(J_fwd, K_inv) > 1e-3  # negative control: the λ rows' sign matters


@settings(max_examples=15, deadline=None)
@given(qps, st.booleans())
def test_inputs_are_never_mutated(case, local):
    """numpy arrays passed as x0 and params are bitwise unchanged by `solve` (API.md)."""
    seed, n, m, c = case
    qp = random_qp(seed, n, m, c)
    before = {k: v.copy() for k, v in qp.items()}
    params = params_of(qp)
    sol = solve(problem_of(qp, params=params, local=local))
    assert bool(sol.converged) and rel_err(sol.x, qp["x0"]) > 1e-6  # x really moved from x0
    for k, v in qp.items():
        assert v.tobytes() == before[k].tobytes() and v.dtype == before[k].dtype and v.shape == before[k].shape, k
    assert params.keys() == qp.keys() - {"x0"} and all(v is qp[k] for k, v in params.items())


@settings(max_examples=15, deadline=None)
@given(qps.filter(lambda case: case[2] > 0))
def test_negative_control_flipped_multiplier_sign_does_not_match(case):
    """The comparison can fail: the closed form with λ's sign flipped (the convention
    ∇E = −Jᵀλ) is far from `solve`'s multipliers, and −Jᵀλ is far from ∇E."""
    seed, n, m, c = case
    qp = random_qp(seed, n, m, c)
    sol = solve(problem_of(qp))
    _, lam = closed_form(qp)
    assert rel_err(sol.multipliers, lam) <= REL
    assert rel_err(sol.multipliers, -lam) > 1.0  # = 2 exactly, up to rounding
    grad = qp["A"] @ np.asarray(sol.x) - qp["b"]
    assert rel_err(-qp["C"].T @ np.asarray(sol.multipliers), grad) > 1.0
