"""The orbit command streams: rows printed or stored block by block are those of one run, bit for
bit; a long orbit killed with SIGKILL loses at most its current block and its rerun finishes the
same file as an uninterrupted run; huge or conflicting requests are refused up front (exit 2)."""
import json
import os
import re
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from explorer import model
from explorer.analysis import sections
from explorer.app import cli, orbit
from explorer.io import store
from explorer.io.store import stream

#: a stored block (a block being written has a temporary name)
BLOCK_FILE = re.compile(r"^\d{6}\.npz$")

PRM = model.FIGURE4.with_(mu=0.5)
ARGS = ["orbit", "--p1", "0.5", "--p2", "0", "--mu", "0.5", "--tol", "1e-12"]


def _datasets(path):
    with h5py.File(path, "r") as f:
        g = f["panels/000"]
        return {k: g[k][()] for k in g}


def test_stored_rows_are_the_rows_of_one_run_bit_for_bit(tmp_path):
    ref = sections.crossings(PRM, 2.0, [(0.5, 0.0)], n_crossings=3000, tol=1e-12)
    rep = orbit.to_store(tmp_path / "o.h5", PRM, 0.5, 0.0, 2.0, 3000, block=700, tol=1e-12)
    assert rep.crossings == 3000 and rep.status == "done" and rep.blocks == 5
    p = store.read_store(tmp_path / "o.h5").panels[0]
    np.testing.assert_array_equal(p.crossings, ref.orbit(0))
    assert rep.max_dh == sections.max_energy_error(p.crossings) > 0   # kept per block, not reread
    np.testing.assert_array_equal(p.final, ref.final)
    np.testing.assert_array_equal(p.info, ref.info)
    assert not os.path.exists(stream.blocks_dir(tmp_path / "o.h5"))   # blocks removed once stored
    # the pieces of iter_rows are the stored rows
    np.testing.assert_array_equal(np.concatenate(list(store.iter_rows(tmp_path / "o.h5", 0, rows=1000))),
                                  p.crossings)


def test_printed_rows_come_block_by_block_and_equal_one_run(capsys):
    ref = sections.crossings(PRM, 2.0, [(0.5, 0.0)], n_crossings=50, tol=1e-12)
    code = cli.main(ARGS + ["--crossings", "50", "--block", "7", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    got = json.loads(out)
    assert got["status"] == "done" and got["settings"]["n_crossings"] == 50
    np.testing.assert_array_equal(np.array(got["crossings"]), ref.orbit(0))
    code = cli.main(ARGS + ["--crossings", "50", "--block", "7"])
    out, _ = capsys.readouterr()
    rows = np.array([[float(v) for v in line.split(",")[1:]] for line in out.strip().splitlines()[1:]])
    np.testing.assert_array_equal(rows, ref.orbit(0))


def test_a_killed_long_orbit_resumes_to_the_same_file_as_an_uninterrupted_run(tmp_path, capsys):
    K, B = 40000, 2000
    full = tmp_path / "full.h5"
    orbit.to_store(full, PRM, 0.5, 0.0, 2.0, K, block=B, tol=1e-12)
    path = tmp_path / "killed.h5"
    cmd = [sys.executable, "-m", "explorer"] + ARGS + ["--crossings", str(K), "--block", str(B), "--out", str(path),
                                                       "--json"]
    blocks = stream.blocks_dir(path)
    kills = 0
    for wait in (3, 6):           # kill twice, each time once a few more blocks are stored
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        deadline = time.time() + 120
        while time.time() < deadline and proc.poll() is None:
            n = len([f for f in os.listdir(blocks) if BLOCK_FILE.match(f)]) if os.path.isdir(blocks) else 0
            if n >= wait:
                os.kill(proc.pid, signal.SIGKILL)
                kills += 1
                break
            time.sleep(0.01)
        proc.wait()
        assert not os.path.exists(path)          # nothing half-written where the store goes
    assert kills >= 1
    # the same command resumes from the killed processes' blocks (in this process)
    capsys.readouterr()
    code = cli.main(cmd[3:])
    out, err = capsys.readouterr()
    assert code == 0, err
    rep = json.loads(out)
    assert rep["crossings"] == K and rep["resumed_blocks"] >= 3 and not rep["already_complete"]
    a, b = _datasets(full), _datasets(path)
    # the energy error of the blocks stored before the kills is carried by their files
    assert rep["max_dh"] == sections.max_energy_error(b["crossings"])
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    # a rerun of a finished run computes nothing
    assert cli.main(cmd[3:]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["already_complete"] and again["crossings"] == K


def test_huge_requests_and_other_runs_are_refused_up_front(tmp_path, capsys):
    code = cli.main(ARGS + ["--crossings", "100000000000000000", "--out", str(tmp_path / "h.h5")])
    _, err = capsys.readouterr()
    assert code == 2 and "on disk" in err and "crossings" in err and "Traceback" not in err
    assert not os.path.exists(tmp_path / "h.h5") and not os.path.exists(stream.blocks_dir(tmp_path / "h.h5"))
    p = tmp_path / "o.h5"
    assert cli.main(ARGS + ["--crossings", "20", "--out", str(p)]) == 0
    capsys.readouterr()
    code = cli.main(ARGS + ["--crossings", "30", "--out", str(p)])   # another run, same file
    _, err = capsys.readouterr()
    assert code == 2 and "--force" in err
    assert cli.main(ARGS + ["--crossings", "30", "--out", str(p), "--force"]) == 0
    assert store.read_store(p).panels[0].count[0] == 30
    for bad in (["--block", "0"],):
        code = cli.main(ARGS + ["--crossings", "30"] + bad)
        _, err = capsys.readouterr()
        assert code == 2 and "--block" in err


@pytest.mark.parametrize("method,kw", [("dop853", ["--tol", "1e-11"]), ("split6", ["--dt", "0.05"])])
def test_every_method_streams_to_a_store_bit_for_bit(tmp_path, method, kw):
    ref = sections.crossings(PRM, 2.0, [(0.5, 0.0)], n_crossings=400, method=method, tol=1e-11, dt=0.05)
    p = tmp_path / "o.h5"
    args = ["orbit", "--p1", "0.5", "--p2", "0", "--mu", "0.5", "--method", method, "--crossings", "400",
            "--block", "64", "--out", str(p)] + kw
    assert cli.main(args) == 0
    np.testing.assert_array_equal(store.read_store(p).panels[0].crossings, ref.orbit(0))
