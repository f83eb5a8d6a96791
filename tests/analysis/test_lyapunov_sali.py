"""SALI and GALI_2 from two deviation vectors (Skokos 2001; Skokos, Bountis & Antonopoulos
2007): they stay away from 0 on regular orbits of the integrable cases (at most a power-law
decay), fall below 1e-8 on a chaotic orbit of Figure 4 at mu = 1, and GALI_2 is the norm of the
wedge product of the two final unit vectors; `explorer lyapunov --json` reports both; only what
is asked for is computed."""
import json

import numpy as np
import pytest

from explorer import model
from explorer.analysis import lyapunov
from explorer.app import cli
from explorer.model import ParameterError

REGULAR = ([0.6, 0.0, -0.5, 1.8], [0.5, 1.0, 0.8, 0.1])
KOZLOV = model.Params(a1=0.7, a2=0.7, b=1.7, lam=1.3, mu=0.9, xi=0.3, eta=-0.25)
BOTH = ("mlce", "megno", "sali", "gali2")


def _integrable_cases():
    c1, c2, r1, r2 = model.allowed_ellipse(KOZLOV, 2.0)
    return [(model.FIGURE4, model.section_state(model.FIGURE4, *REGULAR, 2.0)),
            (KOZLOV, model.section_state(KOZLOV, [c1 + 0.3 * r1, c1 - 0.4 * r1], [c2 + 0.2 * r2, c2 - 0.1 * r2],
                                         2.0))]


@pytest.mark.parametrize("case", [0, 1], ids=["chaplygin_mu0", "kozlov"])
def test_sali_stays_away_from_zero_on_regular_orbits_of_the_integrable_cases(case):
    """Measured at T = 1e3 and 1e4: Chaplygin's case 0.04-0.48 (no decay), Kozlov's case
    ~ 1/T (5e-4 at 1e4); a chaotic orbit reaches 1e-8 within T = 100.  Held: SALI(1e4) > 1e-4
    and the decay from 1e3 to 1e4 no faster than T^-2 (a power law, not an exponential)."""
    prm, y0 = _integrable_cases()[case]
    a = lyapunov.indicators(prm, states=y0, tmax=1e3, tol=1e-12, which=BOTH)
    b = lyapunov.indicators(prm, states=y0, tmax=1e4, tol=1e-12, which=BOTH)
    assert np.all(b.sali > 1e-4), b.sali
    assert np.all(b.sali >= a.sali * 1e-2), (a.sali, b.sali)
    assert np.all(b.gali2 > 1e-4)


def test_sali_falls_below_1e_8_on_a_chaotic_orbit_of_figure4_at_mu_1():
    prm = model.FIGURE4.with_(mu=1.0)
    y0 = model.section_state(prm, [-0.2, 0.0], [0.1, 0.3], 2.0)
    r = lyapunov.indicators(prm, states=y0, tmax=1000.0, tol=1e-12, which=BOTH)
    assert np.all(r.sali < 1e-8), r.sali
    assert np.all(r.megno > 20)


def test_gali2_is_the_wedge_norm_of_the_two_final_unit_vectors():
    prm = model.FIGURE4.with_(mu=0.03)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    rng = np.random.default_rng(2)
    y0 = model.section_state(prm, c1 + 0.5 * r1 * rng.uniform(-1, 1, 12), c2 + 0.5 * r2 * rng.uniform(-1, 1, 12),
                             2.0)
    r = lyapunov.indicators(prm, states=y0, tmax=200.0, tol=1e-12, which=("sali", "gali2"))
    w1, w2 = r.deviation[:, 0], r.deviation[:, 1]
    np.testing.assert_allclose(np.linalg.norm(w1, axis=1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(w2, axis=1), 1.0, rtol=1e-14)
    # GALI_2 = |w1 ^ w2| = product of the singular values of [w1 w2] = sqrt(det of the Gram matrix)
    sv = np.linalg.svd(np.stack([w1, w2], axis=2), compute_uv=False)
    np.testing.assert_allclose(r.gali2, sv[:, 0] * sv[:, 1], rtol=1e-9, atol=1e-15)
    gram = 1.0 - np.sum(w1 * w2, axis=1) ** 2
    ok = gram > 1e-6
    np.testing.assert_allclose(r.gali2[ok], np.sqrt(gram[ok]), rtol=1e-9)
    sali = np.minimum(np.linalg.norm(w1 + w2, axis=1), np.linalg.norm(w1 - w2, axis=1))
    np.testing.assert_allclose(r.sali, sali, rtol=1e-12, atol=1e-300)
    # for unit vectors GALI_2 = |w1 + w2| |w1 - w2| / 2, so SALI and GALI_2 fall together
    big = np.maximum(np.linalg.norm(w1 + w2, axis=1), np.linalg.norm(w1 - w2, axis=1))
    np.testing.assert_allclose(r.gali2, r.sali * big / 2, rtol=1e-9, atol=1e-15)


def test_only_the_indicators_asked_for_are_computed():
    prm = model.FIGURE4.with_(mu=1.0)
    y0 = model.section_state(prm, [-0.2], [0.1], 2.0)
    one = lyapunov.indicators(prm, states=y0, tmax=100.0, tol=1e-12)
    two = lyapunov.indicators(prm, states=y0, tmax=100.0, tol=1e-12, which=("megno", "sali"))
    assert np.isnan(one.sali).all() and np.isnan(one.deviation[:, 1]).all()
    assert np.isfinite(two.sali).all()
    # the second vector changes nothing of the first one's indicators
    for name in ("time", "mlce", "megno", "fli", "steps", "final"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    with pytest.raises(ParameterError, match="indicators must be"):
        lyapunov.indicators(prm, states=y0, tmax=100.0, which=("lyapunov",))
    with pytest.raises(ParameterError, match="needs method 'taylor'"):
        lyapunov.indicators(prm, states=y0, tmax=100.0, method="split6", which=("sali",))


def test_the_methods_of_two_vector_indicators_are_those_with_the_loop_of_two_vectors():
    from explorer.integrate import methods

    two = tuple(n for n in methods.METHODS if methods.get(n).loops.tangent_ext is not None)
    assert two == lyapunov.TWO_VECTOR_METHODS == ("taylor",)
    for name in ("sali", "gali2"):
        assert lyapunov.methods_for(name) == two
    for name in ("mlce", "megno", "fli"):
        assert lyapunov.methods_for(name) == methods.METHODS
    assert "sali" in lyapunov.available("taylor") and "sali" not in lyapunov.available("dop853")
    assert set(lyapunov.available("dop853")) == {"mlce", "megno", "fli"}


def test_lyapunov_cli_json_reports_sali_and_gali2(capsys):
    code = cli.main(["lyapunov", "--p1", "-0.2", "--p2", "0.1", "--mu", "1", "--tmax", "500", "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    doc = json.loads(out)
    assert doc["sali"] < 1e-8 and doc["gali2"] < 1e-8
    code = cli.main(["lyapunov", "--p1", "-0.2", "--p2", "0.1", "--mu", "1", "--tmax", "50", "--json",
                     "--method", "split6"])
    doc = json.loads(capsys.readouterr()[0])
    assert doc["sali"] is None and doc["gali2"] is None
