"""explorer.model.system.System: a system from its SymPy equations (docs/systems.md): what it
holds, what it refuses (a ParameterError naming the problem), and the content hash that keys its
generated code."""
import numpy as np
import pytest
import sympy as sp

from explorer.model.system import System
from explorer.model.validation import ParameterError

x, y, px, py, lam = sp.symbols("x y px py lam")
HH = {x: px, y: py, px: -x - 2 * lam * x * y, py: -y - lam * (x**2 - y**2)}
HH_ENERGY = (px**2 + py**2) / 2 + (x**2 + y**2) / 2 + lam * (x**2 * y - y**3 / 3)


def henon_heiles(value=1.0):
    return System(HH, parameters={lam: value}, energy=HH_ENERGY, name="henon_heiles")


def test_states_follow_the_order_of_the_equations_and_parameters_are_an_array():
    s = henon_heiles(0.75)
    assert s.states == (x, y, px, py)
    assert s.rhs[2] == -x - 2 * lam * x * y
    assert s.dimension == 4
    np.testing.assert_array_equal(s.parameter_array(), [0.75])
    assert s.name == "henon_heiles"
    reordered = System({y: py, x: px, px: HH[px], py: HH[py]}, parameters={lam: 1.0})
    assert reordered.states == (y, x, px, py)


def test_with_changes_a_value_and_keeps_the_content_hash():
    s = henon_heiles(1.0)
    t = s.with_(lam=0.5)
    np.testing.assert_array_equal(t.parameter_array(), [0.5])
    np.testing.assert_array_equal(s.parameter_array(), [1.0])   # the original is unchanged
    assert t.content_hash == s.content_hash                       # a value is runtime data: same code
    assert t.energy == s.energy and t.name == s.name


def test_the_docs_hand_written_henon_heiles_is_classics_and_the_shared_test_systems_one_module():
    """docs/systems.md writes Hénon–Heiles by hand as here (HH, HH_ENERGY, name "henon_heiles"): with
    the reversor, the same content hash and name as explorer.model.classic's and tests/systems.py's;
    without it, another content but the same generated module (its key is the flow hash: a reversor
    is not in the generated code)."""
    import systems

    from explorer.integrate import codegen
    from explorer.model import classic

    hh = henon_heiles()
    reversible = System(HH, parameters={lam: 1.0}, energy=HH_ENERGY, name="henon_heiles", reversor=HH_REVERSOR)
    assert reversible.content_hash == classic.henon_heiles().content_hash == systems.henon_heiles().content_hash
    assert hh.name == reversible.name == classic.henon_heiles().name == systems.henon_heiles().name
    assert hh.content_hash == systems.henon_heiles_without_reversor().content_hash != reversible.content_hash
    assert reversible.flow_hash == hh.flow_hash == hh.content_hash
    assert codegen.module_key(reversible) == codegen.module_key(hh)


def test_content_hash_changes_with_the_equations_the_parameters_and_the_energy():
    base = henon_heiles().content_hash
    assert System(HH, parameters={lam: 1.0}, energy=HH_ENERGY, name="other").content_hash == base
    changed = dict(HH)
    changed[px] = -x - 3 * lam * x * y
    assert System(changed, parameters={lam: 1.0}, energy=HH_ENERGY).content_hash != base
    assert System(HH, parameters={lam: 1.0}).content_hash != base                    # no energy
    mu = sp.Symbol("mu")
    assert System(HH, parameters={lam: 1.0, mu: 2.0}, energy=HH_ENERGY).content_hash != base
    swapped = {y: py, x: px, px: HH[px], py: HH[py]}
    assert System(swapped, parameters={lam: 1.0}, energy=HH_ENERGY).content_hash != base   # state order


@pytest.mark.parametrize("make, words", [
    (lambda: System({x: px + sp.Symbol("z"), px: -x}), ["dx/dt", "z", "neither a state variable", "nor a parameter"]),
    (lambda: System({x: px, px: -lam * x}), ["dpx/dt", "lam", "neither"]),
    (lambda: System({x: px, px: None}), ["dpx/dt", "no equation"]),
    (lambda: System({x: y}), ["y", "neither a state variable (x)"]),
    (lambda: System({x: px, px: -x}, energy=px**2 + y), ["energy", "y"]),
    (lambda: System({x: px, px: -lam * x}, parameters={lam: "1"}), ["parameter lam", "real number", "'1'"]),
    (lambda: System({x: px, px: -lam * x}, parameters={lam: float("nan")}), ["parameter lam", "finite"]),
    (lambda: System({x: px, px: -lam * x}, parameters={lam: True}), ["parameter lam", "real number"]),
    (lambda: System({x: px, px: -lam * x}, parameters={"lam": 1.0}), ["parameter", "sympy Symbol", "'lam'"]),
    (lambda: System({"x": px, px: -x}), ["state variable", "sympy Symbol"]),
    (lambda: System({x + 1: px, px: -x}), ["state variable", "sympy Symbol"]),
    (lambda: System({}), ["non-empty dict"]),
    (lambda: System([(x, px)]), ["dict"]),
    (lambda: System({x: px, px: -x}, parameters={x: 1.0}), ["x is both a state variable and a parameter"]),
    (lambda: System({x: px, px: -sp.Symbol("x", positive=True)}), ["two different symbols are named x"]),
    (lambda: System({x: px, px: -sp.Abs(x)}), ["dpx/dt", "Abs", "not supported"]),
    (lambda: System({x: px, px: -sp.Function("f")(x)}), ["dpx/dt", "f", "not supported"]),
    (lambda: System({x: px, px: sp.I * x}), ["dpx/dt", "real"]),
    (lambda: System({x: px, px: -x}, name=3), ["name", "string"]),
    (lambda: henon_heiles().with_(lamb=0.5), ["no parameter lamb", "did you mean 'lam'"]),
    (lambda: henon_heiles().with_(lam="big"), ["parameter lam", "real number"]),
])
def test_a_bad_system_is_refused_with_a_message_naming_the_problem(make, words):
    with pytest.raises(ParameterError) as err:
        make()
    for w in words:
        assert w in str(err.value), (w, str(err.value))


def test_numbers_and_numpy_scalars_are_accepted():
    s = System({x: 1, px: sp.Rational(1, 3) * x}, parameters={lam: np.float32(0.5)})
    assert s.rhs[0] == 1
    np.testing.assert_array_equal(s.parameter_array(), [0.5])


def test_variational_system_appends_deviation_vectors_under_the_jacobian():
    s = henon_heiles(0.5).variational(2)
    assert s.dimension == 12
    names = [v.name for v in s.states]
    assert names[4:8] == ["d1_x", "d1_y", "d1_px", "d1_py"] and names[8] == "d2_x"
    d1 = s.states[4:8]
    # d(dpx/dt) = (-1 - 2 lam y) dx - 2 lam x dy
    assert sp.expand(s.rhs[6] - ((-1 - 2 * lam * y) * d1[0] - 2 * lam * x * d1[1])) == 0
    np.testing.assert_array_equal(s.parameter_array(), [0.5])
    assert s.energy is None


def test_variational_names_avoid_the_users_symbols():
    d1_x = sp.Symbol("d1_x")
    s = System({x: d1_x, d1_x: -x}).variational(1)
    assert len({v.name for v in s.states}) == 4


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_variational_needs_a_positive_integer_count(bad):
    with pytest.raises(ParameterError, match="vectors must be an integer >= 1"):
        henon_heiles().variational(bad)


#: Hénon–Heiles is even in x: (x, y, px, py) -> (-x, y, px, -py) reverses its flow
HH_REVERSOR = {x: -x, y: y, px: px, py: -py}


def test_a_reversor_is_kept_in_state_order_through_with_and_in_the_content_hash():
    s = System(HH, parameters={lam: 1.0}, energy=HH_ENERGY, reversor=HH_REVERSOR)
    assert s.reversors == ((-x, y, px, -py),)
    assert s.with_(lam=0.5).reversors == s.reversors and s.with_(lam=0.5).content_hash == s.content_hash
    assert s.content_hash != henon_heiles().content_hash
    assert henon_heiles().reversors == ()
    both = System(HH, parameters={lam: 1.0}, energy=HH_ENERGY, reversor=[HH_REVERSOR, {x: x, y: y, px: -px, py: -py}])
    assert len(both.reversors) == 2 and both.content_hash != s.content_hash


@pytest.mark.parametrize("reversor, words", [
    ({x: 2 * x, y: y, px: -px, py: -py}, ["not an involution", "2*x", "4*x"]),
    ({x: x, y: -y, px: -px, py: py}, ["does not reverse the equations", "dpx/dt"]),
    ({x: -x, y: y, px: px}, ["no image of py", "maps every state variable"]),
    ({x: -x, y: y, px: px, py: -py, lam: lam}, ["maps lam", "not a state variable", "map of states"]),
    ({x: -x, y: y, px: px, py: -py + sp.Symbol("q")}, ["image of py", "q", "neither a state variable"]),
    ({x: -x, y: y, px: px, py: -py, sp.Symbol("z"): 1}, ["maps z", "not a state variable"]),
    ("x -> -x", ["reversor must be a dict"]),
    ([], ["reversor must be a dict"]),
])
def test_a_bad_reversor_is_refused_naming_what_is_wrong(reversor, words):
    with pytest.raises(ParameterError) as err:
        System(HH, parameters={lam: 1.0}, energy=HH_ENERGY, reversor=reversor)
    for w in words:
        assert w in str(err.value), (w, str(err.value))


def test_a_reversor_that_changes_the_energy_is_refused():
    # a free particle: px -> -px reverses dx/dt = px, dpx/dt = 0, but the conserved px is odd under it
    with pytest.raises(ParameterError, match="does not keep the energy"):
        System({x: px, px: 0}, energy=px, reversor={x: x, px: -px})
    assert System({x: px, px: 0}, energy=px**2 / 2, reversor={x: x, px: -px}).reversors == ((x, -px),)
