"""The method registry: every integrator once, its setting validated by name, and the user layer
(sections, lyapunov, scenes, CLI) reading the same table."""
import numpy as np
import pytest

from explorer import model
from explorer.analysis import lyapunov, sections
from explorer.integrate import methods
from explorer.io import scene
from explorer.kernels import STATUS_DONE, STATUS_UNRESOLVED, splitting


def test_the_registry_holds_every_method_once_with_its_setting():
    assert methods.METHODS == ("taylor", "dop853") + tuple(splitting.SCHEMES)
    assert methods.ADAPTIVE_METHODS + methods.SPLIT_METHODS == methods.METHODS
    assert sections.METHODS is methods.METHODS
    for name, m in methods.REGISTRY.items():
        assert m.name == name and m.reference
        assert m.setting == ("tol" if name in ("taylor", "dop853") else "dt")
        if m.kind == "split":
            assert m.order == splitting.SCHEMES[name][1]


@pytest.mark.parametrize("name,kw,fragment", [
    ("taylor", dict(tol=0.5), r"tol must be in \[1e-16, 0.01\], got 0.5"),
    ("dop853", dict(tol=float("nan")), "tol must be"),
    ("split4", dict(dt=0.0), "dt must be > 0"),
    ("nope", {}, "method must be one of taylor, dop853, split2"),
])
def test_a_bad_setting_is_refused_with_its_name(name, kw, fragment):
    with pytest.raises(model.ParameterError, match=fragment):
        methods.get(name).prepare(**kw)


def test_prepared_settings_are_what_the_results_record():
    assert methods.get("taylor").prepare(tol=1e-12).settings == {"tol": 1e-12, "order": 15}
    assert methods.get("dop853").prepare(tol=1e-10).settings == {"rtol": 1e-10, "atol": 1e-10}
    p = methods.get("split6").prepare(dt=0.02)
    assert p.settings == {"dt": 0.02, "order": 6}
    assert p.flow_ids.dtype == np.int64 and len(p.flow_ids) == len(p.fracs) > 0
    prm = model.FIGURE4.with_(mu=0.5)
    y0 = model.section_state(prm, [0.1], [0.0], 2.0)
    res = sections.crossings(prm, states=y0, n_crossings=3, method="split6", dt=0.02)
    assert {k: res.settings[k] for k in ("dt", "order")} == p.settings
    ind = lyapunov.indicators(prm, states=y0, tmax=10.0, method="split6", dt=0.02)
    assert {k: ind.settings[k] for k in ("dt", "order")} == p.settings


def test_scenes_accept_exactly_the_registered_methods():
    for name in methods.METHODS:
        assert scene.IntegrationSpec(method=name).method == name
    with pytest.raises(model.ParameterError, match="integration.method"):
        scene.IntegrationSpec(method="rk4")


# ---------------------------------------------------------------- a fixed step that does not resolve the motion
#: a body spinning at M = 1e150 (dphi/dt = 5e149) and at M = 1e4, with an ordinary orbit of the Figure 4 scene
SPINNING = np.array([[0.1, -0.2, 1e150, 0.6, 0.8], [0.1, -0.2, 1e4, 0.6, 0.8], [0.1, -0.2, 2.0, 0.6, 0.8]])


@pytest.mark.parametrize("method", ["split2", "split4", "split8"])
def test_an_orbit_whose_motion_the_fixed_step_does_not_resolve_is_flagged_not_integrated(method):
    """At dt = 0.05 the split methods turned phi by 2.5e148 rad (M = 1e150) or 250 rad (M = 1e4)
    per step and reported 5 crossings as "done" at times unrelated to the motion (0.54 against
    the 6e-150 of the first crossing).  Now such an orbit (dt x model.max_rate > pi) is not
    integrated: status UNRESOLVED, no crossing, no indicator, for the crossings (whole and
    streamed) and the chaos indicators alike, and the other orbits of the batch give what they
    give alone; a step that resolves it integrates it (M = 1e4: crossings every 2 pi b/M, as
    Taylor finds them)."""
    prm = model.FIGURE4.with_(mu=0.1)
    r = sections.crossings(prm, states=SPINNING, n_crossings=5, method=method, dt=0.05, tmax=100.0)
    assert list(r.status) == [STATUS_UNRESOLVED, STATUS_UNRESOLVED, STATUS_DONE]
    assert list(r.count) == [0, 0, 5] and np.all(np.isnan(r.data[:2]))
    assert "does not resolve the motion" in r.status_name(0)
    np.testing.assert_array_equal(r.final[:2], SPINNING[:2])
    alone = sections.crossings(prm, states=SPINNING[2:], n_crossings=5, method=method, dt=0.05, tmax=100.0)
    np.testing.assert_array_equal(r.data[2], alone.data[0])
    blocks = list(sections.iter_crossings(prm, states=SPINNING, n_crossings=5, block=2, method=method, dt=0.05,
                                          tmax=100.0))
    np.testing.assert_array_equal(blocks[-1].state.status, r.status)
    ind = lyapunov.indicators(prm, states=SPINNING, tmax=10.0, method=method, dt=0.05)
    assert list(ind.status) == [STATUS_UNRESOLVED, STATUS_UNRESOLVED, STATUS_DONE]
    assert np.all(np.isnan(ind.mlce[:2])) and np.isfinite(ind.mlce[2])
    fine = 0.5 * methods.MAX_STEP_PHASE / float(model.max_rate(prm, SPINNING[1]))
    r = sections.crossings(prm, states=SPINNING[1:], n_crossings=5, method=method, dt=fine, tmax=100.0)
    assert list(r.count) == [5, 5]
    t = sections.crossings(prm, states=SPINNING[1:], n_crossings=5, method="taylor", tmax=100.0)
    np.testing.assert_allclose(np.diff(t.orbit(0)[:, 0]), 2 * np.pi * prm.b / 1e4, rtol=1e-3)
    np.testing.assert_allclose(r.orbit(0)[:, 0], t.orbit(0)[:, 0], rtol=1e-6)


def test_max_rate_bounds_the_spin_along_the_whole_orbit():
    """model.max_rate(y0) bounds |dphi/dt| = |M|/b over the orbit (an a-priori bound from the
    energy R3), also for asymmetric parameters with a heavy body, and is the Figure-4 rate
    max(|M|/b, lam/a2, ...) = 2 at mu = 0, h = 2 (so dt = 0.05 turns it by 0.1 rad per step)."""
    prm = model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=5.0, xi=0.3, eta=-0.25)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    y0 = model.section_state(prm, c1 + r1 * np.array([0.1, 0.5, -0.8]), c2 + r2 * np.array([0.0, 0.2, -0.1]), 2.0)
    bound = model.max_rate(prm, y0)
    r = sections.crossings(prm, states=y0, n_crossings=30, method="taylor", tmax=300.0)
    for i in range(3):
        assert np.abs(r.orbit(i)[:, 3]).max() / prm.b <= bound[i]
        assert np.abs(r.orbit(i)[:, 3]).max() / prm.b > 0.2 * bound[i]     # and not a vast over-estimate
    assert model.max_rate(model.FIGURE4, model.section_state(model.FIGURE4, 0.3, 0.1, 2.0)) == pytest.approx(2.0)
