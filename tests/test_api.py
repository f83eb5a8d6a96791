"""The public API: small, explicit, lazy, documented."""
import inspect
import subprocess
import sys

import numpy as np
import pytest

import explorer


def test_import_explorer_loads_no_heavy_dependency():
    code = ("import sys, explorer; heavy = [m for m in ('numba', 'matplotlib', 'h5py', 'scipy') "
            "if m in sys.modules]; print(','.join(heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


@pytest.mark.parametrize("name", [n for n in explorer.__all__ if n != "__version__"])
def test_every_public_name_resolves_and_is_documented(name):
    obj = getattr(explorer, name)
    if inspect.isclass(obj) or inspect.isfunction(obj):
        doc = inspect.getdoc(obj) or ""
        # a dataclass without a docstring gets its signature as __doc__: not documentation
        assert doc and not doc.startswith(f"{obj.__name__}("), f"explorer.{name} has no docstring"
    assert name in dir(explorer)


#: public callables that take keywords of their own naming, not a pass-through: why
KEYWORD_DATA = {
    "Params.with_": "the changes are parameter names, each validated by Params",
    "System.with_": "the changes are parameter names, each validated by System",
}


def test_no_public_function_hides_its_keywords_behind_a_pass_through():
    """Every keyword of the public API is in its signature (an IDE shows it), so a
    ``**kw`` forwarded to another function is gone; only the named keyword data remain."""
    hidden = []
    for name in explorer.__all__:
        obj = getattr(explorer, name)
        members = [(name, obj)]
        if inspect.isclass(obj):
            members = [(f"{name}.{k}", v) for k, v in vars(obj).items()
                       if inspect.isfunction(v) and (not k.startswith("_") or k in ("__init__", "__call__"))]
        for label, f in members:
            if label in KEYWORD_DATA or not getattr(f, "__module__", "").startswith("explorer"):
                continue
            try:
                sig = inspect.signature(f)
            except (TypeError, ValueError):
                continue
            if any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values()):
                hidden.append(f"{label}{sig}")
    assert not hidden, hidden


def test_explore_names_every_model_parameter_and_setting_it_takes():
    """``explore(**settings)`` is gone: each model parameter of docs/model.md and each setting of
    the page is a keyword of its own (the count is ``n_crossings``, the API's one name)."""
    from explorer import model

    params = inspect.signature(explorer.explore).parameters
    assert set(model.PARAM_NAMES) | {"h", "method", "tol", "dt", "n_crossings"} <= set(params)
    assert all(params[k].kind == inspect.Parameter.KEYWORD_ONLY for k in model.PARAM_NAMES)


def test_result_types_are_frozen():
    import dataclasses

    for cls in (explorer.Crossings, explorer.Indicators, explorer.FixedPoint, explorer.Branch,
                explorer.SweepReport, explorer.PeriodicOrbit):
        assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen, cls


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'sectionz'"):
        explorer.sectionz  # noqa: B018


def test_the_package_docstring_example_runs_and_conserves_energy():
    ex = explorer
    prm = ex.FIGURE4.with_(mu=0.5)
    smap = ex.SectionMap(prm, ex.FIGURE4_H)
    res = ex.crossings(smap, [(0.1, 0.0), (0.3, 0.0)], n_crossings=50)
    assert res.count.tolist() == [50, 50]
    assert np.nanmax(np.abs(res.data[..., 4])) < 1e-10          # H - H0 at every crossing
    assert res.status_of(0) is ex.Status.DONE
    fp = ex.find_fixed_point(smap, (-0.2, 0.0))
    assert abs(fp.point[1]) < 1e-12 and not fp.stable                  # solution I, hyperbolic at mu = 0.5
    ind = ex.indicators(smap, [(0.1, 0.0)], tmax=100.0)
    assert np.isfinite(ind.megno[0])


def test_the_type_stub_names_exactly_the_public_api_from_the_modules_that_define_it():
    """src/explorer/__init__.pyi (what IDEs read in place of the lazy __getattr__) imports each
    public name from the module that defines it, and nothing else."""
    import ast
    from pathlib import Path

    tree = ast.parse((Path(explorer.__file__).with_suffix(".pyi")).read_text())
    stubbed = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                assert alias.asname == alias.name          # "import X as X": a re-export
                stubbed[alias.name] = node.module
    assert stubbed == explorer._EXPORTS
