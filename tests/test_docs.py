"""The documentation: the Sphinx site builds with warnings as errors, every command has its
page, README stays a front door, and every test, module or object the docs name exists (so a
claim cannot point at a test that was renamed or never written)."""
import ast
import functools
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


@functools.cache
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
    for name in ("crossings", "indicators", "find_fixed_point", "read_store", "run_sweep"):
        assert f'id="explorer.{name}"' in api, name   # autodoc really documented it


def test_readme_is_a_front_door_that_links_every_command_page():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 250
    for c in COMMANDS:
        assert f"docs/commands/{c}.md" in text, c
    assert "figures/figure4.png" in text


# ---------------------------------------------------------------- the model page and its labels
MODEL_PAGE = DOCS / "model.md"
#: the equations file that once lived outside the repository (cited as a bare file name)
_EXTERNAL_MODEL = re.compile(r"(?<![\w/])MODEL\.md")
#: a label list after a citation of the model page: "R3", "(R6, R7, R8)", "R6/R9", "(labels R1-R11)"
_CITED_LABELS = re.compile(r"docs/model\.md`{0,2}[\s(,:]*(?:labels?\s+)?"
                           r"(R\d+(?:\s*(?:-|–|\.\.|/|,|and)\s*R\d+)*)")
_SCANNED = ("src", "tests", "benchmarks", "tools", "docs")
_TEXT_SUFFIXES = {".py", ".pyi", ".md", ".toml", ".txt", ".rst", ".cfg", ".ini", ".yml", ".yaml"}


def _repository_text_files():
    for top in _SCANNED:
        for f in sorted((ROOT / top).rglob("*")):
            rel = f.relative_to(ROOT).parts
            if f.is_file() and f.suffix in _TEXT_SUFFIXES and not any(
                    p.startswith((".", "_build", "__pycache__")) or p.endswith(".egg-info") for p in rel):
                yield f
    yield from (ROOT / "README.md", ROOT / "pyproject.toml")


def _labels(span):
    """The numbers of a label list, ranges expanded ("R1-R11", "R1..R11", "R1–R11")."""
    out = set()
    for a, sep, b in re.findall(r"R(\d+)(?=(\s*(?:-|–|\.\.)\s*R(\d+))?)", span):
        out.add(int(a))
        if sep:
            out.update(range(int(a), int(b) + 1))
    return out


def _defined_model_labels():
    """Labels with a heading ending "(R<n>)" right after its target "(model-r<n>)=" in docs/model.md."""
    text = MODEL_PAGE.read_text()
    return {int(a) for a, b in re.findall(r"^\(model-r(\d+)\)=\n#{1,6} .*\(R(\d+)\)$", text, re.M) if a == b}


def test_model_page_defines_every_label_the_code_cites():
    """Each R<n> the source cites, after "docs/model.md" or bare (inside the model package), has its
    section on the model page, so the repository alone explains every formula the code names."""
    defined = _defined_model_labels()
    cited, bare = {}, {}
    for f in sorted((ROOT / "src").rglob("*")):
        if not (f.is_file() and f.suffix in {".py", ".toml"}):
            continue
        text = re.sub(r"\s*\n\s*#?\s*", " ", f.read_text())   # a citation may run over a line break
        for m in _CITED_LABELS.finditer(text):
            for n in _labels(m.group(1)):
                cited.setdefault(n, f.relative_to(ROOT).as_posix())
        for n in re.findall(r"\bR(\d+)\b", text):
            bare.setdefault(int(n), f.relative_to(ROOT).as_posix())
    assert cited, "no citation of docs/model.md found in src/: the pattern is out of date"
    missing = {f"R{n} ({where})" for n, where in {**bare, **cited}.items() if n not in defined}
    assert not missing, f"cited but not defined in docs/model.md: {sorted(missing)}"


def test_nothing_cites_the_model_file_that_lived_outside_the_repository():
    offenders = [f"{f.relative_to(ROOT)}:{i}" for f in _repository_text_files()
                 for i, line in enumerate(f.read_text(errors="replace").splitlines(), 1)
                 if _EXTERNAL_MODEL.search(line)]
    assert not offenders, f"cite docs/model.md instead: {offenders}"
