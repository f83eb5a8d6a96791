"""The half-turn symmetries of R3 (docs/model.md, "Symmetries"; explorer.model.symmetry,
explorer.analysis.halfturn), checked against the equations as tests/reference.py writes them from
docs/model.md and against scipy's DOP853 (tests/reference.py), not the project's integrators."""
import math

import numpy as np
import pytest
from conftest import random_states

import reference
from explorer import model
from explorer.analysis import halfturn
from explorer.model import ParameterError, symmetry

H = 2.0
FIG = model.FIGURE4.with_(mu=0.1)
#: every parameter generic except chi = eta = 0: K holds, G and S do not (zeta, xi != 0)
K_ONLY = model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.0, zeta=-0.15, mu=0.7, xi=0.3, eta=0.0)

#: name: (params, K a symmetry, S a symmetry)
CASES = {
    "figure4": (FIG, True, True),
    "chi=eta=0, zeta and xi free": (K_ONLY, True, False),
    "zeta only": (FIG.with_(zeta=0.2), True, False),
    "xi only": (FIG.with_(xi=0.3), True, False),
    "eta, mu = 0": (model.FIGURE4.with_(eta=0.3), True, True),
    "eta": (FIG.with_(eta=0.3), False, False),
    "chi": (FIG.with_(chi=0.2), False, False),
    "chi, generic": (K_ONLY.with_(chi=-0.1), False, False),
}


def _rhs(params, y):
    return reference.rhs_numpy(0.0, np.asarray(y).T, params.as_array()).T


@pytest.mark.parametrize("name", sorted(CASES))
def test_half_turn_maps_reverse_or_keep_R3_exactly_when_chi_and_mu_eta_vanish(name):
    """K (p1 -> -p1, phi -> pi - phi, t -> -t) reverses the field of R3, f(K y) = -K f(y), exactly
    when chi = 0 and mu eta = 0; S = G K (p -> -p, phi -> phi + pi) keeps the field,
    f(S y) = S f(y), exactly when also zeta = 0 and mu xi = 0.  Where a condition fails, the
    identity fails by far more than round-off.  (H(K y) = H(y) needs only mu (chi/lam + eta) = 0,
    which none of the broken cases here meets.)"""
    prm, k_holds, s_holds = CASES[name]
    y = random_states(prm, 50, seed=3)
    P = prm.as_array()
    k_err = np.abs(_rhs(prm, symmetry.half_turn_reversor(y)) + symmetry.half_turn_reversor(_rhs(prm, y))).max()
    h_err = np.abs(reference.energy_numpy(symmetry.half_turn_reversor(y).T, P) - reference.energy_numpy(y.T, P)).max()
    s_err = np.abs(_rhs(prm, symmetry.half_turn(y)) - symmetry.half_turn(_rhs(prm, y))).max()
    assert symmetry.has_half_turn_symmetry(prm) is k_holds
    assert bool(k_err < 1e-13) is k_holds and bool(h_err < 1e-13) is k_holds, (k_err, h_err)
    assert bool(s_err < 1e-13) is s_holds, s_err
    if not k_holds:
        assert k_err > 1e-3
        assert symmetry.half_turn_violations(prm)
    else:
        assert symmetry.half_turn_violations(prm) == []


def _partner_scipy(prm, x, h=H):
    """T(x) with scipy: K of the state on phi = pi, then DOP853 to the next crossing of phi = pi."""
    P = prm.as_array()
    y = symmetry.half_turn_reversor(reference.state_on_section(P, x[0], x[1], h))
    row = reference.scipy_crossings(P, y, 1)[0]
    return row[1:3], row[0]


@pytest.mark.parametrize("prm", [FIG, K_ONLY], ids=["figure4", "zeta and xi free"])
def test_partner_map_is_an_involution_that_reverses_the_section_map(prm):
    """T = (flow from phi = 0 to pi) o K: partner_points equals the scipy construction, T(T(x)) = x,
    and P(T(P(x))) = T(x) (T P = P^-1 T) with P scipy's section map, also where G, the
    reflection p2 -> -p2, is not a symmetry (zeta, xi != 0)."""
    c1, c2, r1, r2 = model.allowed_ellipse(prm, H)
    xs = np.array([[c1 + 0.3 * r1, c2 + 0.2 * r2], [c1 - 0.5 * r1, c2 - 0.1 * r2]])
    got = halfturn.partner_points(prm, H, xs)
    assert got.status == ("done", "done")
    P = prm.as_array()
    for x, tx, t in zip(xs, got.points, got.times):
        ref, t_ref = _partner_scipy(prm, x)
        np.testing.assert_allclose(tx, ref, atol=1e-9)
        assert t == pytest.approx(t_ref, abs=1e-9)
        np.testing.assert_allclose(halfturn.partner_points(prm, H, tx).points[0], x, atol=1e-9)
        px = reference.section_map_p(P, x[0], x[1], H)
        tpx = halfturn.partner_points(prm, H, px).points[0]
        np.testing.assert_allclose(reference.section_map_p(P, tpx[0], tpx[1], H), tx, atol=1e-8)


@pytest.mark.parametrize("mu,guesses", [(0.1, (-1.044, 1.571)), (0.03, (-1.155, 1.582))])
def test_distinct_fixed_points_paired_by_the_half_turn_share_trace_and_return_time(mu, guesses):
    """Figure 4 scene: the elliptic fixed points near p1 = -1.044 and 1.571 (mu = 0.1), -1.155 and
    1.582 (mu = 0.03) are each other's partner, so their traces and return times agree (found
    and measured with scipy alone); with eta = 0.3 the pairing is gone and so is the equality."""
    prm = model.FIGURE4.with_(mu=mu)
    P = prm.as_array()
    x1, x2 = (reference.symmetric_fixed_point(P, H, g) for g in guesses)
    for x in (x1, x2):
        assert abs(reference.section_map_p(P, x, 0.0, H)[0] - x) < 1e-9
    assert abs(x1 - x2) > 2.0
    np.testing.assert_allclose(halfturn.partner_points(prm, H, (x1, 0.0)).points[0], (x2, 0.0), atol=1e-8)
    tr1, tr2 = (reference.section_map_trace(P, H, x) for x in (x1, x2))
    assert abs(tr1) < 2 and tr1 == pytest.approx(tr2, abs=1e-6)
    t1, t2 = (reference.scipy_one_step_map(P, reference.state_on_section(P, x, 0.0, H))[0] for x in (x1, x2))
    assert t1 == pytest.approx(t2, abs=1e-9)
    eta = prm.with_(eta=0.3)
    Pe = eta.as_array()
    e1, e2 = (reference.symmetric_fixed_point(Pe, H, x) for x in (x1, x2))
    assert abs(reference.section_map_trace(Pe, H, e1) - reference.section_map_trace(Pe, H, e2)) > 1e-2
    with pytest.raises(ParameterError, match=r"chi = 0 and mu eta = 0; here eta = 0.3"):
        halfturn.partner_points(eta, H, (e1, 0.0))


def test_on_the_section_phi_pi_over_2_the_partner_is_the_reflection_itself():
    """K maps phi = pi/2 to itself, so there T = K: (p1, p2) -> (-p1, p2), and it still reverses P."""
    prm = K_ONLY
    phi0 = math.pi / 2
    c1, c2, r1, r2 = model.allowed_ellipse(prm, H, phi0)
    x = np.array([c1 + 0.2 * r1, c2 + 0.3 * r2])
    got = halfturn.partner_points(prm, H, x, phi0=phi0)
    np.testing.assert_array_equal(got.points[0], [-x[0], x[1]])
    P = prm.as_array()

    def step(p):
        return reference.scipy_one_step_map(P, reference.state_on_section(P, p[0], p[1], H, phi0), phi0=phi0)[1:3]

    px = step(x)
    np.testing.assert_allclose(step(np.array([-px[0], px[1]])), [-x[0], x[1]], atol=1e-8)
