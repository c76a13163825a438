"""Named constraints: `constraints(x, params)` returning a dict, multipliers of the same structure.

The constraint vector of a named problem is its leaves concatenated in sorted-name order; the
solver works on it unchanged, so a named problem and its positional twin (the same constraints
in the catalogue's old order, unit then chord) have the same critical point and the same
multipliers, only reordered.  Tolerances: both are Newton solves of the same equations to
tol 1e-10, converging quadratically to round-off; the multipliers agree to ~1e-12.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import tree_max_abs_diff

import ddgjax as dg
from ddgjax.errors import DDGError, InvalidInputError, ShapeError
from ddgjax.locality import Local
from ddgjax.problem import constraint_values, flatten_multipliers, unflatten_multipliers
from energies import elastica, rod
from solvers import solve, solve_batch
from solvers._kkt import spec_of

CHORD = (0.5, 0.2, 0.0)


def _elastica(n=32, chord=CHORD):
    return elastica.clamped(n, chord=chord, t_start=(1, 0, 0), t_end=(0, 1, 0))


def _rod(n=12):
    start = np.array([1.0, 0.0, 0.0, 0.0])
    end = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])  # tangent e2
    return rod.clamped(n, alpha=0.7, chord=(0.5, 0.3, 0.1), frame_start=start, frame_end=end)


def _part(local: Local, name: str) -> Local:
    return Local(tuple(g for g, n in zip(local.groups, local.names) if n == name))


def flat_twin(problem: dg.Problem) -> dg.Problem:
    """The same problem declared positionally in the old order: unit constraints, then chord."""
    c = problem.constraints
    return dg.Problem(
        problem.energy, problem.x0, constraints=dg.concat(_part(c, "unit"), _part(c, "chord")),
        params=problem.params, fixed=problem.fixed,
    )


@pytest.fixture(scope="module")
def elastica_pair():
    problem = _elastica()
    return problem, solve(problem), solve(flat_twin(problem))


def test_elastica_chord_multipliers_equal_the_old_last_three(elastica_pair):
    _, named, flat = elastica_pair
    assert set(named.multipliers) == {"chord", "unit"}
    assert named.multipliers["chord"].shape == (3,) and named.multipliers["unit"].shape == (30,)
    assert np.ndim(flat.multipliers) == 1 and flat.multipliers.shape == (33,)
    assert float(jnp.max(jnp.abs(named.multipliers["chord"] - flat.multipliers[-3:]))) <= 1e-12
    assert float(jnp.max(jnp.abs(named.multipliers["unit"] - flat.multipliers[:-3]))) <= 1e-12
    assert float(jnp.max(jnp.abs(elastica.load(named) - flat.multipliers[-3:]))) <= 1e-12
    assert float(jnp.max(jnp.abs(named.x - flat.x))) <= 1e-12


@pytest.mark.parametrize(
    "make, method",
    [(_elastica, m) for m in ("dense", "sparse", "krylov")]
    + [pytest.param(_rod, "dense", marks=pytest.mark.slow), (_rod, "sparse"), pytest.param(_rod, "krylov", marks=pytest.mark.slow)],
    ids=["elastica-dense", "elastica-sparse", "elastica-krylov", "rod-dense", "rod-sparse", "rod-krylov"],
)
def test_chord_multipliers_equal_the_flat_twin_on_every_path(make, method):
    problem = make(12)
    named, flat = solve(problem, method=method), solve(flat_twin(problem), method=method)
    assert float(jnp.max(jnp.abs(named.multipliers["chord"] - flat.multipliers[-3:]))) <= 1e-11
    assert float(jnp.max(jnp.abs(named.multipliers["unit"] - flat.multipliers[:-3]))) <= 1e-11
    assert named.multipliers["unit"].shape == (10,)  # clamp="edge": one per free edge, n − 2


def test_thm_3_8_euler_lagrange_vanishes_with_named_multipliers(elastica_pair):
    problem, named, _ = elastica_pair
    el = dg.euler_lagrange(problem)
    assert float(jnp.max(jnp.abs(el(named.x, named.multipliers)))) <= 1e-9
    # the flat vector of a named problem is ordered by sorted names: chord, then unit
    lam = named.multipliers
    assert float(jnp.max(jnp.abs(el(named.x, jnp.concatenate([lam["chord"], lam["unit"]]))))) <= 1e-9
    assert float(jnp.max(jnp.abs(flatten_multipliers(problem, lam) - jnp.concatenate([lam["chord"], lam["unit"]])))) == 0
    assert tree_max_abs_diff(unflatten_multipliers(problem, flatten_multipliers(problem, lam)), lam) == 0.0


def test_negative_control_multipliers_in_the_wrong_order_do_not_solve_euler_lagrange(elastica_pair):
    problem, named, _ = elastica_pair
    el = dg.euler_lagrange(problem)
    lam = named.multipliers
    old_order = jnp.concatenate([lam["unit"], lam["chord"]])  # unit, then chord: the positional order
    assert float(jnp.max(jnp.abs(el(named.x, old_order)))) > 1e-2
    swapped = {"chord": lam["unit"][:3], "unit": jnp.concatenate([lam["chord"], lam["unit"][3:]])}
    assert float(jnp.max(jnp.abs(el(named.x, swapped)))) > 1e-2


def test_implicit_gradient_of_a_named_multiplier_equals_the_flat_one():
    problem = _elastica(12)
    twin = flat_twin(problem)

    def chord_load(p, which):
        params = {**problem.params, "chord": p}
        if which == "named":
            return solve(problem.with_params(params)).multipliers["chord"][0]
        return solve(twin.with_params(params)).multipliers[-3]

    c = jnp.asarray(CHORD)
    g_named, g_flat = jax.grad(chord_load)(c, "named"), jax.grad(chord_load)(c, "flat")
    assert float(jnp.max(jnp.abs(g_named - g_flat))) <= 1e-9 * float(jnp.max(jnp.abs(g_flat)))
    assert float(jnp.max(jnp.abs(g_flat))) > 1.0  # a real dependence, not 0 = 0


def test_vmap_and_solve_batch_over_params_give_named_multipliers():
    problem = _elastica(12, chord=(0.6, 0.2, 0.0))
    chords = jnp.array([[0.5, 0.2, 0.0], [0.6, 0.2, 0.04], [0.68, 0.2, -0.05]])

    def load(c):
        return solve(problem.with_params({**problem.params, "chord": c}), throw=False).multipliers

    vmapped = jax.vmap(load)(chords)
    batch = solve_batch(problem, {"chord": chords})
    assert vmapped["chord"].shape == (3, 3) and vmapped["unit"].shape == (3, 10)
    for k in range(3):
        single = load(chords[k])
        member = jax.tree_util.tree_map(lambda a, k=k: a[k], vmapped)
        assert tree_max_abs_diff(member, single) <= 1e-10
        assert tree_max_abs_diff(jax.tree_util.tree_map(lambda a, k=k: a[k], batch.multipliers), single) <= 1e-10


def test_gradient_flow_of_a_named_problem_is_tangent_and_equals_the_flat_one():
    problem = _elastica(12)
    x = problem.x0 + 0.01 * jnp.asarray(np.random.default_rng(0).normal(size=problem.x0.shape)) * ~problem.fixed
    named, flat = dg.gradient_flow(problem)(x), dg.gradient_flow(flat_twin(problem))(x)
    assert float(jnp.max(jnp.abs(named - flat))) <= 1e-12 * float(jnp.max(jnp.abs(flat)))
    J = jax.jacobian(lambda y: constraint_values(problem, y, problem.params))(x)
    assert float(jnp.max(jnp.abs(jnp.tensordot(J, named, axes=2)))) <= 1e-10


def test_multipliers0_accepts_the_named_and_the_flat_form(elastica_pair):
    problem, named, _ = elastica_pair
    for lam0 in (named.multipliers, flatten_multipliers(problem, named.multipliers)):
        again = solve(problem.with_x0(named.x), multipliers0=lam0)
        assert int(again.steps) <= 1
        assert tree_max_abs_diff(again.multipliers, named.multipliers) <= 1e-10


@pytest.mark.parametrize(
    "bad, message",
    [
        ({"chord": jnp.zeros(3)}, "structure of the constraints"),
        ({"chord": jnp.zeros(2), "unit": jnp.zeros(30)}, r"multipliers\['chord'\] has shape \(2,\)"),
        ({"chord": jnp.zeros(3), "unit": jnp.zeros(30), "extra": jnp.zeros(1)}, "structure of the constraints"),
        (jnp.zeros(32), r"shape \(33,\)"),
        ((jnp.zeros(3), jnp.zeros(30)), "structure of the constraints"),
    ],
)
def test_wrong_structure_multipliers_raise_an_error_naming_the_leaf(elastica_pair, bad, message):
    problem, named, _ = elastica_pair
    with pytest.raises(ShapeError, match=message):
        dg.euler_lagrange(problem)(named.x, bad)
    with pytest.raises(DDGError, match=message):
        solve(problem, multipliers0=bad)


def test_nonfinite_named_multipliers0_raise():
    problem = _elastica(12)
    with pytest.raises(DDGError, match=r"multipliers\['chord'\]"):
        solve(problem, multipliers0={"chord": jnp.array([0.0, jnp.nan, 0.0]), "unit": jnp.zeros(10)})


def test_named_plain_function_with_scalar_leaves_has_closed_form_multipliers():
    """min <c, x> on the unit circle {|x|² = 1, x_3 = 0}: x = −(c1, c2, 0)/ρ with ρ = |(c1, c2)|,
    and ∇E = c = 2λ_sphere x + λ_plane e3 gives λ_sphere = −ρ/2, λ_plane = c3."""
    c = jnp.array([0.3, -0.4, 0.7])
    problem = dg.Problem(
        lambda x, c: c @ x, jnp.array([-0.5, 0.6, 0.2]), params=c,
        constraints=lambda x, _: {"sphere": x @ x - 1.0, "plane": x[2]},
    )
    assert problem.n_constraints == 2 and not problem.is_local
    sol = solve(problem)
    assert sol.multipliers["sphere"].shape == () and sol.multipliers["plane"].shape == ()
    assert abs(float(sol.multipliers["sphere"]) + 0.25) <= 1e-12
    assert abs(float(sol.multipliers["plane"]) - 0.7) <= 1e-12
    assert float(jnp.max(jnp.abs(sol.x - jnp.array([-0.6, 0.8, 0.0])))) <= 1e-12


def test_named_local_declaration_is_local_sorted_and_keyed_by_its_names():
    problem = _elastica(12)
    cons = problem.constraints
    assert problem.is_local and cons.names == ("chord", "unit")
    out = cons(problem.x0, problem.params)
    assert set(out) == {"chord", "unit"} and out["chord"].shape == (3,) and out["unit"].shape == (10,)
    flat = jnp.concatenate([_part(cons, "chord")(problem.x0, problem.params), _part(cons, "unit")(problem.x0, problem.params)])
    assert float(jnp.max(jnp.abs(constraint_values(problem, problem.x0, problem.params) - flat))) == 0.0
    renamed = Local(cons.groups, ("a", "b"))
    assert renamed != cons and renamed.key() != cons.key()
    assert spec_of(problem) != spec_of(flat_twin(problem))


def test_concat_rejects_mixed_and_nested_names():
    unit = dg.local_map(lambda x, _: x[0] @ x[0] - 1.0, np.arange(3)[:, None])
    with pytest.raises(InvalidInputError, match="either all by position or all by name"):
        dg.concat(unit, chord=unit)
    with pytest.raises(InvalidInputError, match="itself named"):
        dg.concat(outer=dg.concat(inner=unit))
    with pytest.raises(InvalidInputError, match="name every part"):
        dg.concat(dg.concat(inner=unit), unit)
    with pytest.raises(InvalidInputError, match="not a local declaration"):
        dg.concat(unit=lambda x, p: x)
