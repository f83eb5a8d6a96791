"""`python -m explorer periodic` and `rotation`: JSON shape, agreement with the library, bad input."""
import json
import math

import numpy as np
import pytest

from explorer import model
from explorer.analysis import periodic
from explorer.app import cli


def run_cli(args, capsys):
    code = cli.main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_periodic_guess_json_has_the_documented_shape_and_the_library_numbers(capsys):
    code, out, _ = run_cli(["periodic", "--period", "2", "--guess", "-1.9119,0", "--mu", "0.03", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert d["period"] == 2 and len(d["orbits"]) == 1
    o = d["orbits"][0]
    for k in ("points", "trace", "residue", "eigenvalues", "stable", "symmetric"):
        assert k in o
    ref = periodic.find_periodic_orbit(model.FIGURE4.with_(mu=0.03), 2.0, (-1.9119, 0.0), 2)
    np.testing.assert_allclose(o["points"], ref.points, atol=1e-12)
    assert o["trace"] == pytest.approx(ref.trace) and o["residue"] == pytest.approx((2 - ref.trace) / 4)


@pytest.mark.cpu_dependent
def test_periodic_search_reports_each_orbit_once_with_minimal_period(capsys):
    code, out, _ = run_cli(["periodic", "-K", "2", "--search", "--grid", "8", "--mu", "0.03", "--json"], capsys)
    assert code == 0
    orbits = json.loads(out)["orbits"]
    assert len(orbits) >= 4 and all(len(o["points"]) == 2 for o in orbits)
    pts = np.array([p for o in orbits for p in o["points"]])
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2) + np.eye(len(pts))
    assert d.min() > 1e-6


@pytest.mark.cpu_dependent
def test_periodic_continuation_prints_the_stability_changes(capsys):
    code, out, _ = run_cli(["periodic", "-K", "1", "--guess", "0,0", "--continue", "h", "3", "5", "0.5", "--json"],
                           capsys)
    assert code == 0
    d = json.loads(out)
    assert [b["type"] for b in d["bifurcations"]] == ["tangent"]
    assert d["bifurcations"][0]["value"] == pytest.approx(4.0, rel=1e-6)
    assert len(d["branch"]) == 5 and d["stopped"] is None


def test_rotation_profile_json_from_the_elliptic_point(capsys):
    code, out, _ = run_cli(["rotation", "--from", "1.5822,0", "--to", "1.45,0", "--n", "3", "--iterates", "500",
                            "--mu", "0.03", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert d["center_stable"] and len(d["profile"]) == 3
    # at the fixed point the rotation number is its linear one, trace = 2 cos(2 pi rho) (1.558448...)
    r0 = d["profile"][0]["rotation"]
    assert abs(r0) == pytest.approx(math.acos(1.5584484 / 2) / (2 * math.pi), abs=1e-3)


@pytest.mark.parametrize("args,fragment", [
    (["periodic", "--period", "0", "--guess", "0,0"], "--period must be an integer K >= 1"),
    (["periodic", "--period", "2", "--guess", "3,0"], "outside the allowed region"),
    (["periodic", "--period", "2"], "one of the arguments --guess --search is required"),
    (["periodic", "--period", "2", "--guess", "0,0", "--search"], "not allowed with"),
    (["periodic", "--period", "2", "--guess", "1"], "--guess must be two numbers"),
    (["periodic", "--period", "2", "--search", "--grid", "1"], "--grid must be"),
    (["periodic", "--period", "1", "--search", "--continue", "mu", "0", "1", "0.1"], "--continue needs --guess"),
    (["periodic", "--period", "1", "--guess", "0,0", "--continue", "nope", "0", "1", "0.1"],
     "--continue PARAM must be one of"),
    (["periodic", "--period", "1", "--guess", "0,0", "--h", "-5"], "the region is empty"),
    (["rotation", "--from", "0,0", "--to", "3,0"], "--to (3, 0) lies outside the allowed region"),
    (["rotation", "--from", "0,0", "--to", "1,0", "--n", "1"], "--n must be"),
    (["rotation", "--from", "0,0"], "the following arguments are required: --to"),
])
def test_bad_input_gives_one_line_and_status_2(args, fragment, capsys):
    code, out, err = run_cli(args, capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("explorer: error:") and fragment in err


def test_negative_values_parse_without_equals():
    a = cli.build_parser().parse_args(["rotation", "--from", "-1.2,0", "--to", "-0.5,-0.1"])
    assert a.start == "-1.2,0" and a.stop == "-0.5,-0.1"
