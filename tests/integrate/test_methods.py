"""The method registry: every integrator once, its setting validated by name, and the user layer
(sections, lyapunov, scenes, CLI) reading the same table."""
import numpy as np
import pytest

from explorer import model
from explorer.analysis import lyapunov, sections
from explorer.integrate import methods
from explorer.io import scene
from explorer.kernels import splitting


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
    res = sections.crossings(prm, y0, 3, method="split6", dt=0.02)
    assert {k: res.settings[k] for k in ("dt", "order")} == p.settings
    ind = lyapunov.indicators(prm, y0, 10.0, method="split6", dt=0.02)
    assert {k: ind.settings[k] for k in ("dt", "order")} == p.settings


def test_scenes_accept_exactly_the_registered_methods():
    for name in methods.METHODS:
        assert scene.IntegrationSpec(method=name).method == name
    with pytest.raises(model.ParameterError, match="integration.method"):
        scene.IntegrationSpec(method="rk4")
