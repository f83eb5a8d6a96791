"""README.md's two commands: the test command is exactly what CI runs, and both commands
install into a fresh virtual environment before they run anything."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def fenced_bash(text):
    return re.findall(r"```bash\n(.*?)\n```", text, re.S)


def test_ci_runs_exactly_the_readme_test_command():
    blocks = fenced_bash((ROOT / "README.md").read_text())
    main_job, tests = blocks[0].strip(), blocks[1].strip()
    assert main_job.endswith("python -m explorer sweep") and "pip install ." in main_job
    # both cores, a module's tests on one worker (its module-scoped fixtures once); the test
    # environment installed by uv, editable (the plain-install test shares numba's cache of the same
    # files, tests/test_plain_install.py); the tests write the bytecode of what they import
    # (tests/conftest.py), so the install compiles none
    assert 'python -m pip install -q uv && uv pip install -q -e ".[test]"' in tests
    # the CPU-dependent tests rerun beside the suite for a generic CPU (tests/generic_cpu.py)
    assert tests.endswith("&& python -m pytest -q -n 2 --dist loadscope --rerun-cpu-dependent "
                          '"NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=.numba-generic"')
    for cmd in (main_job, tests):
        assert cmd.startswith("python3 -m venv .venv && . .venv/bin/activate && ")
    ci_lines = [ln.strip() for ln in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert tests in ci_lines


def test_every_figure_of_explorer_figures_is_committed_and_linked_from_the_readme():
    from explorer.app.paper.registry import FIGURES

    text = (ROOT / "README.md").read_text()
    for name in FIGURES:
        for ext in ("png", "pdf"):
            assert (ROOT / "figures" / f"{name}.{ext}").stat().st_size > 10_000, (name, ext)
        assert f"](figures/{name}.png)" in text, name
