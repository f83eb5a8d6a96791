"""Bad input to the command line and to scene files: one line `explorer: error: ...` on stderr,
exit status 2, no traceback, nothing on stdout.

Kinds already covered elsewhere (not repeated here): test_cli.py (orbit: point outside the
region, a1 < 0, b = 0, lam = 0, p1 NaN, h inf, mu < 0, unknown method, tol 0, dt < 0,
crossings 0, tmax < 0, bad direction, non-number, missing --p1, unknown option; unknown
command), test_sweep.py (unknown scene, --jobs 0, --scheduler without dask, unknown backend,
corrupt output file), test_lyapunov.py (time < 0, outside, method, lam 0), test_fixedpoints.py
(guess outside, guess not numbers, unknown continuation parameter, step sign, b < 0),
test_explore.py (no display), test_melnikov.py, test_trajectory.py, and test_scene.py (every
bad scene key through parse_scene, not through the command line).  This file adds the rest,
through cli.main and (a handful) through `python -m explorer` in a subprocess; every case is a
distinct kind of mistake.  Some cases were bugs when the file was written (fixed since).
"""
import subprocess
import sys

import pytest

from explorer.app import cli

P0 = ["--p1", "0", "--p2", "0"]

# (id, argv, fragment the message must contain)
CLI_CASES = [
    # ---- orbit
    ("orbit_tol_below_min", ["orbit"] + P0 + ["--tol", "1e-20"], "tol must be in [1e-16, 0.01]"),
    ("orbit_tol_above_max", ["orbit"] + P0 + ["--tol", "0.5"], "tol must be in [1e-16, 0.01]"),
    ("orbit_dt_nan", ["orbit"] + P0 + ["--method", "split8", "--dt", "nan"], "dt must be finite"),
    ("orbit_dt_zero", ["orbit"] + P0 + ["--method", "split8", "--dt", "0"], "dt must be"),
    ("orbit_crossings_not_int", ["orbit"] + P0 + ["--crossings", "abc"], "--crossings"),
    ("orbit_option_without_value", ["orbit"] + P0 + ["--crossings"], "expected one argument"),
    ("orbit_max_steps_zero", ["orbit"] + P0 + ["--max-steps", "0"], "max_steps must be an integer >= 1"),
    ("orbit_max_steps_float", ["orbit"] + P0 + ["--max-steps", "1.5"], "--max-steps"),
    ("orbit_a2_zero", ["orbit"] + P0 + ["--a2", "0"], "a2 must be > 0"),
    ("orbit_eta_nan", ["orbit"] + P0 + ["--eta", "nan"], "eta must be finite"),
    ("orbit_chi_inf", ["orbit"] + P0 + ["--chi", "inf"], "chi must be finite"),
    ("orbit_tmax_nan", ["orbit"] + P0 + ["--tmax", "nan"], "tmax must be finite"),
    ("orbit_tmax_inf", ["orbit"] + P0 + ["--tmax", "inf"], "tmax must be finite"),
    ("orbit_empty_region", ["orbit"] + P0 + ["--h", "-5"], "the region is empty"),
    ("orbit_direction_empty", ["orbit"] + P0 + ["--direction", ""], "direction must be one of"),
    ("orbit_phi0_nan", ["orbit"] + P0 + ["--phi0", "nan"], "phi0"),
    # ---- lyapunov
    ("lyapunov_history_negative", ["lyapunov"] + P0 + ["--history", "-1"], "history must be an integer >= 0"),
    ("lyapunov_history_float", ["lyapunov"] + P0 + ["--history", "1.5"], "--history"),
    ("lyapunov_tol_above_max", ["lyapunov"] + P0 + ["--tol", "1"], "tol must be"),
    ("lyapunov_dt_zero", ["lyapunov"] + P0 + ["--method", "split4", "--dt", "0"], "dt must be"),
    ("lyapunov_time_nan", ["lyapunov"] + P0 + ["--time", "nan"], "time must be finite"),
    ("lyapunov_time_inf", ["lyapunov"] + P0 + ["--time", "inf"], "time must be finite"),
    ("lyapunov_p2_nan", ["lyapunov", "--p1", "0", "--p2", "nan"], "p2 must be finite"),
    ("lyapunov_mu_negative", ["lyapunov"] + P0 + ["--mu", "-1"], "mu must be >= 0"),
    ("lyapunov_empty_region", ["lyapunov"] + P0 + ["--h", "-3"], "the region is empty"),
    # ---- fixedpoint
    ("fixedpoint_guess_one_number", ["fixedpoint", "--guess", "1"], "--guess must be two numbers"),
    ("fixedpoint_guess_nan", ["fixedpoint", "--guess", "nan,0"], "--guess must be finite"),
    ("fixedpoint_continue_not_numbers", ["fixedpoint", "--continue", "mu", "a", "b", "c"], "--continue needs"),
    ("fixedpoint_continue_zero_step", ["fixedpoint", "--continue", "mu", "0", "1", "0"], "--continue needs"),
    ("fixedpoint_continue_infinite", ["fixedpoint", "--continue", "mu", "0", "inf", "0.1"], "--continue needs"),
    ("fixedpoint_continue_too_few", ["fixedpoint", "--continue", "mu", "0"], "expected 4 arguments"),
    ("fixedpoint_h_nan", ["fixedpoint", "--h", "nan"], "h must be finite"),
    ("fixedpoint_empty_region", ["fixedpoint", "--h", "-5"], "the region is empty"),
    ("fixedpoint_lam_zero", ["fixedpoint", "--lam", "0"], "lam must be nonzero"),
    ("fixedpoint_tol_zero", ["fixedpoint", "--tol", "0"], "tol must be"),
    ("fixedpoint_tol_nan", ["fixedpoint", "--tol", "nan"], "tol must be"),
    ("fixedpoint_tol_above_max", ["fixedpoint", "--tol", "0.5"], "tol must be"),
    # ---- sweep
    ("sweep_jobs_negative", ["sweep", "figure4", "--jobs", "-1"], "--jobs must be >= 1"),
    ("sweep_jobs_not_int", ["sweep", "figure4", "--jobs", "abc"], "--jobs"),
    ("sweep_missing_file", ["sweep", "/nonexistent/dir/scene.toml"], "/nonexistent/dir/scene.toml"),
    # ---- melnikov (test_melnikov.py has the model conditions)
    ("melnikov_mus_negative", ["melnikov", "--splitting", "--mus", "-1"], "--mus must be finite and > 0"),
    ("melnikov_g0_nan", ["melnikov", "--splitting", "--g0", "nan"], "g0 must be finite"),
    ("melnikov_h_nan", ["melnikov", "--h", "nan"], "h must be finite"),
    # ---- trajectory (test_trajectory.py has the parameters)
    ("trajectory_glyphs_zero", ["trajectory", "--no-figure", "--glyphs", "0"], "glyphs must be >= 1"),
    ("trajectory_tol_nan", ["trajectory", "--no-figure", "--tol", "nan"], "tol must be"),
    ("trajectory_time_inf", ["trajectory", "--no-figure", "--time", "inf"], "must be finite"),
    # ---- top level
    ("global_unknown_option", ["--bogus"], "unrecognized arguments"),
]


def assert_one_line_error(code, out, err, fragment):
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("explorer: error:"), err
    assert fragment in lines[0], (fragment, lines[0])
    assert out == "", out


def run_main(argv, capsys):
    try:
        code = cli.main(argv)
    except SystemExit as exc:      # argparse must not exit on its own
        code = ("SystemExit", exc.code)
    except Exception as exc:       # noqa: BLE001 - a traceback is a failure of this test
        code = ("exception", repr(exc))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("argv,fragment", [c[1:] for c in CLI_CASES], ids=[c[0] for c in CLI_CASES])
def test_bad_command_line_gives_one_line_and_status_2(argv, fragment, capsys):
    """Formerly buggy cases: orbit --phi0 nan reports the start point, not phi0
    (cli.cmd_orbit does not check phi0); fixedpoint --tol 0
    or nan raise a ValueError traceback and --tol 0.5 is accepted (cli.cmd_fixedpoint and
    fixedpoints.SectionMap do not validate tol: kernels.taylor.order_for_tolerance gets it)."""
    code, out, err = run_main(argv, capsys)
    assert_one_line_error(code, out, err, fragment)


# ---------------------------------------------------------------- scene files through `sweep`
GOOD = 'name = "s"\n[seeds]\nn = 4\n[integration]\ncrossings = 2\n'

SCENE_CASES = [
    # (id, file content (str or bytes), fragment)
    ("scene_toml_syntax", 'name = "s"\n[model\nmu = 1\n', "TOML syntax error"),
    ("scene_empty_file", "", "'name' is required"),
    ("scene_not_utf8", b"\xff\xfe\x00 name", "cannot read"),
    ("scene_unknown_table", GOOD + "[modle]\nmu = 1.0\n", "modle"),
    ("scene_unknown_key", GOOD.replace("crossings = 2", "crossings = 2\ntolerance = 1e-9"), "integration.tolerance"),
    ("scene_wrong_type", GOOD + "[model]\nmu = 'heavy'\n", "model.mu"),
    ("scene_value_out_of_range", GOOD.replace("crossings = 2", "crossings = 2\ntol = 0.5"), "integration.tol"),
    ("scene_bad_parameter_value", GOOD + "[model]\nlam = 0\n", "model.lam"),
    ("scene_empty_region", GOOD + "[energy]\nh = -1.0\n", "energy.h"),
    ("scene_sweep_empties_a_panel", GOOD + "[sweep]\nparameter = 'h'\nvalues = [2.0, -1.0]\n", "sweep.values[1]"),
    ("scene_duplicate_key", 'name = "s"\nname = "t"\n', "TOML syntax error"),
    ("scene_bad_name", 'name = "a b"\n', "'name'"),
]


@pytest.mark.parametrize("content,fragment", [c[1:] for c in SCENE_CASES], ids=[c[0] for c in SCENE_CASES])
def test_bad_scene_file_gives_one_line_and_status_2(content, fragment, tmp_path, capsys):
    path = tmp_path / "bad.toml"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    code, out, err = run_main(["sweep", str(path), "--out", str(tmp_path / "o.h5"), "--no-figure", "--quiet"],
                              capsys)
    assert_one_line_error(code, out, err, fragment)
    assert not (tmp_path / "o.h5").exists()


def test_scene_path_is_a_directory(tmp_path, capsys):
    code, out, err = run_main(["sweep", str(tmp_path), "--no-figure", "--quiet"], capsys)
    assert_one_line_error(code, out, err, str(tmp_path))


def test_output_path_is_a_directory(tmp_path, capsys):
    (tmp_path / "s.toml").write_text(GOOD)
    (tmp_path / "d.h5").mkdir()
    code, out, err = run_main(["sweep", str(tmp_path / "s.toml"), "--out", str(tmp_path / "d.h5"), "--no-figure",
                               "--quiet"], capsys)
    assert_one_line_error(code, out, err, "is a directory")


@pytest.mark.parametrize("where", ["out", "figure"])
def test_output_under_a_regular_file_is_refused(where, tmp_path, capsys):
    """Formerly a bug: --out file.txt/x.h5 or --figure file.txt/fig (a parent that is a file) ends in
    a FileExistsError traceback (runner.run_sweep: out.parent.mkdir; the figure directory
    likewise) instead of one line."""
    (tmp_path / "s.toml").write_text(GOOD)
    (tmp_path / "file.txt").write_text("x")
    argv = ["sweep", str(tmp_path / "s.toml"), "--quiet"]
    if where == "out":
        argv += ["--out", str(tmp_path / "file.txt" / "x.h5"), "--no-figure"]
    else:
        argv += ["--out", str(tmp_path / "o.h5"), "--figure", str(tmp_path / "file.txt" / "fig")]
    code, out, err = run_main(argv, capsys)
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, (code, err)
    assert "file.txt" in err


def test_unwritable_output_location_is_refused(tmp_path, capsys):
    """An output file that cannot be created (here under /proc, which refuses new
    files even to root) ends in an h5py FileNotFoundError traceback from the store commit
    (store.py, called by runner.run_sweep) after the panel was computed; it should be one line
    naming the path (ideally checked before computing)."""
    import os
    if not os.path.isdir("/proc/self"):
        pytest.skip("needs /proc")
    (tmp_path / "s.toml").write_text(GOOD)
    code, out, err = run_main(["sweep", str(tmp_path / "s.toml"), "--out", "/proc/explorer-test.h5", "--no-figure",
                               "--quiet"], capsys)
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, (code, err)
    assert "/proc/explorer-test.h5" in err


# ---------------------------------------------------------------- a handful through `python -m explorer`
@pytest.mark.parametrize("argv,fragment", [
    (["orbit", "--p1", "0", "--p2", "0", "--tol", "1e-20"], "tol must be"),
    (["lyapunov", "--p1", "0", "--p2", "0", "--time", "nan"], "time must be finite"),
    (["fixedpoint", "--guess", "1"], "--guess must be two numbers"),
    (["sweep", "figure4", "--jobs", "abc"], "--jobs"),
    (["melnikov", "--h", "nan"], "h must be finite"),
    (["orbit", "--p1", "0", "--p2", "0", "--h", "1e308"], ""),
])
def test_python_dash_m_explorer_bad_input(argv, fragment):
    """Formerly a bug: orbit --h 1e308 (M^2 overflows) prints numpy's RuntimeWarning (two lines per
    warning, from model.section_M2 / model.energy called by sections.section_crossings) before
    the error line; under pytest's capsys the warnings are captured separately, hence the
    subprocess."""
    p = subprocess.run([sys.executable, "-m", "explorer"] + argv, capture_output=True, text=True, timeout=300)
    assert_one_line_error(p.returncode, p.stdout, p.stderr, fragment)


def test_python_dash_m_explorer_bad_scene_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD + "[integration]\nmethod = 'rk4'\n")
    p = subprocess.run([sys.executable, "-m", "explorer", "sweep", str(path), "--out", str(tmp_path / "o.h5")],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert p.stderr.startswith("explorer: error:")


def test_the_cases_are_distinct_and_number_at_least_30():
    """Every id is a different kind of mistake, and this file alone has more than 30 of them
    (plus the directory / unwritable-output cases and the subprocess runs)."""
    ids = [c[0] for c in CLI_CASES] + [c[0] for c in SCENE_CASES]
    assert len(ids) == len(set(ids))
    assert len(ids) >= 30
