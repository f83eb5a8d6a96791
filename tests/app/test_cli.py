"""`python -m explorer orbit`: output formats, agreement with the library, bad input."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from explorer import model
from explorer.analysis import sections
from explorer.app import cli


def run_cli(args, capsys):
    code = cli.main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_orbit_csv_has_header_and_one_row_per_crossing(capsys):
    code, out, err = run_cli(["orbit", "--p1", "0.3", "--p2", "0.1", "--h", "2", "--crossings", "5", "--mu", "0.5"],
                             capsys)
    assert code == 0, err
    lines = out.strip().splitlines()
    assert lines[0] == "k,t,p1,p2,M,dH"
    rows = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    assert rows.shape == (5, 6)
    np.testing.assert_array_equal(rows[:, 0], np.arange(1, 6))
    lib = sections.crossings(model.FIGURE4.with_(mu=0.5), 2.0, [(0.3, 0.1)], n_crossings=5).orbit(0)
    np.testing.assert_array_equal(rows[:, 1:], lib)  # repr round-trips exactly


def test_orbit_json_matches_the_documented_shape(capsys):
    code, out, _ = run_cli(["orbit", "--p1", "0", "--p2", "0", "--crossings", "3", "--json", "--method", "split8",
                            "--dt", "0.01"], capsys)
    assert code == 0
    doc = json.loads(out)
    assert set(doc) >= {"params", "h", "method", "status", "crossings"}
    assert doc["params"] == model.FIGURE4.as_dict()
    assert doc["method"] == "split8" and doc["status"] == "done" and doc["h"] == 2.0
    t = np.array(doc["crossings"])[:, 0]
    c = math.sqrt(2 * 2.0 * 2.0)
    np.testing.assert_allclose(t, 2 * math.pi * 2.0 / c * np.arange(1, 4), rtol=1e-12)


def test_orbit_that_stops_early_reports_its_status(capsys):
    code, out, err = run_cli(["orbit", "--p1", "0.1", "--p2", "0", "--crossings", "50", "--tmax", "10",
                              "--json", "--mu", "0.5"], capsys)
    assert code == 0
    doc = json.loads(out)
    assert doc["status"] == "time budget exhausted" and 0 < len(doc["crossings"]) < 50


def test_orbit_with_a_step_too_coarse_for_its_energy_error_is_warned(capsys):
    """split4 at dt = 0.5 on Figure 4 (mu = 0.5) drifts in energy by far more than 1e-6 h: the
    crossings are printed and stderr names the energy error and the setting to refine; the
    default taylor run of the same orbit stays silent."""
    base = ["orbit", "--p1", "0.3", "--p2", "0.1", "--crossings", "20", "--mu", "0.5", "--json"]
    code, out, err = run_cli(base + ["--method", "split4", "--dt", "0.5"], capsys)
    dh = np.abs(np.array(json.loads(out)["crossings"])[:, 4]).max()
    assert code == 0 and dh > 2e-6
    assert len(err.strip().splitlines()) == 1
    assert "warning: energy error up to" in err and "--dt 0.5" in err
    code, out, err = run_cli(base, capsys)
    assert code == 0 and err == ""


@pytest.mark.parametrize("args,fragment", [
    (["--p1", "5", "--p2", "0"], "outside the allowed region"),
    (["--p1", "0", "--p2", "0", "--a1", "-1"], "a1 must be > 0"),
    (["--p1", "0", "--p2", "0", "--b", "0"], "b must be > 0"),
    (["--p1", "0", "--p2", "0", "--lam", "0"], "lam must be nonzero"),
    (["--p1", "nan", "--p2", "0"], "p1 must be finite"),
    (["--p1", "0", "--p2", "0", "--h", "inf"], "h must be finite"),
    (["--p1", "0", "--p2", "0", "--mu", "-2"], "mu must be >= 0"),
    (["--p1", "0", "--p2", "0", "--method", "euler"], "method must be one of"),
    (["--p1", "0", "--p2", "0", "--tol", "0"], "tol must be"),
    (["--p1", "0", "--p2", "0", "--method", "split4", "--dt", "-1"], "dt must be"),
    (["--p1", "0", "--p2", "0", "--crossings", "0"], "crossings must be"),
    (["--p1", "0", "--p2", "0", "--tmax", "-5"], "tmax must be"),
    (["--p1", "0", "--p2", "0", "--direction", "sideways"], "direction must be"),
    (["--p1", "abc", "--p2", "0"], "--p1"),
    (["--p2", "0"], "--p1"),
    (["--p1", "0", "--p2", "0", "--bogus", "1"], "unrecognized arguments"),
])
def test_bad_input_gives_one_line_and_status_2(args, fragment, capsys):
    code, out, err = run_cli(["orbit"] + args, capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("explorer: error:") and fragment in lines[0]
    assert "Traceback" not in err


def test_unknown_command_is_an_error(capsys):
    code, _, err = run_cli(["fly"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1


def test_python_dash_m_explorer_runs_and_exits_2_on_bad_input():
    ok = subprocess.run([sys.executable, "-m", "explorer", "orbit", "--p1", "0", "--p2", "0", "--crossings", "2"],
                        capture_output=True, text=True, timeout=300)
    assert ok.returncode == 0 and ok.stdout.startswith("k,t,p1,p2,M,dH")
    bad = subprocess.run([sys.executable, "-m", "explorer", "orbit", "--p1", "0", "--p2", "0", "--lam", "0"],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("argv, dest, value", [
    (["fixedpoint", "--guess", "-0.4,0"], "guess", "-0.4,0"),
    (["fixedpoint", "--guess", "-.4,-1e-3"], "guess", "-.4,-1e-3"),
    (["orbit", "--p1", "-1.2", "--p2", "0"], "p1", -1.2),
    (["orbit", "--p1", "-3e-1", "--p2", "0"], "p1", -0.3),
    (["orbit", "--p1", "0", "--p2", "-inf"], "p2", -math.inf),
    (["fixedpoint", "--continue", "xi", "-1e-3", "-0.5", "-0.1"], "cont", ["xi", "-1e-3", "-0.5", "-0.1"]),
])
def test_values_with_a_leading_minus_parse_without_equals(argv, dest, value):
    args = cli.build_parser().parse_args(argv)
    assert getattr(args, dest) == value


@pytest.mark.parametrize("argv, dest, value", [
    (["orbit", "--p1", "0", "--p2", "0", "--phi0", "pi/2"], "phi0", 0.5 * math.pi),
    (["orbit", "--p1", "0", "--p2", "0", "--phi0=-pi"], "phi0", -math.pi),
    (["trajectory", "--phi", "2pi"], "phi", 2 * math.pi),
    (["melnikov", "--g0", "0.5*π"], "g0", 0.5 * math.pi),
    (["melnikov", "--g0", "1.25"], "g0", 1.25),
])
def test_an_angle_option_takes_a_number_or_a_multiple_of_pi(argv, dest, value):
    assert getattr(cli.build_parser().parse_args(argv), dest) == value


@pytest.mark.parametrize("text", ["pi/0", "two pi", "pix", "nan"])
def test_a_bad_angle_is_refused_in_one_line_naming_the_option(text, capsys):
    code, _, err = run_cli(["orbit", "--p1", "0", "--p2", "0", f"--phi0={text}"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--phi0" in err and "Traceback" not in err


def test_an_option_is_still_an_option_after_an_option_missing_its_value(capsys):
    assert cli.main(["orbit", "--p1", "--p2", "0"]) == 2
    assert "--p1: expected one argument" in capsys.readouterr().err


def test_fixedpoint_with_a_negative_guess_without_equals_finds_the_fixed_point(capsys):
    """The command the issue found broken: solution I at mu = 0.5 lies at p1 < 0 on p2 = 0."""
    assert cli.main(["fixedpoint", "--guess", "-0.4,0", "--mu", "0.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    p1, p2 = out["p1"], out["p2"]
    assert p1 < 0 and abs(p2) < 1e-10


@pytest.mark.parametrize("command", sorted(cli.EXAMPLES))
def test_every_help_ends_with_an_example_that_parses(command, capsys):
    with pytest.raises(SystemExit) as exc:
        cli.build_parser().parse_args([command, "--help"])
    assert exc.value.code == 0
    lines = capsys.readouterr().out.rstrip().splitlines()
    assert lines[-2] == "example:"
    example = lines[-1].split()
    assert example[:4] == ["python", "-m", "explorer", command]
    cli.build_parser().parse_args(example[3:])  # raises UsageError if the example is wrong


def test_every_command_has_an_example():
    sub = next(a for a in cli.build_parser()._actions if isinstance(a, __import__("argparse")._SubParsersAction))
    assert set(sub.choices) == set(cli.EXAMPLES)


def test_the_registry_lists_every_command_module_once_with_its_page():
    """One module per command (app/commands/<name>.py, serve beside its web page): each is in the
    registry, has its declaration (or parser), its run and its example, a page docs/commands/<name>.md in the
    toctree, and the parser lists the commands in the registry's order."""
    from pathlib import Path

    from explorer.app import commands
    from explorer.app.commands import registry

    root = Path(commands.__file__).parent
    modules = {f"explorer.app.commands.{p.stem}" for p in root.glob("*.py")} - {
        "explorer.app.commands.__init__", "explorer.app.commands.options", "explorer.app.commands.registry"}
    assert modules <= set(registry.MODULES.values())
    assert len(set(registry.MODULES.values())) == len(registry.MODULES)
    docs = Path(__file__).resolve().parents[2] / "docs"
    toctree = (docs / "index.md").read_text().split()
    for name in registry.COMMANDS:
        mod = registry.module(name)
        assert callable(mod.run) and registry.example(name).split()[3] == name
        assert mod.COMMAND.name == name and mod.COMMAND.help and mod.COMMAND.description
        assert (docs / "commands" / f"{name}.md").is_file() and f"commands/{name}" in toctree, name
    sub = next(a for a in cli.build_parser()._actions if isinstance(a, __import__("argparse")._SubParsersAction))
    assert tuple(sub.choices) == registry.COMMANDS


@pytest.mark.parametrize("command", ["lyapunov", "trajectory"])
@pytest.mark.parametrize("spelling", ["--time", "-T"])
def test_the_time_an_orbit_runs_has_one_name_tmax_and_other_spellings_are_refused(command, spelling, capsys):
    """One name per thing: the time an orbit runs is --tmax (the API's tmax=, orbit's --tmax);
    any other spelling is an unknown option: exit 2, a usage line, no traceback."""
    start = ["--p1", "-0.2", "--p2", "0.1"] if command == "lyapunov" else []
    code, out, err = run_cli([command, *start, spelling, "5"], capsys)
    assert code == 2 and f"unrecognized arguments: {spelling} 5" in err and "Traceback" not in err, err
    assert cli.build_parser().parse_args([command, *start, "--tmax", "7"]).tmax == 7.0


def test_sweep_backend_dask_without_distributed_says_which_extra_to_install(monkeypatch, tmp_path, capsys):
    """A plain `pip install .` has no dask: `sweep --backend dask` then exits 2 with one line that
    names the extra (pyproject's `explorer[dask]`), not a traceback."""
    monkeypatch.setitem(sys.modules, "dask.distributed", None)           # (an import of it fails)
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["sweep", "--backend", "dask", "--jobs", "2"], capsys)
    assert code == 2 and "explorer[dask]" in err and "Traceback" not in err, err
    assert not [f for f in tmp_path.rglob("*") if f.is_file()]           # and no result half-written
