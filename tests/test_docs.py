"""The documentation: the Sphinx site builds with warnings as errors, every command has its
page, README stays a front door, and every test, module or object the docs name exists (so a
claim cannot point at a test that was renamed or never written)."""
import ast
import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(DOCS.rglob("*.md")) + [ROOT / "README.md", ROOT / "benchmarks" / "README.md",
                                      ROOT / "benchmarks" / "stress" / "README.md"]
COMMANDS = ("sweep", "orbit", "lyapunov", "fixedpoint", "explore", "melnikov", "trajectory", "figures")


def _test_functions(path):
    tree = ast.parse(path.read_text())
    return {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))}


def _test_references(text):
    """(file, test name) for `tests/x.py::name` and the `::name` that follow it in one span."""
    refs = []
    first = r"(tests/[\w/]+\.py)((?:::\w+(?:\[[^\]]*\])?)?)"
    more = r"((?:`?,?\s*(?:also\s+)?`::\w+(?:\[[^\]]*\])?)*)"
    for m in re.finditer(first + more, text):
        path = m.group(1)
        names = re.findall(r"::(\w+)", m.group(2) + m.group(3))
        refs.append((path, names))
    return refs


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_test_the_docs_name_exists(page):
    missing = []
    for path, names in _test_references(page.read_text()):
        f = ROOT / path
        if not f.exists():
            missing.append(path)
            continue
        funcs = _test_functions(f)
        missing += [f"{path}::{n}" for n in names if n not in funcs]
    assert not missing, missing


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_module_path_and_dotted_name_the_docs_give_exists(page):
    text = page.read_text()
    missing = [p for p in re.findall(r"\b(src/explorer/[\w/]+\.py)", text) if not (ROOT / p).exists()]
    for dotted in set(re.findall(r"`(explorer(?:\.\w+)+)", text)):
        parts = dotted.split(".")
        for k in range(len(parts), 0, -1):  # longest importable module, then attributes
            try:
                obj = importlib.import_module(".".join(parts[:k]))
            except ImportError:
                continue
            try:
                for attr in parts[k:]:
                    obj = getattr(obj, attr)
            except AttributeError:
                missing.append(dotted)
            break
        else:
            missing.append(dotted)
    assert not missing, missing


def test_the_site_builds_with_warnings_as_errors_and_has_a_page_per_command(tmp_path):
    out = tmp_path / "html"
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS),
                        str(out)], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr
    for page in ["index", "quickstart", "api", "scenes", "store", "methods", "tests", "errata", "benchmarks",
                 "architecture"] + [f"commands/{c}" for c in COMMANDS]:
        assert (out / f"{page}.html").is_file(), page
    api = (out / "api.html").read_text()
    for name in ("section_crossings", "indicators", "find_fixed_point", "read_store", "run_sweep"):
        assert f'id="explorer.{name}"' in api, name   # autodoc really documented it


def test_readme_is_a_front_door_that_links_every_command_page():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 250
    for c in COMMANDS:
        assert f"docs/commands/{c}.md" in text, c
    assert "figures/figure4.png" in text
