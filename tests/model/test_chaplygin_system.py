"""Chaplygin's R3 as a System (explorer.model.chaplygin, docs/model.md R3) through the Taylor
generator (explorer.integrate.codegen, docs/systems.md): its recurrence, right-hand side, energy and
variational recurrence equal the hand-written ones of explorer.model.equations to round-off.

Not bit for bit: the generator sums a right-hand side's terms in SymPy's canonical order (added
terms first, then the subtracted ones) and computes the scalar factors as SymPy writes them
((a1 - a2)/(a1 a2) for 1/a2 - 1/a1, (zeta/b) M for zeta (M/b)), and sympy.cse rebuilds any other
grouping a caller writes; the hand-written recurrence fixes its own order of the same operations.
"""
import numpy as np
import pytest

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


@pytest.fixture(scope="module")
def tangent():
    return codegen.load(chaplygin.variational())


def states(params, n=6, seed=4):
    """n states: random ones (|p|, |M| up to 2) and, at Figure 4's energy, section points (R9)."""
    rng = np.random.default_rng(seed)
    y = rng.uniform(-2, 2, (n, 5))
    phi = rng.uniform(0, 2 * np.pi, n)
    y[:, 3], y[:, 4] = np.sin(phi), np.cos(phi)
    c1, c2, r1, r2 = mp.allowed_ellipse(params, mp.FIGURE4_H)
    p1 = c1 + r1 * np.array([-0.6, 0.1, 0.7])
    return np.vstack([y, mp.section_state(params, p1, np.full(3, c2), mp.FIGURE4_H)])


def relative_to_each_order(gen, hand):
    """max |gen - hand| over the rows of each order k, over that order's largest |hand|."""
    return np.max(np.abs(gen - hand), axis=0) / np.max(np.abs(hand), axis=0)


#: the bound of :func:`relative_to_each_order` at each order k: 1e-15, or (k + 1) eps where that is
#: larger (k > 3), as each order inherits the rounding of the lower ones (observed: 4e-15 at k = 30)
BOUND = np.maximum(1e-15, (np.arange(ORDER + 1) + 1) * np.finfo(float).eps)


def test_parameters_are_the_packed_vector_and_the_state_is_r3s():
    s = chaplygin.system(PARAMS[1])
    assert [p.name for p in s.parameters] == list(mp.PARAM_NAMES)
    assert np.array_equal(s.parameter_array(), mp.packed_params(PARAMS[1]))
    assert [x.name for x in s.states] == ["p1", "p2", "M", "g1", "g2"]


@pytest.mark.parametrize("params", PARAMS)
def test_generated_recurrence_equals_the_hand_written_to_1e_15_k_eps_of_each_order(orbit, params):
    P = mp.packed_params(params)
    worst = 0.0
    for y in states(params):
        gen = np.zeros((5, ORDER + 1))
        hand = np.zeros((5, ORDER + 1))
        gen[:, 0] = hand[:, 0] = y
        orbit.taylor_coefficients(P, gen, ORDER)
        eq.taylor_coefficients(P, hand, ORDER)
        worst = max(worst, (relative_to_each_order(gen, hand) / BOUND).max())
    assert worst <= 1.0, worst


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


@pytest.mark.parametrize("params", PARAMS)
def test_variational_recurrence_equals_taylor_coefficients_tangent(tangent, params):
    P = mp.packed_params(params)
    rng = np.random.default_rng(9)
    worst = 0.0
    for y in states(params):
        d = rng.uniform(-1, 1, 5)
        Z = np.zeros((10, ORDER + 1))
        Z[:5, 0], Z[5:, 0] = y, d
        tangent.taylor_coefficients(P, Z, ORDER)
        X = np.zeros((5, ORDER + 1))
        D = np.zeros((5, ORDER + 1))
        X[:, 0], D[:, 0] = y, d
        eq.taylor_coefficients_tangent(P, X, D, ORDER)
        worst = max(worst, (relative_to_each_order(Z[:5], X) / BOUND).max(),
                    (relative_to_each_order(Z[5:], D) / BOUND).max())
    assert worst <= 1.0, worst


def test_a_regular_orbit_on_either_recurrence_agrees_to_1e_13(orbit):
    """R5 case 3 (chi = -lam eta, zeta = lam xi, a1 = a2 = 1: integrable, every orbit regular) with
    weight and circulation asymmetry: 400 Taylor steps of 0.1 (T = 40) with each recurrence from
    one section point stay within 1e-13 of each other (observed 3e-14; 1e-13 at T = 100)."""
    params = mp.Params(a1=1.0, a2=1.0, b=1.7, lam=1.0, chi=0.25, zeta=0.3, mu=0.7, xi=0.3, eta=-0.25)
    P = mp.packed_params(params)
    y0 = states(params)[-1]
    order = 20
    ys = []
    for coefficients in (orbit.taylor_coefficients, eq.taylor_coefficients):
        X = np.zeros((5, order + 1))
        y = y0.copy()
        for _ in range(400):
            X[:, 0] = y
            coefficients(P, X, order)
            evaluate(X, order, 0.1, y)
        ys.append(y)
    assert np.max(np.abs(ys[0] - ys[1])) <= 1e-13
    assert np.max(np.abs(ys[0] - y0)) > 0.1     # it moved
