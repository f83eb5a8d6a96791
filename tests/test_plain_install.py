"""README's first command installs the package with no extras (`pip install .`): everything it
offers must run from that install alone, not only from the test environment, which has the test
extras (scipy, pytest, ...) besides.  One virtual environment with the package and nothing else,
then, in it: every command's documented example (the `example:` line of each `--help`; `figures`
draws Figure 4, from the store of `sweep`'s example, which runs with `--no-figure` so that the
same figure is not drawn twice) and `serve` answering an HTTP request.  Each exits 0 with no traceback.  Every
figure is drawn by tests/app/test_paper.py in the test environment; that no figure needs more
than a plain install rests on the static rule below (every import of src/explorer, lazy ones
included, is a declared distribution's), which a figure run would only sample.

What a plain install is made of, proved in two parts (docs/tests.md, "What the tests prove"):

- the distribution: the sdist and the wheel built from it (what `pip install .` installs) hold
  every file of ``src/explorer`` and nothing else, and declare pyproject's dependencies;
- the environment: a venv with the package installed in editable mode and **no extra**, at the
  test environment's versions of the distributions they share, runs every command.  Editable,
  because its kernels are then the test environment's files, so numba's on-disk cache (keyed by
  each source file's path) serves both: the plain venv loads what the suite compiled and the
  suite loads what the plain venv compiled, where a wheel's copy of the package recompiled every
  kernel cold (about 100 CPU-seconds, the suite's largest single item; README's test command
  installs the test environment editable for this).  A dependency missing from pyproject fails
  here exactly as in a wheel's install: the venv has only what the package declares.
"""
from __future__ import annotations

import importlib.metadata as md
import importlib.util
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import sysconfig
import time
import urllib.request
import venv
import zipfile
from pathlib import Path

import pytest

from explorer.app.commands import registry

ROOT = Path(__file__).resolve().parents[1]
#: what a command may take at most in the plain install, compiling its kernels included (a
#: bound on a hang, not a speed goal: the 2-core CI machine runs the suite beside it)
COMMAND_TIMEOUT = 900.0
#: commands that run until Ctrl-C: started, asked for their page over HTTP, then interrupted
SERVERS = ("serve", "explore")
#: extra arguments for an example where its own would reach outside the sandbox: explore's
#: example opens the user's web browser
EXTRA = {"explore": ["--no-browser"]}


def _uv() -> str | None:
    """uv's executable if the test environment has it (README's test command installs it), else
    None."""
    try:
        from uv import find_uv_bin
    except ImportError:
        return shutil.which("uv")
    return find_uv_bin()


def _plain_venv(where: Path) -> Path:
    """A virtual environment with the package (editable, at ROOT) and its declared dependencies,
    and nothing else; its python.  Each distribution it shares with the test environment is
    pinned to the test environment's version (a constraint, so nothing is added by it): the two
    run the same numba on the same files and share its cache.  The installer is uv where the test
    environment has it (README's test command: the same build backend and the same declared
    dependencies, in seconds where pip takes about 50 s), else the venv's own pip."""
    uv = _uv()
    venv.EnvBuilder(with_pip=uv is None, clear=True).create(where)
    py = where / "bin" / "python"
    constraints = where / "test-environment.txt"
    constraints.write_text("".join(f"{d.metadata['Name']}=={d.version}\n" for d in md.distributions()
                                   if d.metadata["Name"] and d.metadata["Name"].lower() != "explorer"))
    install = ([uv, "pip", "install", "-q", "--python", str(py)] if uv is not None
               else [str(py), "-m", "pip", "install", "-q", "--disable-pip-version-check"])
    r = subprocess.run([*install, "-c", str(constraints), "-e", str(ROOT)], capture_output=True, text=True,
                       timeout=COMMAND_TIMEOUT)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    _share_bytecode(where)
    return py


def _share_bytecode(where: Path) -> int:
    """Link into the venv at ``where`` the test environment's bytecode of each module file that the two
    environments share, the same file (one inode: uv links both from its cache), as a pip install would
    have compiled it; how many.  The commands then do not compile numpy, numba, matplotlib, Bokeh and
    Panel from source (8 CPU-s over the module's processes).  Only the bytecode of a source the venv
    has, next to it: a .pyc in __pycache__ imports nothing without its source, and Python checks each
    against its source (mtime and size) as ever.  With a copying installer nothing is the same file:
    nothing is linked and the commands compile as before."""
    site = Path(sysconfig.get_path("purelib"))
    plain = Path(sysconfig.get_path("purelib", vars={"base": str(where), "platbase": str(where)}))
    if sys.pycache_prefix is not None or site == plain or not plain.is_dir():
        return 0
    linked = 0
    for d, dirs, files in os.walk(plain):
        dirs[:] = [x for x in dirs if x != "__pycache__"]
        for f in files:
            if not f.endswith(".py"):
                continue
            source, theirs = Path(d) / f, site / Path(d).relative_to(plain) / f
            cached = Path(importlib.util.cache_from_source(str(theirs)))
            try:
                if not os.path.samefile(source, theirs) or not cached.is_file():
                    continue
                mine = Path(importlib.util.cache_from_source(str(source)))
                mine.parent.mkdir(exist_ok=True)
                os.link(cached, mine)
            except OSError:     # not in the test environment, no bytecode there, or already linked
                continue
            linked += 1
    return linked


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    """(python of the plain install, a working directory, the environment to run commands in: the
    test run's own, NUMBA_CACHE_DIR included, so that the kernels are shared)."""
    py = _plain_venv(tmp_path_factory.mktemp("plain-venv"))
    cwd = tmp_path_factory.mktemp("plain-cwd")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST", "COV_"))}
    env.pop("PYTHONPATH", None)
    # pip compiles what it installs to bytecode; uv does not.  So that the commands run as after a
    # pip install, the venv has the test environment's bytecode of the files the two share
    # (_share_bytecode), and they write the bytecode of whatever else they import (the first one
    # does, the others read it), as every process of the test run does (tests/conftest.py)
    env.update(PYTHONUNBUFFERED="1", MPLBACKEND="Agg")
    return py, cwd, env


def _run(plain, argv):
    py, cwd, env = plain
    r = subprocess.run([str(py), *argv], cwd=cwd, env=env, capture_output=True, text=True,
                       timeout=COMMAND_TIMEOUT, stdin=subprocess.DEVNULL)
    out = r.stdout + r.stderr
    assert r.returncode == 0 and "Traceback" not in out, f"{shlex.join(argv)} -> {r.returncode}\n{out[-4000:]}"
    return r


def _requirement_name(requirement: str) -> str:
    """The distribution's name of a requirement string (``numba>=0.59``, ``tomli>=1.1; ...``)."""
    return re.match(r"[A-Za-z0-9._-]+", requirement.strip()).group().lower()


def _declared() -> set:
    """The names of pyproject.toml's run-time dependencies."""
    try:
        import tomllib
    except ImportError:  # python 3.10
        import tomli as tomllib

    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    return {_requirement_name(d) for d in deps}


def test_the_plain_install_has_no_test_extra_and_its_explorer_is_the_packages(plain):
    """The venv has the package and its declared dependencies only: none of the test extras, and
    its explorer is this tree's (what the cache sharing rests on)."""
    py, _cwd, _env = plain
    r = _run(plain, ["-c", "import explorer, importlib.util as u; print(explorer.__file__); "
                           "print(*(u.find_spec(m) is None for m in ('pytest', 'playwright', 'xdist', 'mypy')))"])
    where, *absent = r.stdout.split()
    assert Path(where) == ROOT / "src" / "explorer" / "__init__.py" and absent == ["True"] * 4, r.stdout


def test_the_wheel_that_pip_install_builds_holds_every_file_of_the_package_and_its_dependencies(tmp_path):
    """What `pip install .` installs: the wheel built from the sdist (uv's default, or pip's
    wheel of the tree) holds exactly the package's files (the presets and the type stubs
    included: the commands read them) and declares pyproject's dependencies."""
    uv = _uv()
    build = ([uv, "build", "-q", "--out-dir", str(tmp_path), str(ROOT)] if uv is not None
             else [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp_path), str(ROOT)])
    r = subprocess.run(build, capture_output=True, text=True, timeout=COMMAND_TIMEOUT)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    (wheel,) = tmp_path.glob("explorer-*.whl")
    src = ROOT / "src"
    files = {p.relative_to(src).as_posix() for p in (src / "explorer").rglob("*")
             if p.is_file() and "__pycache__" not in p.parts and p.suffix not in (".nbi", ".nbc", ".pyc")}
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        meta = z.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
    assert {n for n in names if n.startswith("explorer/")} == files
    requires = [line.split(":", 1)[1] for line in meta.splitlines() if line.startswith("Requires-Dist:")]
    assert _declared() == {_requirement_name(q) for q in requires if "extra ==" not in q}, requires


def _example_argv(name):
    argv = shlex.split(registry.example(name))
    assert argv[:3] == ["python", "-m", "explorer"], argv
    return ["-m", "explorer", *argv[3:], *EXTRA.get(name, [])]


#: the two examples of one figure: sweep's computes the preset figure4 into results/figure4.h5 and
#: draws it beside the store (runner.draw_figure); figures' (``--only figure4``) finds that store
#: complete and draws the same figure from it with the same runner.draw_figure
FIGURE4_EXAMPLES = ("sweep", "figures")


@pytest.fixture(scope="module")
def figure4_examples(plain):
    """(sweep's run, figures' run): sweep's example with ``--no-figure``, then figures' example in
    the same working directory, which draws the figure that sweep's would have drawn, from the
    store sweep's wrote.  Every line of both examples runs once, where sweep's figure and then
    figures' redrew the 955,000 crossings twice (7 CPU-s)."""
    return _run(plain, _example_argv("sweep") + ["--no-figure"]), _run(plain, _example_argv("figures"))


@pytest.mark.parametrize("name", [n for n in registry.COMMANDS if n not in SERVERS])
def test_every_commands_example_runs_from_the_plain_install(plain, name, request):
    if name not in FIGURE4_EXAMPLES:
        _run(plain, _example_argv(name))
        return
    _sweep, figures = request.getfixturevalue("figure4_examples")
    # figures drew from sweep's store (complete: not the reduced figure4-quick.h5 of --quick)
    assert "(from results/figure4.h5)" in figures.stdout, figures.stdout
    _py, cwd, _env = plain
    assert all((cwd / "figures" / f"figure4.{ext}").stat().st_size > 1000 for ext in ("png", "pdf"))


@pytest.mark.parametrize("name", SERVERS)
def test_the_page_is_served_from_the_plain_install(plain, name):
    py, cwd, env = plain
    proc = subprocess.Popen([str(py), *_example_argv(name), "--port", "0"], cwd=cwd, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
    try:
        url = proc.stdout.readline().strip()
        assert url.startswith("http://"), (url, proc.stderr.read()[-3000:] if proc.poll() is not None else "")
        t0, body = time.monotonic(), ""
        while time.monotonic() - t0 < COMMAND_TIMEOUT and not body:   # until it answers
            try:
                with urllib.request.urlopen(url, timeout=30) as r:
                    body = r.read().decode("utf-8", "replace")
            except OSError:
                assert proc.poll() is None, proc.stderr.read()[-3000:]
                time.sleep(0.2)
        assert "bokeh" in body.lower()
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(60)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    err = proc.stderr.read()
    assert proc.returncode in (0, 130) and "Traceback" not in err, err[-3000:]


def test_the_package_declares_every_module_it_imports_as_a_dependency():
    """No module of src/explorer imports a distribution that pyproject.toml does not declare as a
    run-time dependency (the cause of `melnikov --splitting` failing in a plain install): every
    top-level import is the standard library, explorer itself, or a declared distribution's."""
    import ast

    declared = _declared()
    provides = md.packages_distributions()
    missing = set()
    for path in (ROOT / "src" / "explorer").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                     else [])
            for name in names:
                top = name.split(".")[0]
                if top in sys.stdlib_module_names or top in ("explorer", "__future__"):
                    continue
                dists = {d.lower() for d in provides.get(top, [top])}
                if not dists & declared:
                    missing.add((path.relative_to(ROOT).as_posix(), top))
    # llvmlite is numba's own (pinned by it); dask is the optional extra `explorer[dask]` of
    # `sweep --backend dask`, imported only there, with a ParameterError naming the extra
    assert {t for _p, t in missing} <= {"llvmlite", "dask"}, sorted(missing)
