"""`python -m explorer greene`: the JSON of the documented shape, the library's numbers, bad input."""
import json
import math

import pytest
from test_cli_periodic import run_cli

import explorer as ex
from explorer.analysis import greene as gm
from explorer.analysis import greene_core
from explorer.app import cli


def test_greene_standard_json_has_the_documented_shape_and_greenes_k_c(capsys):
    code, out, _ = run_cli(["greene", "--map", "standard", "--nu", "golden", "--qmax", "233", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert set(d) == {"map", "param", "nu", "critical", "uncertainty", "convergents"}
    assert d["map"] == "standard" and d["param"] == "k" and d["nu"] == pytest.approx((math.sqrt(5) - 1) / 2)
    assert abs(d["critical"] - 0.971635406) < 1e-8          # Greene 1979 / MacKay 1983
    assert [c["q"] for c in d["convergents"]] == [2, 3, 5, 8, 13, 21, 34, 55, 89, 144, 233]
    for c in d["convergents"]:
        assert set(c) == {"p", "q", "param_n", "residue_at_critical", "point_at_critical"}
        assert len(c["point_at_critical"]) == 2
        assert c["point_at_critical"][0] == pytest.approx(math.pi)       # on Greene's symmetry line (theta = pi here)
    ref = ex.greene(ex.StandardMap(0.9), "golden", qmax=233)
    assert d["critical"] == ref.critical and d["convergents"] == json.loads(json.dumps(ref.as_dict()))["convergents"]
    for c in d["convergents"][-3:]:     # param_n: where the residue is R*; the rest: the orbit at the critical k
        theta, p = c["point_at_critical"]
        at_n = gm.symmetric_orbit(ex.StandardMap(c["param_n"]), c["p"], c["q"], guess=p)
        at_critical = gm.symmetric_orbit(ex.StandardMap(d["critical"]), c["p"], c["q"], guess=p)
        assert at_n.residue == pytest.approx(gm.CRITICAL_RESIDUE, abs=1e-9)
        assert at_critical.residue == pytest.approx(c["residue_at_critical"], abs=1e-9)
        assert at_critical.points[0, 1] == pytest.approx(p, abs=1e-12) and c["param_n"] != d["critical"]


def test_greene_standard_text_lists_the_convergents(capsys):
    code, out, _ = run_cli(["greene", "--map", "standard", "--nu", "0.6180339887498949", "--qmax", "55"], capsys)
    assert code == 0
    lines = out.strip().splitlines()
    assert lines[0].startswith("standard map, curve nu = 0.618") and "critical k = 0.97163" in lines[0]
    assert lines[1] == "p,q,k_n,residue_at_critical,point_x,point_y" and len(lines) == 2 + 8


def test_greene_section_json_gives_mu_c_of_a_noble_curve_of_the_right_island(capsys):
    code, out, _ = run_cli(["greene", "--around", "1.58,0", "--nu", "noble:6", "--mu", "0.025", "--qmax", "20",
                            "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert d["map"] == "section" and d["param"] == "mu" and d["nu"] == pytest.approx(1 / (6 + (math.sqrt(5) - 1) / 2))
    assert [(c["p"], c["q"]) for c in d["convergents"]] == [(1, 6), (1, 7), (2, 13), (3, 20)]
    points = [c["point_at_critical"] for c in d["convergents"]]
    assert all(p2 == 0.0 and 1.69 < p1 < 1.71 for p1, p2 in points)     # on p2 = 0
    # the extrapolation of four convergents: mu_c = 0.030339798 (q <= 139, benchmarks/RESULTS.md) within its error
    assert abs(d["critical"] - 0.030339798) <= d["uncertainty"] < 1e-3


def test_greene_help_names_the_qmax_defaults_the_command_uses_and_every_form_of_nu(capsys, monkeypatch):
    with pytest.raises(SystemExit):
        cli.main(["greene", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert f"[{greene_core.DEFAULT_QMAX} standard, {greene_core.SECTION_QMAX} section]" in out
    assert "noble:A,B,... = [0; A, B, ..., 1, 1, ...]" in out and "golden2" in out
    assert "the first guess of mu_c" in out
    calls = []

    def record(system, nu, **kw):
        calls.append((type(system).__name__, kw["qmax"]))
        return greene_core.GreeneResult("x", "mu", nu, 0.0, 0.0)

    monkeypatch.setattr(gm, "greene", record)
    assert run_cli(["greene", "--map", "standard", "--json"], capsys)[0] == 0
    assert run_cli(["greene", "--around", "1.58,0", "--mu", "0.025", "--nu", "noble:6", "--json"], capsys)[0] == 0
    assert calls == [("StandardMap", greene_core.DEFAULT_QMAX), ("SectionMap", greene_core.SECTION_QMAX)]


def test_greene_help_ends_with_its_example(capsys):
    with pytest.raises(SystemExit):
        cli.main(["greene", "--help"])
    out = capsys.readouterr().out
    assert out.rstrip().splitlines()[-1].strip() == "python -m explorer greene --map standard --nu golden --json"


@pytest.mark.parametrize("args,fragment", [
    (["greene", "--map", "standard", "--nu", "1.5"], "nu must be"),
    (["greene", "--map", "standard", "--qmax", "3"], "raise qmax"),
    (["greene", "--map", "section"], "--map section needs --around"),
    (["greene", "--map", "standard", "--around", "1,0"], "--around is for --map section"),
    (["greene", "--around", "9,0"], "--around (9, 0) lies outside the allowed region"),
    (["greene", "--around", "0,0", "--mu", "0.025"], "is not elliptic"),
    (["greene", "--around", "1.58,0", "--nu", "noble:6"], "--map section needs --mu, the first guess of mu_c"),
    (["greene", "--around", "1.58,0", "--nu", "noble:6", "--param", "h", "--qmax", "20"], "is not elliptic (trace 2)"),
    (["greene", "--map", "standard", "--nu", "noble:0"], "noble:A needs an integer A >= 1"),
])
def test_greene_bad_input_gives_one_line_and_status_2(args, fragment, capsys):
    code, out, err = run_cli(args, capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("explorer: error:") and fragment in err
