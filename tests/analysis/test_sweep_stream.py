"""Streamed sweep panels: a panel whose rows exceed the budget is computed in rounds of blocks and
written to the store block by block; its file is the file of an unstreamed run, for one process
and for joblib workers; a killed streamed sweep resumes from its stored blocks; a scene whose rows
would not fit on the disk is refused up front (exit 2, its size named)."""
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from test_sweep import datasets, write_scene

from explorer.analysis import sweep
from explorer.app import cli
from explorer.io import store
from explorer.io.store import stream

#: a stored block (a block being written has a temporary name)
BLOCK_FILE = re.compile(r"^\d{6}\.npz$")

SCENE = """
name = "streamed"
[model]
mu = 0.5
[energy]
h = 2.0
[sweep]
parameter = "mu"
values = [0.3, 1.0]
[seeds]
kind = "grid"
n = 6
[integration]
method = "taylor"
tol = 1e-12
crossings = 3000
"""


def _run(scene, out, *extra):
    assert cli.main(["sweep", str(scene), "--out", str(out), "--no-figure", "--quiet", *extra]) == 0


def test_a_streamed_panel_is_stored_as_one_run_would_store_it(tmp_path, monkeypatch):
    scene = write_scene(tmp_path, SCENE)
    _run(scene, tmp_path / "whole.h5")                       # 6 orbits x 3000 rows: one round
    monkeypatch.setattr(sweep, "STREAM_BYTES", 6 * 700 * 40)  # -> blocks of 700 crossings
    assert sweep.panel_block(6, 3000) == 700
    _run(scene, tmp_path / "streamed.h5")
    a, b = datasets(tmp_path / "whole.h5"), datasets(tmp_path / "streamed.h5")
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    p = store.read_store(tmp_path / "streamed.h5").panels[1]
    assert p.attrs["block"] == sweep.panel_block(len(p.count), 3000) < 3000 and p.count.sum() > 0
    assert not any(n.endswith(".blocks") for n in os.listdir(tmp_path))   # blocks removed
    # rerun: both panels are stored with the same settings, nothing is computed
    _run(scene, tmp_path / "streamed.h5")
    # joblib workers stream the same numbers
    _run(scene, tmp_path / "jobs.h5", "--jobs", "2")
    c = datasets(tmp_path / "jobs.h5")
    for k in a:
        np.testing.assert_array_equal(a[k], c[k], err_msg=k)


def test_a_killed_streamed_sweep_resumes_from_its_blocks(tmp_path, monkeypatch):
    scene = write_scene(tmp_path, SCENE.replace("crossings = 3000", "crossings = 10000"))
    ref, out = tmp_path / "ref.h5", tmp_path / "killed.h5"
    env = dict(os.environ, EXPLORER_STREAM_BYTES=str(6 * 1000 * 40))
    cmd = [sys.executable, "-m", "explorer", "sweep", str(scene), "--no-figure", "--quiet"]
    _run(scene, ref)                         # the unstreamed run, in this process
    blocks = stream.blocks_dir(out, 0)
    proc = subprocess.Popen(cmd + ["--out", str(out)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    killed = False
    deadline = time.time() + 300
    while proc.poll() is None and time.time() < deadline:
        if os.path.isdir(blocks) and len([f for f in os.listdir(blocks) if BLOCK_FILE.match(f)]) >= 6:
            os.kill(proc.pid, signal.SIGKILL)
            killed = True
            break
        time.sleep(0.01)
    proc.wait()
    assert killed, "the streamed sweep finished before it could be killed"
    assert not out.exists()                  # the panel was not written: its blocks were
    # the same command resumes from the killed process's blocks (in this process, with its budget)
    monkeypatch.setattr(sweep, "STREAM_BYTES", int(env["EXPLORER_STREAM_BYTES"]))
    _run(scene, out)
    a, b = datasets(ref), datasets(out)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert store.read_store(out).panels[0].attrs["resumed_blocks"] >= 6


def test_a_scene_whose_rows_do_not_fit_on_the_disk_is_refused_up_front(tmp_path, capsys):
    scene = write_scene(tmp_path, SCENE.replace("crossings = 3000", "crossings = 100000000000000"))
    code = cli.main(["sweep", str(scene), "--out", str(tmp_path / "h.h5"), "--no-figure", "--quiet"])
    _, err = capsys.readouterr()
    assert code == 2 and "on disk" in err and "crossings" in err and "Traceback" not in err
    assert not (tmp_path / "h.h5").exists()


@pytest.mark.parametrize("n,K,block", [(2, 10**6, 104857), (200, 10**3, 10**3), (1000, 10**3, 256),
                                      (10**5, 10**4, 256)])
def test_panel_blocks_bound_the_rows_in_memory(n, K, block):
    assert sweep.panel_block(n, K) == block
    assert min(K, block) * n * 40 <= max(sweep.STREAM_BYTES, sweep.MIN_BLOCK * n * 40)


SYSTEM_SCENE = """
name = "hh_streamed"
section = "x"
direction = 1
coords = ["y", "py"]
solve = "px"
[energy]
value = 0.125
[seeds]
kind = "points"
points = [[0.1, 0.1], [-0.1, 0.2], [0.3, 0.0], [0.0, 0.35], [0.2, -0.1]]
[integration]
crossings = 1500
"""


def test_a_systems_streamed_panel_is_one_runs_panel_and_resumes_after_an_interruption(tmp_path, monkeypatch):
    """A System's scene panel past the row budget is streamed as Chaplygin's (docs/scenes.md): a sweep
    interrupted after 3 blocks resumes from them, and its store is the unstreamed run's."""
    from systems import henon_heiles

    import explorer as ex
    from explorer.io.scene import parse_scene

    scene = parse_scene(SYSTEM_SCENE, system=henon_heiles())
    ex.run_sweep(scene, tmp_path / "whole.h5", progress=False)
    monkeypatch.setattr(sweep, "STREAM_BYTES", 5 * 256 * 40)     # -> blocks of 256 crossings
    stored = [0]
    block = stream.PanelStreams.block

    def interrupted(self, *args):
        block(self, *args)
        stored[0] += 1
        if stored[0] == 3:
            raise KeyboardInterrupt
    monkeypatch.setattr(stream.PanelStreams, "block", interrupted)
    with pytest.raises(KeyboardInterrupt):
        ex.run_sweep(scene, tmp_path / "resumed.h5", progress=False)
    assert not (tmp_path / "resumed.h5").exists()                 # the panel was not written: its blocks were
    monkeypatch.setattr(stream.PanelStreams, "block", block)
    ex.run_sweep(scene, tmp_path / "resumed.h5", progress=False)
    a = datasets(tmp_path / "whole.h5")
    b = datasets(tmp_path / "resumed.h5")
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    p = store.read_store(tmp_path / "resumed.h5").panels[0]
    assert p.attrs["block"] == 256 and p.attrs["resumed_blocks"] == 3 and p.count.sum() == 5 * 1500
    assert not any(n.endswith(".blocks") for n in os.listdir(tmp_path))
