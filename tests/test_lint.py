"""Static checks in the suite: ruff over the whole tree (rules in pyproject.toml [tool.ruff]) and
mypy over the pure-Python layers ([tool.mypy] files). Both are test extras."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(*args):
    return subprocess.run([sys.executable, "-m", *args], cwd=ROOT, capture_output=True, text=True)


def test_ruff_finds_nothing():
    r = run("ruff", "check", "--no-cache", "src", "tests", "benchmarks", "tools")
    assert r.returncode == 0, r.stdout + r.stderr


def test_mypy_finds_nothing_in_the_pure_python_layers():
    r = run("mypy", "--no-incremental", "--config-file", "pyproject.toml")
    assert r.returncode == 0, r.stdout + r.stderr
