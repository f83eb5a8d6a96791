"""What guards a store (issue 25 items 2 and 4): one writer at a time (a second `sweep` or `orbit
--out` on the same store exits 2 naming the holder; the lock dies with its holder), one scene per
store (another scene is refused without --force), a read-only place refused in one line, block
folders that nothing will resume removed, and the default sweep's figure written beside its store
(never over the repository's committed figures/)."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from explorer.app import cli, runner
from explorer.io import store
from explorer.io.store import lock, stream

#: one panel that takes a few seconds (the first writer holds the lock meanwhile)
LONG = """
name = "long"
[energy]
h = 2.0
[seeds]
kind = "grid"
n = 2000
[integration]
method = "taylor"
tol = 1e-12
crossings = 2000
"""
TINY = """
name = "tiny"
[energy]
h = 2.0
[sweep]
parameter = "mu"
values = [0.5, 1.0]
[seeds]
kind = "grid"
n = 8
[integration]
method = "taylor"
tol = 1e-12
crossings = 30
"""
ORBIT = ["orbit", "--p1", "0.5", "--p2", "0", "--mu", "0.5", "--tol", "1e-12"]


def _scene(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _explorer(args, **env):
    return subprocess.Popen([sys.executable, "-m", "explorer"] + [str(a) for a in args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=dict(os.environ, EXPLORER_NATIVE="0", **env))


def _wait_for_lock(proc, out, timeout=120.0):
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None:
        if os.path.exists(lock.lock_path(out)):
            return True
        time.sleep(0.02)
    return False


@pytest.mark.parametrize("command", ["sweep", "orbit"])
def test_a_second_writer_of_a_store_exits_2_naming_the_holder(tmp_path, command):
    out = tmp_path / "shared.h5"
    if command == "sweep":
        args = ["sweep", _scene(tmp_path, LONG), "--out", out, "--no-figure", "--quiet"]
    else:
        args = ORBIT + ["--crossings", "10000000", "--block", "20000", "--out", out]
    first = _explorer(args, NUMBA_NUM_THREADS="1")   # it only holds the lock: one thread burns half the CPU
    try:
        assert _wait_for_lock(first, out), first.communicate()
        second = subprocess.run([sys.executable, "-m", "explorer"] + [str(a) for a in args], capture_output=True,
                                text=True, timeout=120, env=dict(os.environ, EXPLORER_NATIVE="0"))
        assert first.poll() is None, "the first writer finished before the second started"
        assert second.returncode == 2, second.stderr
        lines = second.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in second.stderr, second.stderr
        assert f"being written by pid {first.pid}" in lines[0] and str(out) in lines[0]
    finally:
        first.send_signal(signal.SIGKILL)      # the kernel releases the lock of a killed holder
        first.communicate()
    assert os.path.exists(lock.lock_path(out))  # its file is left, but it locks nothing any more
    with store.store_lock(out):
        pass
    assert not os.path.exists(lock.lock_path(out))


def test_another_scene_with_the_same_out_is_refused_without_force(tmp_path, capsys):
    out = tmp_path / "one.h5"
    first = _scene(tmp_path, TINY, "tiny.toml")
    other = _scene(tmp_path, TINY.replace('name = "tiny"', 'name = "other"').replace("[0.5, 1.0]", "[2.0]"),
                   "other.toml")
    assert cli.main(["sweep", str(first), "--out", str(out), "--no-figure", "--quiet"]) == 0
    before = store.read_store(out)
    capsys.readouterr()
    assert cli.main(["sweep", str(other), "--out", str(out), "--no-figure", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "'tiny'" in err and "'other'" in err and "--force" in err, err
    kept = store.read_store(out)                  # untouched
    assert kept.attrs["scene_name"] == "tiny" and sorted(kept.panels) == [0, 1]
    np.testing.assert_array_equal(kept.panels[1].crossings, before.panels[1].crossings)
    # with --force the store is the other scene's alone (no panel of the first one left behind)
    assert cli.main(["sweep", str(other), "--out", str(out), "--no-figure", "--quiet", "--force"]) == 0
    replaced = store.read_store(out)
    assert replaced.attrs["scene_name"] == "other" and sorted(replaced.panels) == [0]


@pytest.mark.parametrize("where", ["proc", "under_a_file"])
def test_orbit_out_in_a_place_that_cannot_be_written_is_one_line(tmp_path, capsys, where):
    """Was `OSError: [Errno 30] Read-only file system: 'results/o.h5.blocks'` (a traceback): the
    place is now checked before anything runs, as `sweep --out` does.  As root no directory is
    read-only, so: /proc (refuses new files, even to root), and a path under a regular file."""
    if where == "proc":
        if not os.path.isdir("/proc/self"):
            pytest.skip("needs /proc")
        out = "/proc/explorer-test-orbit.h5"
    else:
        (tmp_path / "file.txt").write_text("x")
        out = str(tmp_path / "file.txt" / "o.h5")
    code = cli.main(ORBIT + ["--crossings", "10", "--out", out])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert f"--out {out}" in err and "cannot write" in err
    assert not os.path.exists(out + ".blocks")


def test_block_folders_of_finished_or_replaced_panels_are_removed(tmp_path):
    scene = _scene(tmp_path, TINY)
    out = tmp_path / "s.h5"
    assert cli.main(["sweep", str(scene), "--out", str(out), "--no-figure", "--quiet"]) == 0
    # left by an interrupted --force rerun of panel 0 (the same hash) and by a scene that had 8 panels
    for i in (0, 7):
        bs = stream.BlockStream(out, {"panel_hash": f"x{i}"}, index=i)
        bs.resume({a: np.zeros((9, 5)) for a in stream.STATE_ARRAYS})
        assert os.path.isdir(bs.dir)
    rep = runner.run_sweep(str(scene), out, draw=False, progress=False)
    assert rep.computed == () and stream.panel_block_dirs(out) == {}
    # orbit --out: a finished store's stale blocks go too
    from explorer.app import orbit
    from explorer.model import FIGURE4

    o = tmp_path / "o.h5"
    orbit.to_store(o, FIGURE4.with_(mu=0.5), 0.5, 0.0, 2.0, 50, block=20, tol=1e-12)
    os.makedirs(stream.blocks_dir(o))
    assert orbit.to_store(o, FIGURE4.with_(mu=0.5), 0.5, 0.0, 2.0, 50, block=20, tol=1e-12).already_complete
    assert not os.path.exists(stream.blocks_dir(o))


def test_the_default_sweep_writes_its_figure_beside_its_store_not_into_figures(tmp_path, monkeypatch):
    """README command 1 in a clone must not overwrite the committed figures/figure4.png: the
    repository's figures are regenerated by `explorer figures` only (docs/commands/sweep.md)."""
    scene = _scene(tmp_path, TINY)
    monkeypatch.chdir(tmp_path)
    rep = runner.run_sweep(str(scene), draw=True, progress=False)     # as `explorer sweep` runs it
    assert os.path.normpath(rep.out) == os.path.join("results", "tiny.h5")
    assert {os.path.normpath(p) for p in rep.figure} == {os.path.join("results", "tiny" + e) for e in (".png", ".pdf")}
    assert (tmp_path / "results" / "tiny.png").stat().st_size > 0 and not (tmp_path / "figures").exists()


def test_a_sweep_from_python_draws_nothing_unless_asked(tmp_path, monkeypatch):
    """run_sweep(scene, out) computes and stores; a figure only with figure= or draw=True (issue 21:
    the Python API does not write pictures into the working directory by default)."""
    scene = _scene(tmp_path, TINY)
    monkeypatch.chdir(tmp_path)
    rep = runner.run_sweep(str(scene), tmp_path / "s.h5", progress=False)
    assert rep.figure == () and not list(tmp_path.rglob("*.png")) and (tmp_path / "s.h5").exists()
    rep = runner.run_sweep(str(scene), tmp_path / "s.h5", figure=tmp_path / "fig", progress=False)
    assert (tmp_path / "fig.png").stat().st_size > 0
