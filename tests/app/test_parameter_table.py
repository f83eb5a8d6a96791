"""The one table of model parameters (explorer.model.PARAMETERS) drives the packed layout, Params
and its validation, the closed forms' indices, the commands' options and help lines and the
figure labels."""
import argparse
import math

import numpy as np
import pytest

from explorer import model
from explorer.app import figures
from explorer.app.commands import options
from explorer.model import exact


def test_the_packed_layout_and_params_follow_the_table():
    names = [p.name for p in model.PARAMETERS]
    assert list(model.PARAM_NAMES) == names and len(set(names)) == model.N_PARAMS
    for i, name in enumerate(names):
        assert getattr(model, name.upper()) == i == getattr(exact, name.upper())
    prm = model.FIGURE4.with_(mu=0.3, eta=-0.2)
    assert list(prm.as_array()) == [getattr(prm, n) for n in names]
    assert model.Params.from_array(prm.as_array()) == prm


@pytest.mark.parametrize("p", model.PARAMETERS, ids=lambda p: p.name)
def test_each_parameter_is_validated_offered_and_labelled_from_its_row(p):
    bad = {"positive": 0.0, "nonnegative": -1.0, "nonzero": 0.0}.get(p.constraint)
    if bad is not None:
        with pytest.raises(model.ParameterError, match=f"^{p.name} must be"):
            model.FIGURE4.with_(**{p.name: bad})
    good = {"positive": 2.5, "nonnegative": 0.0, "nonzero": -1.5, "": -0.75}[p.constraint]
    assert getattr(model.FIGURE4.with_(**{p.name: good}), p.name) == good
    parser = argparse.ArgumentParser()
    options.add_model_args(parser)
    assert getattr(parser.parse_args([f"--{p.name}", "0.125"]), p.name) == 0.125
    assert p.help in parser.format_help()
    assert figures.symbol_label(p.name) == f"${p.latex}$"


def test_the_energy_gradient_is_the_derivative_of_the_energy():
    prm = model.FIGURE4.with_(mu=0.7, chi=0.2, zeta=-0.1, xi=0.3, eta=0.4, lam=1.3)
    y = np.array([0.3, -0.2, 1.1, math.sin(2.0), math.cos(2.0)])
    eps = 1e-6
    numeric = [(model.energy(prm, y + eps * e) - model.energy(prm, y - eps * e)) / (2 * eps) for e in np.eye(5)]
    np.testing.assert_allclose(model.energy_gradient(prm, y), numeric, rtol=1e-8, atol=1e-9)


def test_the_notation_table_of_the_model_page_lists_every_parameter_with_its_constraint():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "model.md").read_text()
    table = text[text.index("| here | code |"):text.index("State: the reduced state")]
    rows = {}
    for line in table.splitlines()[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 4:
            for name in cells[1].replace("`", "").split(","):
                rows[name.strip()] = cells[3]
    assert set(rows) == set(model.PARAM_NAMES)
    allowed = {"positive": "> 0", "nonnegative": "≥ 0", "nonzero": "≠ 0", "": "finite"}
    for p in model.PARAMETERS:
        assert rows[p.name].startswith(allowed[p.constraint]), (p.name, rows[p.name])
