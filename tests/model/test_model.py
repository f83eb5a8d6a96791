"""Every equation of docs/model.md used by the code, checked (R3, R4, R5, R9)."""
import math

import numpy as np
import pytest
from conftest import PARAM_SETS, random_states

import reference
from explorer import model
from explorer.integrate import _lanes_generated
from explorer.model import ParameterError, equations


def grad_fd(fun, y, eps=1e-6):
    """Central-difference gradient of a scalar function of the state."""
    g = np.empty(5)
    for i in range(5):
        yp = y.copy()
        ym = y.copy()
        yp[i] += eps
        ym[i] -= eps
        g[i] = (fun(yp) - fun(ym)) / (2 * eps)
    return g


def field(params, y):
    out = np.empty(5)
    equations.rhs(y, params.as_array(), out)
    return out


# ---------------------------------------------------------------- parameters
@pytest.mark.parametrize("name,value,fragment", [
    ("a1", 0.0, "a1 must be > 0"), ("a2", -1.0, "a2 must be > 0"), ("b", 0.0, "b must be > 0"),
    ("lam", 0.0, "lam must be nonzero"), ("mu", -0.1, "mu must be >= 0"),
    ("chi", float("nan"), "chi must be finite"), ("eta", float("inf"), "eta must be finite"),
    ("xi", "abc", "xi must be a number"),
])
def test_bad_parameter_is_refused_with_its_name(name, value, fragment):
    with pytest.raises(ParameterError, match=fragment):
        model.FIGURE4.with_(**{name: value})


def test_figure4_preset_is_model_md_r9():
    assert model.FIGURE4.as_dict() == dict(a1=1.0, a2=0.5, b=2.0, lam=1.0, chi=0.0, zeta=0.0, mu=0.0, xi=0.0, eta=0.0)
    assert model.FIGURE4_H == 2.0
    assert model.Params.from_array(model.FIGURE4.as_array()) == model.FIGURE4


# ---------------------------------------------------------------- R3: field and energy
@pytest.mark.parametrize("name", sorted(PARAM_SETS))
def test_compiled_field_matches_numpy_twin_and_independent_reference(name):
    prm = PARAM_SETS[name]
    for y in random_states(prm, 20, seed=1):
        f = field(prm, y)
        np.testing.assert_allclose(f, model.rhs(prm, y), rtol=0, atol=1e-14)
        np.testing.assert_allclose(f, reference.rhs_numpy(0.0, y, prm.as_array()), rtol=0, atol=1e-14)
        assert equations.energy(y, prm.as_array()) == pytest.approx(model.energy(prm, y), abs=1e-14)
        assert model.energy(prm, y) == pytest.approx(reference.energy_numpy(y, prm.as_array()), abs=1e-14)


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
def test_energy_and_casimir_are_integrals_of_the_field(name):
    """dH/dt = grad H . f = 0 and d(g1^2 + g2^2)/dt = 0 for R3 (central differences)."""
    prm = PARAM_SETS[name]
    for y in random_states(prm, 20, seed=2):
        f = field(prm, y)
        dH = grad_fd(lambda z: model.energy(prm, z), y) @ f
        dC = grad_fd(model.casimir, y) @ f
        assert abs(dH) < 1e-8
        assert abs(dC) < 1e-8


def test_energy_would_fail_with_the_seed_double_counted_gravity():
    """docs/model.md R3: reading dH/dp in ur12 as the full gradient counts -mu g twice; the
    resulting field does not conserve H (so the test above can fail)."""
    prm = PARAM_SETS["figure4_mu0.5"]
    y = random_states(prm, 1, seed=3)[0]
    f = field(prm, y)
    f[:2] -= prm.mu * y[3:5]
    assert abs(grad_fd(lambda z: model.energy(prm, z), y) @ f) > 1e-3


# ---------------------------------------------------------------- R5: integrable cases
CASES = {
    "case1_chaplygin": (dict(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.0, xi=0.3, eta=-0.25),
                        model.chaplygin_integral),
    "case2_kozlov": (dict(a1=0.7, a2=0.7, b=1.7, lam=1.3, chi=0.0, zeta=0.0, mu=0.9, xi=0.3, eta=-0.25),
                     model.kozlov_integral),
    "case3": (dict(a1=1.0, a2=1.0, b=1.7, lam=1.3, chi=-1.3 * -0.25, zeta=1.3 * 0.3, mu=0.9, xi=0.3, eta=-0.25),
              model.case3_integral),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_extra_integral_of_each_integrable_case_is_conserved_by_the_field(case):
    kw, F = CASES[case]
    prm = model.Params(**kw)
    for y in random_states(prm, 20, seed=4):
        assert abs(grad_fd(lambda z: F(prm, z), y) @ field(prm, y)) < 1e-8


def test_case3_integral_fails_for_unequal_masses():
    """docs/model.md R5: case 3 needs a1 = a2 = 1; with a1 != a2 F is not an integral."""
    kw = dict(CASES["case3"][0], a1=1.4)
    prm = model.Params(**kw)
    rates = [abs(grad_fd(lambda z: model.case3_integral(prm, z), y) @ field(prm, y))
             for y in random_states(prm, 5, seed=5)]
    assert max(rates) > 1e-3


def test_hess_relation_df_dt_equals_eta_over_b_p2_f():
    """docs/model.md R5 case 4: chi = zeta = xi = 0, eta^2 = b (1/a2 - 1/a1): dF/dt = (eta/b) p2 F."""
    base = model.Params(a1=1.5, a2=0.6, b=1.7, lam=0.9, mu=0.8)
    prm = base.with_(eta=model.hess_eta(base))
    for y in random_states(prm, 20, seed=6):
        dF = grad_fd(lambda z: model.hess_function(prm, z), y) @ field(prm, y)
        assert dF == pytest.approx(prm.eta / prm.b * y[1] * model.hess_function(prm, y), abs=1e-8)
    # the seed's F (without eta p1 - lam b/a2) is not invariant
    seed_F = lambda z: z[2]  # noqa: E731
    y = random_states(prm, 1, seed=7)[0]
    assert abs(grad_fd(seed_F, y) @ field(prm, y) - prm.eta / prm.b * y[1] * seed_F(y)) > 1e-3


# ---------------------------------------------------------------- R4: the splitting
def subfield(k, P, y):
    """The vector field of sub-Hamiltonian k written out from docs/model.md R4."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = P
    p1, p2, m, g1, g2 = y
    if k == equations.FLOW_HM:
        w = m / b
        return np.array([w * (p2 - zeta), -w * (p1 - chi), 0.0, w * g2, -w * g1])
    if k == equations.FLOW_H1:
        return np.array([0.0, lam * p1 / a1, -(p2 - zeta) * p1 / a1, 0.0, 0.0])
    if k == equations.FLOW_H2:
        return np.array([-lam * p2 / a2, 0.0, (p1 - chi) * p2 / a2, 0.0, 0.0])
    return np.array([-mu * g1, -mu * g2, -mu * (xi * g2 - eta * g1), 0.0, 0.0])


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
def test_subfields_sum_to_the_full_field(name):
    prm = PARAM_SETS[name]
    P = prm.as_array()
    for y in random_states(prm, 10, seed=8):
        total = sum(subfield(k, P, y) for k in range(equations.N_FLOWS))
        np.testing.assert_allclose(total, field(prm, y), atol=1e-14)


@pytest.mark.parametrize("k", range(4))
@pytest.mark.parametrize("t", [0.1, 1.0, 10.0])
def test_each_subflow_is_exact(k, t):
    """Closed-form sub-flows of R4 against scipy's DOP853 at rtol = atol = 1e-13 on the sub-field."""
    from scipy.integrate import solve_ivp

    prm = PARAM_SETS["asym_lam_neg"]
    P = prm.as_array()
    y0 = random_states(prm, 1, seed=9)[0]
    ref = solve_ivp(lambda _t, z: subfield(k, P, z), (0.0, t), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    y = y0.copy()
    equations.apply_flow(k, y, P, t)
    scale = max(1.0, np.abs(ref).max())
    assert np.abs(y - ref).max() <= 1e-11 * scale


@pytest.mark.parametrize("k", range(4))
def test_each_subflow_is_a_group(k):
    """phi_t o phi_s = phi_{t+s} and phi_{-t} o phi_t = id (to round-off)."""
    prm = PARAM_SETS["asym_lam_pos"]
    P = prm.as_array()
    y0 = random_states(prm, 1, seed=10)[0]
    a = y0.copy()
    equations.apply_flow(k, a, P, 0.3)
    equations.apply_flow(k, a, P, 0.4)
    b = y0.copy()
    equations.apply_flow(k, b, P, 0.7)
    np.testing.assert_allclose(a, b, atol=1e-14)
    equations.apply_flow(k, b, P, -0.7)
    np.testing.assert_allclose(b, y0, atol=1e-14)


# ---------------------------------------------------------------- Taylor coefficients
@pytest.mark.parametrize("name", sorted(PARAM_SETS))
def test_taylor_series_reproduces_the_flow(name):
    from scipy.integrate import solve_ivp

    from explorer.kernels import taylor

    prm = PARAM_SETS[name]
    P = prm.as_array()
    y0 = random_states(prm, 1, seed=11)[0]
    order = 30
    X = np.zeros((5, order + 1))
    X[:, 0] = y0
    _lanes_generated.taylor_coefficients(P, X, order)   # generated from explorer.model.chaplygin
    np.testing.assert_allclose(X[:, 1], field(prm, y0), atol=1e-15)
    out = np.empty(5)
    for h in (0.02, 0.1):
        taylor.evaluate(X, order, h, out)
        ref = solve_ivp(lambda _t, z: reference.rhs_numpy(_t, z, P), (0, h), y0, method="DOP853",
                        rtol=1e-13, atol=1e-13).y[:, -1]
        assert np.abs(out - ref).max() < 1e-12


# ---------------------------------------------------------------- R9: the section
def test_section_state_has_the_requested_energy_on_the_section(param_set):
    _, prm = param_set
    h = 2.0
    rng = np.random.default_rng(0)
    rad = np.sqrt(rng.uniform(0, 1, 50))
    ang = rng.uniform(0, 2 * np.pi, 50)
    for phi0 in (math.pi, 0.7):
        c1, c2, r1, r2 = model.allowed_ellipse(prm, h, phi0)
        p1 = c1 + 0.99 * r1 * rad * np.cos(ang)
        p2 = c2 + 0.99 * r2 * rad * np.sin(ang)
        y = model.section_state(prm, p1, p2, h, phi0)
        np.testing.assert_allclose(model.energy(prm, y), h, atol=1e-13)
        assert np.all(y[:, 2] >= 0)
        np.testing.assert_allclose(y[:, 3], math.sin(phi0) if phi0 != math.pi else 0.0)


def test_allowed_region_boundary_has_zero_M(param_set):
    _, prm = param_set
    h = 2.0
    for phi0 in (math.pi, 0.7, -2.0):
        c1, c2, r1, r2 = model.allowed_ellipse(prm, h, phi0)
        ang = np.linspace(0, 2 * np.pi, 17)
        m2 = model.section_M2(prm, c1 + r1 * np.cos(ang), c2 + r2 * np.sin(ang), h, phi0)
        np.testing.assert_allclose(m2, 0.0, atol=1e-12)
        assert model.is_admissible(prm, c1, c2, h, phi0)
        assert not model.is_admissible(prm, c1 + 1.01 * r1, c2, h, phi0)


def test_r9_formula_at_phi_pi():
    """docs/model.md R9 as printed: M^2 = 2b (h - 1/2(p1^2/a1 + p2^2/a2) - (mu/lam)(p1 - chi) + mu eta)."""
    prm = PARAM_SETS["asym_lam_neg"]
    p1, p2, h = 0.3, -0.2, 2.0
    expect = 2 * prm.b * (h - 0.5 * (p1**2 / prm.a1 + p2**2 / prm.a2) - prm.mu / prm.lam * (p1 - prm.chi)
                          + prm.mu * prm.eta)
    assert model.section_M2(prm, p1, p2, h) == pytest.approx(expect, abs=1e-14)


def test_point_outside_the_allowed_region_is_refused():
    with pytest.raises(ParameterError, match="outside the allowed region"):
        model.section_state(model.FIGURE4, 5.0, 0.0, 2.0)
    assert model.allowed_ellipse(model.FIGURE4, -1.0) is None
