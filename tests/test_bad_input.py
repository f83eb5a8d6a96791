"""Bad input, everywhere a user can type (issue 20 item 4): every command's options and every scene
key.  Each case ends with one line ``explorer: error: ...`` on stderr naming the option or key,
exit status 2, no traceback, nothing on stdout, nothing written (the working directory is left
as it was) and an existing output file unchanged, byte for byte.  The rule and the limits are in
docs/bad_input.md; the limits are named once in :mod:`explorer.model.validation`.

The tables below are the list of cases tried:

* ``CLI_TABLE``: per command and option, non-finite numbers (nan, inf, -inf), wrong types (a word
  for a number, a float for an integer), empty values, out-of-range values (zero and negative
  counts, values past a named limit, counts whose arrays would not fit in memory);
* ``SCENE_TABLE``: per scene key, non-finite numbers, wrong types (string, boolean, list, table,
  float for an integer), out-of-range and huge values, empty values and unknown keys (with a
  "did you mean" when a key is close to an allowed one);
* ``OUTPUT_TABLE``: places a command writes: empty, unwritable (under /proc, which refuses new
  files even to root), a directory for a file or a file for a directory, a path under a file, a
  read-only existing file (old file intact, byte for byte).

Covered elsewhere (not repeated): two processes on one store (store locking, tests/io/test_store.py),
kinds in tests/app/test_cli.py, tests/app/test_cli_periodic.py, tests/analysis/test_sweep.py,
tests/io/test_scene.py (the same keys through parse_scene).

Accepted on purpose (not bad input, documented): budgets with no memory cost (``--tmax``,
``--max-steps``, ``integration.tmax``, ``max_steps``, a huge ``--tmax``), any finite angle
(``--phi0``, ``--phi``, ``--g0``), ``trajectory --glyphs 10**12`` (at most one glyph per sample is
drawn), ``orbit --crossings 10**12`` (streamed in blocks of bounded
memory until interrupted; with ``--out`` the disk it may need is checked first).

Most cases run in-process through :func:`explorer.app.cli.main`; a few run ``python -m explorer``
in a subprocess to prove the real exit path.
"""
import os
import re
import subprocess
import sys

import pytest

from explorer import model
from explorer.app import cli
from explorer.model import validation

P0 = ["--p1", "0", "--p2", "0"]
BIG = str(10**12)

#: a valid, cheap invocation of each command (the bad option is appended; argparse keeps the last)
BASE = {
    "orbit": ["orbit"] + P0 + ["-K", "2"],
    "lyapunov": ["lyapunov"] + P0 + ["--tmax", "1"],
    "fixedpoint": ["fixedpoint"],
    "periodic": ["periodic", "-K", "1", "--guess", "0,0"],
    "rotation": ["rotation", "--from", "0.1,0", "--to", "0.2,0", "--n", "2", "--iterates", "10"],
    "explore": ["explore", "--port", "0"],  # never starts either (explore is serve that opens a browser)
    "melnikov": ["melnikov"],
    "trajectory": ["trajectory", "--no-figure", "--tmax", "1", "--samples", "10"],
    "sweep": ["sweep", "{scene}", "--no-figure", "--quiet", "--out", "o.h5"],
    "figures": ["figures", "--only", "figure4"],
    "manifold": ["manifold", "--arclength", "0.5"],
    "greene": ["greene", "--map", "standard", "--qmax", "13"],
    "serve": ["serve", "--port", "0"],     # never starts: the server is replaced (_no_server below)
}
MODEL_OPTIONS = tuple(f"--{name}" for name in model.PARAM_NAMES)
#: options taking a real number, per command (the model parameters are added below)
REAL_OPTIONS = {
    "orbit": ("--p1", "--p2", "--h", "--tol", "--dt", "--tmax", "--phi0"),
    "lyapunov": ("--p1", "--p2", "--h", "--tmax", "--tol", "--dt"),
    "fixedpoint": ("--h", "--tol"),
    "periodic": ("--h", "--tol"),
    "rotation": ("--h", "--tol"),
    "explore": ("--h", "--tol", "--dt", "--megno-time"),
    "melnikov": ("--h", "--g0"),
    "trajectory": ("--p1", "--p2", "--M", "--phi", "--tmax", "--tol"),
    "manifold": ("--h", "--tol", "--arclength", "--max-time"),
    "greene": ("--h", "--tol", "--k"),
    "serve": ("--h", "--tol", "--dt", "--megno-time"),
}
#: options taking an integer: (option, values out of range)
INT_OPTIONS = {
    "orbit": (("--crossings", ("0", "-1")), ("--max-steps", ("0",)), ("--block", ("0", "-1"))),
    "lyapunov": (("--history", ("-1", BIG)),),
    "periodic": (("--period", ("0", BIG)), ("--grid", ("1", "-1", BIG)), ("--max-guesses", ("0",))),
    "rotation": (("--n", ("1", BIG)), ("--iterates", ("9", BIG))),
    "explore": (("--panel", ("-1", "1")), ("--port", ("-1", "65536")), ("--crossings", ("0", BIG)),
                ("--megno-resolution", ("0", "8", "100", "1024", BIG))),
    "trajectory": (("--samples", ("1", BIG)), ("--glyphs", ("0", "-1"))),
    "sweep": (("--jobs", ("0", "-1", BIG)),),
    "manifold": (("--period", ("0", BIG)), ("--index", ("-1", BIG)), ("--max-points", ("0", BIG))),
    "greene": (("--qmax", ("1", "-1", BIG)),),
    "serve": (("--panel", ("-1", "1")), ("--port", ("-1", "65536")), ("--crossings", ("0", BIG)),
              ("--megno-resolution", ("0", "8", "100", "1024", BIG))),
}
#: options taking a point p1,p2
PAIR_OPTIONS = {"manifold": ("--guess",), "fixedpoint": ("--guess",), "periodic": ("--guess",),
                "rotation": ("--from", "--to", "--center"), "greene": ("--around",)}


def _cases():
    rows = []
    for cmd, opts in REAL_OPTIONS.items():
        for opt in opts + MODEL_OPTIONS:
            values = ["nan", "inf", "-inf", "abc", ""]
            if opt in MODEL_OPTIONS or opt in ("--h", "--p1", "--p2", "--M"):
                values.append("1e300")          # past MAX_MAGNITUDE (or outside the region)
            if opt in ("--tol",):
                values += ["0", "1", "-1e-12"]
            if opt in ("--dt", "--tmax", "--arclength", "--max-time", "--megno-time"):
                values += ["0", "-1"]
            if opt == "--megno-time":
                values.append(BIG)
            for v in values:
                rows.append((f"{cmd}{opt}={v or 'empty'}", BASE[cmd] + [f"{opt}={v}"], opt))
    for cmd, opts in INT_OPTIONS.items():
        for opt, out_of_range in opts:
            for v in ("1.5", "abc", "", "nan") + out_of_range:
                rows.append((f"{cmd}{opt}={v or 'empty'}", BASE[cmd] + [f"{opt}={v}"], opt))
    for cmd, opts in PAIR_OPTIONS.items():
        for opt in opts:
            for v in ("", "1", "a,b", "nan,0", "0,inf", "1,2,3", "1e300,0"):
                rows.append((f"{cmd}{opt}={v or 'empty'}", BASE[cmd] + [f"{opt}={v}"], opt))
    for cmd in ("fixedpoint", "periodic"):
        for label, cont in (("nan", ["mu", "nan", "1", "0.1"]), ("inf", ["mu", "0", "inf", "0.1"]),
                            ("zero_step", ["mu", "0", "1", "0"]), ("wrong_sign", ["mu", "0", "1", "-0.1"]),
                            ("too_many_steps", ["mu", "0", "1e300", "1e-300"]), ("words", ["mu", "a", "b", "c"]),
                            ("unknown_parameter", ["bogus", "0", "1", "0.1"]), ("empty", ["", "", "", ""])):
            rows.append((f"{cmd}--continue={label}", BASE[cmd] + ["--continue"] + cont, "--continue"))
    rows += [
        ("orbit--block=huge_with_huge_crossings", BASE["orbit"] + [f"--crossings={BIG}", f"--block={BIG}"], "--block"),
        ("orbit--method=empty", BASE["orbit"] + ["--method="], "method"),
        ("orbit--method=rk4", BASE["orbit"] + ["--method=rk4"], "method"),
        ("orbit--direction=empty", BASE["orbit"] + ["--direction="], "direction"),
        ("orbit--direction=2", BASE["orbit"] + ["--direction=2"], "direction"),
        ("lyapunov--method=empty", BASE["lyapunov"] + ["--method="], "method"),
        ("explore--method=bogus", BASE["explore"] + ["--method=bogus"], "method"),
        ("melnikov--mus=empty", BASE["melnikov"] + ["--mus="], "--mus"),
        ("melnikov--mus=nan", BASE["melnikov"] + ["--mus=nan"], "--mus"),
        ("melnikov--mus=words", BASE["melnikov"] + ["--mus=a,b"], "--mus"),
        ("melnikov--mus=negative", BASE["melnikov"] + ["--splitting", "--mus=-1"], "--mus"),
        ("sweep--backend=empty", BASE["sweep"] + ["--backend="], "--backend"),
        ("sweep--scheduler=empty", BASE["sweep"] + ["--backend=dask", "--scheduler="], "--scheduler"),
        ("sweep--scheduler_without_dask", BASE["sweep"] + ["--scheduler=x:1"], "--scheduler"),
        ("sweep--unknown_scene", ["sweep", "nosuchscene"], "scene"),
        ("sweep--system=empty", BASE["sweep"] + ["--system="], "--system"),
        ("sweep--system=no_such_module", BASE["sweep"] + ["--system=no_such_module_xyz:hh"], "--system"),
        ("serve--system=empty", BASE["serve"] + ["--system="], "--system"),
        ("serve--system=no_such_module", BASE["serve"] + ["--system=no_such_module_xyz:hh"], "--system"),
        ("explore--system=empty", BASE["explore"] + ["--system="], "--system"),
        ("figures--only=empty", ["figures", "--only="], "figure"),
        ("figures--only=unknown", ["figures", "--only=figure44"], "figure"),
        ("explore--unknown_scene", ["explore", "nosuchscene"], "scene"),
        ("explore--token=empty", BASE["explore"] + ["--token="], "--token"),
        ("explore--token=space", BASE["explore"] + ["--token=a b"], "--token"),
        ("explore--export-dir=missing", BASE["explore"] + ["--export-dir=/nonexistent/explorer"], "--export-dir"),
        ("explore--host=empty", BASE["explore"] + ["--host="], "--host"),
        ("explore--no-browser=value", BASE["explore"] + ["--no-browser=1"], "--no-browser"),
        ("greene--map=empty", BASE["greene"] + ["--map="], "--map"),
        ("greene--map=henon", BASE["greene"] + ["--map=henon"], "--map"),
        ("greene--nu=2", BASE["greene"] + ["--nu=2"], "nu"),
        ("greene--nu=word", BASE["greene"] + ["--nu=silverish"], "nu"),
        ("greene--nu=empty", BASE["greene"] + ["--nu="], "nu"),
        ("greene--param=bogus", BASE["greene"] + ["--param=bogus"], "--param"),
        ("greene--param=empty", BASE["greene"] + ["--param="], "--param"),
        ("greene--around_with_standard", BASE["greene"] + ["--around=1.5,0"], "--around"),
        ("serve--unknown_scene", ["serve", "nosuchscene"], "scene"),
        ("serve--method=bogus", BASE["serve"] + ["--method=bogus"], "method"),
        ("serve--token=empty", BASE["serve"] + ["--token="], "--token"),
        ("serve--token=space", BASE["serve"] + ["--token=a b"], "--token"),
        ("serve--export-dir=missing", BASE["serve"] + ["--export-dir=/nonexistent/explorer"], "--export-dir"),
        ("serve--host=empty", BASE["serve"] + ["--host="], "--host"),
        ("global_unknown_option", ["--bogus"], "--bogus"),
        ("global_unknown_command", ["orbitt"], "orbitt"),
        ("orbit_unknown_option", BASE["orbit"] + ["--tolerance=1e-9"], "--tolerance"),
        ("orbit_option_without_value", BASE["orbit"] + ["--crossings"], "--crossings"),
    ]
    return rows


CLI_TABLE = _cases()


def _tokens(message: str) -> list:
    """The words of a message, '_' read as '-' (max_steps names --max-steps)."""
    return re.findall(r"[A-Za-z0-9][\w-]*", message.replace("_", "-"))


@pytest.fixture(autouse=True)
def _no_server(monkeypatch):
    """`serve` must refuse every bad value before it starts a server: here a server that would
    start raises instead, so a value that slips through fails its case rather than hanging."""
    from explorer.app.serve import server

    def started(*args, **kwargs):
        raise RuntimeError("the server would have started")

    monkeypatch.setattr(server, "run", started)


@pytest.fixture(scope="module")
def _one_parser():
    """The parser of :func:`explorer.app.cli.build_parser`, built once for the module's ~1,600
    cases (building it took 10 ms, about half of the module's CPU time).  Parsing does not change
    a parser (argparse keeps the values in a new namespace; no option's default depends on the
    working directory or the environment), so each case parses with what ``cli.main`` builds."""
    return cli.build_parser()


@pytest.fixture(autouse=True)
def _parser_built_once(_one_parser, monkeypatch):
    monkeypatch.setattr(cli, "build_parser", lambda: _one_parser)


def run_main(argv, capsys):
    try:
        code = cli.main(argv)
    except SystemExit as exc:      # argparse must not exit on its own
        code = ("SystemExit", exc.code)
    except Exception as exc:       # noqa: BLE001 - a traceback is a failure of this test
        code = ("exception", repr(exc))
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code, out, err, name):
    """Exit 2, one line ``explorer: error: ...`` naming ``name`` (an option or a dotted scene key,
    compared word by word), no traceback, nothing on stdout."""
    assert code == 2, (code, err, out[:300])
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("explorer: error:"), err
    words = _tokens(lines[0])
    for part in _tokens(name):
        assert part in words, (name, lines[0])
    assert out == "", out


def _listing(root):
    return sorted(os.path.relpath(os.path.join(d, f), root) for d, _dirs, files in os.walk(root) for f in files)


GOOD_SCENE = 'name = "s"\n[seeds]\nn = 4\n[integration]\ncrossings = 2\n'


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """An empty working directory holding one good scene; the test checks nothing else appears."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "good.toml").write_text(GOOD_SCENE)
    return tmp_path


#: allowed values whose integration overflows: the monodromy of the orbit at (0, 0) is not finite
#: for |lam| >= 1e4 (trace 1e127 at lam = 100); Newton's linear algebra raised LinAlgError there
#: before the section map's Jacobian was checked (analysis/periodic.py, _not_finite)
OVERFLOWS = [
    pytest.param(BASE["periodic"] + ["--lam=1e4"], "lam", id="periodic--lam=1e4_monodromy_overflows"),
    pytest.param(BASE["fixedpoint"] + ["--lam=1e4"], "lam", id="fixedpoint--lam=1e4_monodromy_overflows"),
]


@pytest.mark.parametrize("argv,name", [c[1:] for c in CLI_TABLE] + OVERFLOWS,
                         ids=[c[0] for c in CLI_TABLE] + [p.id for p in OVERFLOWS])
def test_bad_option_gives_one_line_naming_it_and_status_2_and_writes_nothing(argv, name, workdir, capsys):
    """Formerly bugs (all mended by this table's commit): tracebacks for orbit --out '', lyapunov
    --history 10**12, periodic --period 10**12, rotation --n 10**12, trajectory --samples 10**12
    (MemoryError), --continue mu 0 1e300 1e-300 (OverflowError), periodic --lam 1e300
    (LinAlgError), trajectory --p1/--lam/--mu 1e300 (LinAlgError in the drift fit); runs that
    ended with status 0 for --dt nan with the taylor method, --grid/--max-guesses out of range
    without --search, melnikov --mus/--g0 nan without --splitting, rotation --center '',
    sweep --jobs 10**12 or --scheduler '', and model parameters of 1e300 (non-finite states,
    numpy warnings on stderr)."""
    argv = [a.replace("{scene}", "good.toml") for a in argv]
    before = _listing(workdir)
    code, out, err = run_main(argv, capsys)
    assert_one_line_error(code, out, err, name)
    assert _listing(workdir) == before


# ---------------------------------------------------------------- scene keys, through `sweep`
REAL = ("nan", "inf", "-inf", "'abc'", "true", "[1.0]", "{}")
INT = ("2.5", "nan", "'3'", "true", "[1]")
WORD = ("1", "''", "'bogus'", "[]", "true")
BOOL = ("1", "'yes'", "[]")
LIST = ("1", "'a'", "[]")
#: key -> bad values (TOML literals) beyond its kind's; keys of one kind share its list
SCENE_KEYS = {
    "name": ("''", "'a b'", "'.hidden'", "1", f"'{'x' * 200}'"),
    "description": ("1", "[]"),
    "energy.h": REAL + ("1e300", "-1e300"),
    "sweep.parameter": WORD,
    "sweep.values": LIST + ("[nan]", "[1.0, 1.0]", "['a']"),
    "seeds.kind": WORD,
    "seeds.n": INT + ("0", "-1", BIG),
    "seeds.margin": REAL + ("0", "1.5"),
    "seeds.seed": INT + ("-1",),
    "seeds.lines": LIST + ("[[0, 0, 1]]", "[[0, 0, 2, 0]]", "[[nan, 0, 1, 0]]"),
    "seeds.points": LIST + ("[[0]]", "[[nan, 0]]", "[['a', 0]]"),
    "integration.method": WORD,
    "integration.tol": REAL + ("0", "0.5", "1e-20"),
    "integration.dt": REAL + ("0", "-0.1"),
    "integration.crossings": INT + ("0", "-1", BIG),
    "integration.tmax": REAL + ("0", "-1"),
    "integration.max_steps": INT + ("0",),
    "integration.phi0": REAL,
    "integration.direction": INT + ("2",),
    "compute.sections": BOOL + ("false",),       # false with nothing else to compute
    "compute.lyapunov": BOOL,
    "compute.separatrices": BOOL,
    "lyapunov.time": REAL + ("0", "-1"),
    "lyapunov.method": WORD,
    "lyapunov.tol": REAL + ("0", "0.5"),
    "lyapunov.dt": REAL + ("0",),
    "lyapunov.threshold": REAL + ("2", "1"),
    "lyapunov.indicators": LIST + ("['lyap']",),
    "lyapunov.early_stop": BOOL,
    "lyapunov.exact": BOOL,
    "lyapunov.early_sali": REAL + ("-1", "2"),
    "lyapunov.early_megno": REAL + ("2",),
    "lyapunov.early_time": REAL + ("-1",),
    "lyapunov.map_resolution": INT + ("-1", BIG),
    "lyapunov.map_indicator": WORD,
    "lyapunov.center": LIST + ("[0]", "[0, 0, 0]", "[nan, 0]", "['a', 0]"),
    "lyapunov.diffusion_iterates": INT + ("9", BIG),
    "figure.layout": WORD,
    "figure.columns": INT + ("0",),
    "figure.share_scale": BOOL,
    "figure.own_scale": ("1", "'a'", "[-1]", "[0, 0]", "[5]"),
    "figure.marker_size": REAL + ("0",),
    "figure.dpi": INT + ("0", BIG),
    "manifolds.draw": BOOL,
    "manifolds.arclength": REAL + ("0", "-1", "1e4"),
    "manifolds.guess": LIST + ("[0]", "[0, 0, 0]", "[nan, 0]", "['a', 0]"),
    "manifolds.period": INT + ("0", "65"),
    "manifolds.max_points": INT + ("2", BIG),
}
#: the values each constraint of model.PARAMETERS refuses (besides non-numbers and overflow)
CONSTRAINT_BAD = {"": (), "positive": ("0", "-1"), "nonnegative": ("-1",), "nonzero": ("0",)}
for _p in model.PARAMETERS:
    SCENE_KEYS[f"model.{_p.name}"] = REAL + CONSTRAINT_BAD[_p.constraint] + ("1e300",)
#: what a key needs around it to be checked at all (e.g. a sweep for sweep.values)
SCENE_CONTEXT = {"sweep.values": {"sweep": {"parameter": "'mu'"}}, "sweep.parameter": {"sweep": {"values": "[1.0]"}},
                 "seeds.lines": {"seeds": {"kind": "'lines'"}}, "seeds.points": {"seeds": {"kind": "'points'"}},
                 "figure.own_scale": {"sweep": {"parameter": "'mu'", "values": "[0.1, 0.2]"}}}


def scene_text(key, literal, extra=None) -> str:
    """TOML of the good scene with ``key = literal`` (dotted: table.key) and ``extra`` tables."""
    tables = {"seeds": {"n": "4"}, "integration": {"crossings": "2"}}
    for t, kv in (extra or {}).items():
        tables.setdefault(t, {}).update(kv)
    top = {"name": "'s'"}
    if "." in key:
        t, k = key.split(".")
        tables.setdefault(t, {})[k] = literal
    else:
        top[key] = literal
    text = "".join(f"{k} = {v}\n" for k, v in top.items())
    for t, kv in tables.items():
        text += f"[{t}]\n" + "".join(f"{k} = {v}\n" for k, v in kv.items())
    return text


SCENE_TABLE = [(f"{key}={v}"[:80], scene_text(key, v, SCENE_CONTEXT.get(key)), key)
               for key, values in SCENE_KEYS.items() for v in values]
SCENE_TABLE += [
    # unknown keys and tables: the message names them and suggests the close allowed one
    ("unknown_key_close", scene_text("integration.tolerance", "1e-9"), "integration.tolerance"),
    ("unknown_key_misspelt", scene_text("integration.crosings", "2"), "integration.crosings"),
    ("unknown_key_far", scene_text("integration.zzz", "1"), "integration.zzz"),
    ("unknown_table", GOOD_SCENE + "[modle]\nmu = 1.0\n", "modle"),
    ("unknown_top_key", 'nmae = "s"\n', "nmae"),
    ("table_as_value", 'name = "s"\nseeds = 1\n', "seeds"),
    ("empty_file", "", "name"),
    ("not_utf8", b"\xff\xfe\x00 name", "scene"),
    ("energy_h_below_the_region", scene_text("energy.h", "-1.0"), "energy.h"),
    ("toml_syntax", 'name = "s"\n[model\n', "TOML"),
    ("duplicate_key", 'name = "s"\nname = "t"\n', "TOML"),
    ("sweep_without_values", scene_text("sweep.parameter", "'mu'"), "sweep.values"),
    ("sweep_empties_a_panel", scene_text("sweep.values", "[2.0, -1.0]", {"sweep": {"parameter": "'h'"}}),
     "sweep.values"),
    ("atlas_parameter_unknown", scene_text("atlas.parameter", "'bogus'", {"atlas": {"values": "[1.0]"}}),
     "atlas.parameter"),
    ("atlas_values_empty", scene_text("atlas.values", "[]", {"atlas": {"parameter": "'h'"}}), "atlas.values"),
    ("atlas_values_nan", scene_text("atlas.values", "[nan]", {
        "atlas": {"parameter": "'h'"}, "sweep": {"parameter": "'mu'", "values": "[0.1]"},
        "compute": {"sections": "false", "lyapunov": "true"}}), "atlas.values"),
]
DID_YOU_MEAN = {"unknown_key_close": "did you mean 'tol'", "unknown_key_misspelt": "did you mean 'crossings'",
                "unknown_top_key": "did you mean 'name'",
                "unknown_table": "did you mean 'model'"}


@pytest.mark.parametrize("text,key", [c[1:] for c in SCENE_TABLE], ids=[c[0] for c in SCENE_TABLE])
def test_bad_scene_key_gives_one_line_naming_it_and_status_2_and_keeps_the_store(text, key, request, tmp_path,
                                                                                capsys):
    """Nothing is written (OUTPUT_TABLE's sweep_bad_scene_keeps_out: an existing store stays byte
    for byte what it was).  Formerly bugs: energy.h and the model parameters at 1e300 were
    accepted (non-finite runs); unknown keys had no "did you mean"."""
    path = tmp_path / "bad.toml"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    code, out, err = run_main(["sweep", str(path), "--out", str(tmp_path / "o.h5"), "--no-figure", "--quiet"],
                              capsys)
    assert_one_line_error(code, out, err, key)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]
    case = request.node.callspec.id
    if case in DID_YOU_MEAN:
        assert DID_YOU_MEAN[case] in err, err


def test_every_scene_key_is_in_the_table():
    """The table covers every key of every table of the scene schema (a key added to the schema
    must get its bad values here)."""
    from explorer.io import scene

    schema = {"name", "description", "energy.h", "sweep.parameter", "sweep.values", "atlas.parameter", "atlas.values"}
    schema |= {f"seeds.{k}" for k in scene._SEED_KEYS} | {f"integration.{k}" for k in scene._INTEGRATION_KEYS}
    schema |= {f"compute.{k}" for k in scene.COMPUTE_QUANTITIES} | {f"lyapunov.{k}" for k in scene._LYAPUNOV_KEYS}
    schema |= {f"figure.{k}" for k in scene._FIGURE_KEYS} | {f"model.{k}" for k in scene.PARAM_NAMES}
    schema |= {f"manifolds.{k}" for k in scene._MANIFOLD_KEYS}
    tried = set(SCENE_KEYS) | {key for _id, _text, key in SCENE_TABLE}
    assert schema <= tried, sorted(schema - tried)


def test_every_option_of_every_command_is_in_a_table():
    """Every option that takes a value, of every command, is tried with bad values (CLI_TABLE or
    OUTPUT_TABLE); flags take none."""
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    tried = set()
    for argv in [c[1] for c in CLI_TABLE] + [c[1] for c in OUTPUT_TABLE]:
        base = BASE.get(argv[0], [])
        extra = argv[len(base):] if argv[:len(base)] == base else argv
        tried |= {(argv[0], a.split("=")[0]) for a in extra if a.startswith("-")}
    missing = []
    for cmd, p in sub.choices.items():
        for action in p._actions:
            if action.option_strings and action.nargs != 0 and action.dest != "help":
                if not any((cmd, o) in tried for o in action.option_strings):
                    missing.append((cmd, action.option_strings[-1]))
    assert missing == [], missing


# ---------------------------------------------------------------- where commands write
#: (id, argv ({file}: an existing file, {dir}: an existing directory), the option, what {file} is)
OUTPUT_TABLE = [
    ("orbit_out_empty", BASE["orbit"] + ["--out="], "--out", None),
    ("orbit_out_unwritable", BASE["orbit"] + ["--out=/proc/explorer-test/o.h5"], "--out", None),
    ("orbit_out_is_a_directory", BASE["orbit"] + ["--out={dir}"], "--out", None),
    ("orbit_out_under_a_file", BASE["orbit"] + ["--out={file}/o.h5"], "--out", "other"),
    ("orbit_out_read_only", BASE["orbit"] + ["--out={file}"], "--out", "read-only"),
    ("orbit_out_holds_another_run", BASE["orbit"] + ["--out={file}"], "--out", "other"),
    ("orbit_bad_input_keeps_out", BASE["orbit"] + ["--out={file}", "--tol=nan"], "--tol", "other"),
    ("sweep_out_empty", BASE["sweep"] + ["--out="], "--out", None),
    ("sweep_out_unwritable", BASE["sweep"] + ["--out=/proc/explorer-test.h5"], "--out", None),
    ("sweep_out_is_a_directory", BASE["sweep"] + ["--out={dir}"], "--out", None),
    ("sweep_out_under_a_file", BASE["sweep"] + ["--out={file}/o.h5"], "--out", "other"),
    ("sweep_out_read_only", BASE["sweep"] + ["--out={file}"], "--out", "read-only"),
    ("sweep_bad_scene_keeps_out", ["sweep", "bad.toml", "--out={file}", "--no-figure"], "integration.tol", "other"),
    ("sweep_figure_empty", BASE["sweep"] + ["--figure="], "--figure", None),
    ("sweep_figure_unwritable", BASE["sweep"] + ["--figure=/proc/explorer-test/fig"], "--figure", None),
    ("sweep_figure_under_a_file", BASE["sweep"] + ["--figure={file}/fig"], "--figure", "other"),
    ("trajectory_out_empty", ["trajectory", "--out="], "--out", None),
    ("trajectory_out_unwritable", ["trajectory", "--out=/proc/explorer-test/traj"], "--out", None),
    ("figures_out_dir_empty", ["figures", "--only=figure4", "--out-dir="], "--out-dir", None),
    ("figures_out_dir_unwritable", ["figures", "--only=figure4", "--out-dir=/proc/explorer-test"], "--out-dir", None),
    ("figures_out_dir_is_a_file", ["figures", "--only=figure4", "--out-dir={file}"], "--out-dir", "other"),
    ("figures_results_dir_empty", ["figures", "--only=figure4", "--results-dir="], "--results-dir", None),
    ("figures_results_dir_is_a_file", ["figures", "--only=figure4", "--results-dir={file}"], "--results-dir", "other"),
    ("figures_benchmark_missing", ["figures", "--only=work_precision", "--benchmark=nosuch.json"], "--benchmark",
     None),
    ("explore_export_dir_empty", ["explore", "--port=0", "--export-dir="], "--export-dir", None),
    ("explore_export_dir_is_a_file", ["explore", "--port=0", "--export-dir={file}"], "--export-dir", "other"),
    ("serve_export_dir_empty", ["serve", "--port=0", "--export-dir="], "--export-dir", None),
    ("serve_export_dir_is_a_file", ["serve", "--port=0", "--export-dir={file}"], "--export-dir", "other"),
    ("sweep_scene_empty", ["sweep", ""], "scene", None),
    ("sweep_scene_is_a_directory", ["sweep", "{dir}"], "scene", None),
    ("explore_scene_empty", ["explore", ""], "scene", None),
]
OLD_BYTES = b"old contents \x00\xff kept byte for byte"


@pytest.mark.parametrize("argv,name,setup", [c[1:] for c in OUTPUT_TABLE], ids=[c[0] for c in OUTPUT_TABLE])
def test_bad_output_place_gives_one_line_and_keeps_what_was_there(argv, name, setup, workdir, monkeypatch, capsys):
    """A read-only file is made so with chmod; running as root (which may write anyway) the
    check's permission test (os.access) is told the file is read-only.  Formerly bugs:
    orbit --out '' ended in a FileNotFoundError traceback; sweep --out '' or --figure '' wrote to
    the default place; a read-only store was replaced by os.replace; the figures' directories were
    not checked."""
    if any("/proc/" in a for a in argv) and not os.path.isdir("/proc/self"):
        pytest.skip("needs /proc")
    old = workdir / "old.h5"
    old.write_bytes(OLD_BYTES)
    (workdir / "d").mkdir()
    (workdir / "bad.toml").write_text(GOOD_SCENE.replace("crossings = 2", "crossings = 2\ntol = nan"))
    if setup == "read-only":
        old.chmod(0o444)
        if os.geteuid() == 0:
            real_access = os.access
            monkeypatch.setattr(validation.os, "access", lambda p, mode, **kw: False if os.fspath(p) == str(old)
                                else real_access(p, mode, **kw))
    argv = [a.replace("{scene}", "good.toml").replace("{file}", str(old)).replace("{dir}", str(workdir / "d"))
            for a in argv]
    before = _listing(workdir)
    code, out, err = run_main(argv, capsys)
    assert_one_line_error(code, out, err, name)
    assert _listing(workdir) == before
    assert old.read_bytes() == OLD_BYTES


# ---------------------------------------------------------------- the limits are named once
def test_the_limits_are_named_in_validation_and_documented():
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "bad_input.md").read_text()
    for name in ("MAX_MAGNITUDE", "MAX_MEMORY_FRACTION", "MAX_PERIOD", "MAX_CONTINUATION_STEPS", "MAX_JOBS",
                 "MAX_SEEDS", "MAX_MAP_RESOLUTION", "MAX_DPI", "MIN_TOL", "MAX_TOL"):
        assert name in doc, name
    assert validation.MAX_MAGNITUDE >= 1e6   # tests/test_stress.py integrates h = 1e6


def test_memory_limit_names_the_option_and_the_machine():
    with pytest.raises(validation.ParameterError, match=r"--n = 1000000000000 needs .* in memory .* this machine"):
        validation.fits_in_memory("--n", 10**12, 32, "returns")


# ---------------------------------------------------------------- a handful through `python -m explorer`
@pytest.mark.parametrize("argv,name", [
    (["orbit", "--p1", "0", "--p2", "0", "--tol", "1e-20"], "tol"),
    (["lyapunov", "--p1", "0", "--p2", "0", "--history", BIG], "history"),
    (["periodic", "--period", BIG, "--guess", "0,0"], "period"),
    (["orbit", "--p1", "0", "--p2", "0", "--out", ""], "out"),
    (["orbit", "--p1", "0", "--p2", "0", "--h", "1e308"], "h"),
    (["trajectory", "--lam", "1e300", "--no-figure"], "lam"),
])
def test_python_dash_m_explorer_bad_input(argv, name, tmp_path):
    """The real exit path: status 2, one line, no numpy warning lines (orbit --h 1e308 used to
    print numpy's RuntimeWarning before the error line), nothing written."""
    p = subprocess.run([sys.executable, "-m", "explorer"] + argv, capture_output=True, text=True, timeout=300,
                       cwd=tmp_path)
    assert_one_line_error(p.returncode, p.stdout, p.stderr, name)
    assert list(tmp_path.iterdir()) == []


def test_python_dash_m_explorer_bad_scene_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD_SCENE + "[integration]\nmethod = 'rk4'\n")
    p = subprocess.run([sys.executable, "-m", "explorer", "sweep", str(path), "--out", str(tmp_path / "o.h5")],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert p.stderr.startswith("explorer: error:")
    assert not (tmp_path / "o.h5").exists()


def test_the_tables_have_distinct_ids():
    for table in (CLI_TABLE, SCENE_TABLE, OUTPUT_TABLE):
        ids = [c[0] for c in table]
        assert len(ids) == len(set(ids)), [i for i in ids if ids.count(i) > 1]
