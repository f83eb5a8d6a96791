"""Chaplygin's R3 as a System (explorer.model.chaplygin, docs/model.md R3) and the engine's recurrences
generated from it (tools/gen_lanes.py -> explorer.integrate._lanes_generated and
_tangent_lanes_generated, docs/systems.md): their series are those of the hand-written vector field
and its linearisation (explorer.model.equations.rhs, rhs_tangent), they conserve H and the Casimir
|g|^2 = 1, and the generated right-hand side and energy equal the hand-written ones to round-off.
"""
import numpy as np
import pytest

from explorer.integrate import _lanes_generated as G
from explorer.integrate import _tangent_lanes_generated as T
from explorer.integrate import codegen
from explorer.kernels.taylor import evaluate
from explorer.model import chaplygin
from explorer.model import equations as eq
from explorer.model import parameters as mp

#: Figure 4 with weight, and a set with circulation asymmetry (chi, zeta), the centre of mass off
#: the axes and lam < 0
PARAMS = [mp.FIGURE4.with_(mu=0.5),
          mp.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3, eta=-0.25)]
ORDER = 30


@pytest.fixture(scope="module")
def orbit():
    return codegen.load(chaplygin.system())


def states(params, n=6, seed=4):
    """n states: random ones (|p|, |M| up to 2) and, at Figure 4's energy, section points (R9)."""
    rng = np.random.default_rng(seed)
    y = rng.uniform(-2, 2, (n, 5))
    phi = rng.uniform(0, 2 * np.pi, n)
    y[:, 3], y[:, 4] = np.sin(phi), np.cos(phi)
    c1, c2, r1, r2 = mp.allowed_ellipse(params, mp.FIGURE4_H)
    p1 = c1 + r1 * np.array([-0.6, 0.1, 0.7])
    return np.vstack([y, mp.section_state(params, p1, np.full(3, c2), mp.FIGURE4_H)])


def close(a, b, rel=1e-15):
    """|a - b| within ``rel`` of the largest |b| (a single entry may cancel to near zero)."""
    return np.max(np.abs(a - b)) <= rel * max(1.0, np.max(np.abs(b)))


def test_parameters_are_the_packed_vector_and_the_state_is_r3s():
    s = chaplygin.system(PARAMS[1])
    assert [p.name for p in s.parameters] == list(mp.PARAM_NAMES)
    assert np.array_equal(s.parameter_array(), mp.packed_params(PARAMS[1]))
    assert [x.name for x in s.states] == ["p1", "p2", "M", "g1", "g2"]


@pytest.mark.parametrize("params", PARAMS)
def test_recurrence_gives_the_first_two_derivatives_of_the_hand_written_field(params):
    """x_1 = f(x) and x_2 = Df(x) f(x) / 2 (f: equations.rhs, Df: equations.rhs_tangent); for the
    tangent recurrence v_1 = Df(x) v, and the orbit's rows are the orbit recurrence's."""
    P = mp.packed_params(params)
    rng = np.random.default_rng(9)
    for y in states(params):
        X = np.zeros((5, ORDER + 1))
        X[:, 0] = y
        G.taylor_coefficients(P, X, ORDER)
        f = np.empty(5)
        eq.rhs(y, P, f)
        jf = np.empty(5)
        eq.rhs_tangent(y, f, P, jf)
        assert close(X[:, 1], f) and close(X[:, 2], jf / 2, 4e-15)
        v = rng.uniform(-1, 1, 5)
        Z = np.zeros((10, ORDER + 1))
        Z[:5, 0], Z[5:, 0] = y, v
        T.tangent_coefficients(P, Z, ORDER)
        jv = np.empty(5)
        eq.rhs_tangent(y, v, P, jv)
        assert close(Z[5:, 1], jv)
        assert close(Z[:5], X, 1e-14)


@pytest.mark.parametrize("params", PARAMS)
def test_deviation_recurrence_is_the_tangent_recurrences_for_the_same_vector(params):
    """The second vector's rows 10..14 of chaplygin.variational(2)'s recurrence (the indicators' module,
    explorer.integrate.tangent.indicators_module) give the coefficients of its first vector's rows 5..9
    for the same vector, to round-off."""
    from explorer.integrate.tangent import indicators_module

    mod = indicators_module(2)
    P = mp.packed_params(params)
    rng = np.random.default_rng(2)
    for y in states(params):
        Z = np.zeros((15, ORDER + 1))
        Z[:5, 0] = y
        Z[5:10, 0] = Z[10:, 0] = rng.uniform(-1, 1, 5)
        mod.taylor_coefficients(P, Z, ORDER)
        scale = np.max(np.abs(Z[5:10]), axis=0)
        assert np.all(np.max(np.abs(Z[10:] - Z[5:10]), axis=0) <= 1e-14 * scale)


def test_taylor_steps_conserve_the_energy_and_the_casimir():
    """R5 case 3 (chi = -lam eta, zeta = lam xi, a1 = a2 = 1: integrable) with weight and circulation
    asymmetry, and Figure 4 with weight (chaotic): 400 Taylor steps of 0.05 (order 20) keep H and
    g1^2 + g2^2 to 1e-13."""
    for params in (mp.Params(a1=1.0, a2=1.0, b=1.7, lam=1.0, chi=0.25, zeta=0.3, mu=0.7, xi=0.3, eta=-0.25),
                   PARAMS[0]):
        P = mp.packed_params(params)
        y0 = states(params)[-1]
        order = 20
        X = np.zeros((5, order + 1))
        y = y0.copy()
        for _ in range(400):
            X[:, 0] = y
            G.taylor_coefficients(P, X, order)
            evaluate(X, order, 0.05, y)
        assert abs(eq.energy(y, P) - eq.energy(y0, P)) <= 1e-13 * max(1.0, abs(eq.energy(y0, P)))
        assert abs(y[3] ** 2 + y[4] ** 2 - 1.0) <= 1e-13
        assert np.max(np.abs(y - y0)) > 0.1     # it moved


@pytest.mark.parametrize("params", PARAMS)
def test_generated_rhs_and_energy_equal_the_hand_written(orbit, params):
    P = mp.packed_params(params)
    for y in states(params):
        gen = np.empty(5)
        hand = np.empty(5)
        orbit.rhs(y, P, gen)
        eq.rhs(y, P, hand)
        assert np.max(np.abs(gen - hand)) <= 1e-15 * np.max(np.abs(hand))
        h = eq.energy(y, P)
        assert abs(orbit.energy(y, P) - h) <= 1e-15 * max(1.0, abs(h))
