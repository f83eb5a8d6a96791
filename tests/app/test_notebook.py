"""``ex.explore(...)`` in a live Jupyter kernel (src/explorer/app/serve/notebook.py,
docs/commands/serve.md "In a notebook").

A small notebook is built with nbformat and executed headless by nbclient in a real ipykernel
running this interpreter (its kernelspec installed into a temporary directory, the package on the
kernel's PYTHONPATH): no cell raises, the cell that ends with the explorer displays a Panel/Bokeh
bundle, and a click in the next cell streams the asked-for number of crossings, which equal
``explorer.crossings`` from that start bit for bit.  Skipped with the
reason when nbclient, nbformat, ipykernel or panel is missing; under CI=true that is a failure.
"""
from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import numpy as np
import pytest

import explorer
from explorer.analysis import sections


def _notebook_problem() -> str | None:
    for module, package in (("nbclient", "nbclient"), ("nbformat", "nbformat"), ("ipykernel", "ipykernel"),
                            ("panel", "panel")):
        if importlib.util.find_spec(module) is None:
            return f"{package} is not installed (pip install {package})"
    return None


#: on CI (.ci/run installs the test extras) a missing Jupyter piece is a failure, not a skip: the
#: notebook path must have run in a real kernel for the run to count
_PROBLEM = _notebook_problem()
if _PROBLEM is not None and os.environ.get("CI") == "true":
    raise RuntimeError(f"CI=true but the notebook test cannot run: {_PROBLEM}")

#: the notebook's settings and its click (inside the allowed region of Figure 4 at mu = 0.03, h = 2)
MU, CROSSINGS, START = 0.03, 50, (0.3, 0.1)
#: what a displayed Panel object carries in a notebook: Panel's own mime type next to the HTML that
#: holds the Bokeh document (``docs_json``)
PANEL_MIME = "application/vnd.holoviews_exec.v0+json"

CELLS = [
    "import panel as pn\nimport explorer as ex\npn.extension()\nprint('explorer:', ex.__file__)",
    f"app = ex.explore(mu={MU}, n_crossings={CROSSINGS})\napp",
    # the page's work runs on the kernel's event loop: the cell awaits (top-level await) while it waits
    "import asyncio\nimport time\nimport numpy as np\n"
    f"assert app.page.click({START[0]}, {START[1]}) is not None\n"
    "t0 = time.time()\n"
    f"while len(app.page.orbits.columns()['t']) < {CROSSINGS} and time.time() - t0 < 240:\n"
    "    await asyncio.sleep(0.01)\n"
    "got = np.column_stack([np.asarray(app.page.orbits.columns()[k]) for k in ('t', 'p1', 'p2', 'M', 'dH')])\n"
    "np.save('orbit.npy', got)\n"
    "print('crossings:', len(app.page.orbits.columns()['t']))",
    "app.close()",
]


@pytest.mark.skipif(_PROBLEM is not None, reason=str(_PROBLEM))
def test_explore_in_a_live_kernel_displays_the_page_and_streams_the_clicked_orbit(tmp_path, monkeypatch):
    import nbclient
    import nbformat
    from ipykernel.kernelspec import install

    from explorer.app.serve.settings import page_settings

    # the kernel is this interpreter (not whatever "python3" a Jupyter path holds) and imports the
    # explorer the tests import
    prefix = tmp_path / "jupyter"
    install(prefix=str(prefix), kernel_name="python3")
    monkeypatch.setenv("JUPYTER_PATH", str(prefix / "share" / "jupyter"))
    src = str(Path(explorer.__file__).resolve().parents[1])
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([src, *filter(None, [os.environ.get("PYTHONPATH")])]))
    spec = (prefix / "share" / "jupyter" / "kernels" / "python3" / "kernel.json").read_text()
    assert sys.executable.replace("\\", "\\\\") in spec

    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in CELLS])
    client = nbclient.NotebookClient(nb, kernel_name="python3", timeout=600,
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()                                   # raises CellExecutionError if a cell raised
    nbformat.validate(nb)
    for cell in nb.cells:
        assert not [o for o in cell.outputs if o.output_type == "error"], cell.outputs

    printed = "".join(o.get("text", "") for o in nb.cells[0].outputs if o.output_type == "stream")
    assert f"explorer: {explorer.__file__}" in printed.splitlines(), printed     # the package under test

    display = [o for o in nb.cells[1].outputs if o.output_type in ("execute_result", "display_data")]
    assert display, nb.cells[1].outputs
    bundle = display[-1].data
    assert PANEL_MIME in bundle and "text/html" in bundle, sorted(bundle)
    html = bundle["text/html"]
    assert "docs_json" in html and '"name":"section"' in html     # the page's section figure is in it

    printed = "".join(o.get("text", "") for o in nb.cells[2].outputs if o.output_type == "stream")
    assert f"crossings: {CROSSINGS}" in printed.splitlines(), printed

    base, _label, _seeds = page_settings(mu=MU, crossings=CROSSINGS)
    ref = sections.crossings(base.params, base.h, [(START[0], START[1])], n_crossings=CROSSINGS)
    np.testing.assert_array_equal(np.load(tmp_path / "orbit.npy"), ref.orbit(0))
