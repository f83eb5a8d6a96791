"""explorer.store: layout, round trips, atomicity under crashes and SIGKILL."""
import json
import os
import random
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from explorer.io import store
from explorer.io.store import StoreError, commit_panel, panel_hashes, read_store

TESTS_DIR = os.path.dirname(os.path.abspath(__file__))
SCENE_TOML = 'name = "fig4"\n[model]\nmu = 0.5\n'
FILE_ATTRS = {
    "scene_name": "fig4",
    "scene": SCENE_TOML,
    "provenance": {"versions": {"explorer": "test"}, "git_revision": "unknown"},
}


def make_panel(index, gen, n=40, k=150):
    """Deterministic panel (index, generation): arrays with NaN-padded ``data``
    + ``count`` and attrs; the expected ragged rows are ``data[i, :count[i]]``."""
    rng = np.random.default_rng([index, gen])
    count = rng.integers(0, k + 1, n).astype(np.int64)
    count[0] = 0          # an orbit without crossings
    count[-1] = k         # a full one
    data = np.full((n, k, 5), np.nan)
    for i in range(n):
        data[i, :count[i]] = rng.normal(size=(count[i], 5))
    arrays = {
        "seeds": rng.normal(size=(n, 2)),
        "y0": rng.normal(size=(n, 5)),
        "count": count,
        "status": rng.integers(0, 5, n).astype(np.int8),
        "final": rng.normal(size=(n, 5)),
        "info": rng.normal(size=(n, 3)),
        "data": data,
    }
    settings = {"method": "taylor", "tol": 1e-13, "crossings": k, "gen": int(gen)}
    attrs = {
        "label": f"mu = {index * 0.1:.1f}", "parameter": "mu", "value": index * 0.1, "h": 1.5,
        "params": {"a1": 1.0, "mu": index * 0.1}, "settings": settings,
        "method": "taylor", "tol": 1e-13, "dt": 0.05, "phi0": 0.0, "direction": 1,
        "crossings_requested": k, "wall_time": 0.25, "generation": int(gen),
    }
    return arrays, attrs


def assert_panel_equals(p, index, gen, **kw):
    arrays, attrs = make_panel(index, gen, **kw)
    for name in ("seeds", "y0", "count", "status", "final", "info"):
        np.testing.assert_array_equal(getattr(p, name), arrays[name], err_msg=name)
    assert p.crossings.dtype == np.float64 and p.offsets.dtype == np.int64
    assert p.status.dtype == np.int8 and p.count.dtype == np.int64
    np.testing.assert_array_equal(np.diff(p.offsets), arrays["count"])
    for i in range(len(arrays["count"])):
        np.testing.assert_array_equal(p.orbit(i), arrays["data"][i, :arrays["count"][i]])
    assert not np.isnan(p.crossings).any()
    assert p.complete and p.attrs["complete"] is True
    assert p.attrs["index"] == index
    for key in ("label", "parameter", "value", "h", "method", "tol", "dt", "phi0", "direction",
                "crossings_requested", "wall_time", "generation"):
        assert p.attrs[key] == attrs[key], key
    assert p.params == attrs["params"] and p.settings == attrs["settings"]
    assert json.loads(p.attrs["settings"]) == attrs["settings"]
    assert p.hash == store.settings_hash(attrs["settings"])


def store_bytes(path):
    """Bytes on disk of the store at ``path``: its file and its panel files."""
    folder = path.parent / (path.name + ".panels")
    return path.stat().st_size + sum(p.stat().st_size for p in folder.iterdir())


def assert_only_the_store(directory, path):
    """``directory`` holds the store file ``path`` and its panel folder, and the folder holds exactly
    the panel files the store links: nothing half-written or unlinked is left behind."""
    folder = path.parent / (path.name + ".panels")
    assert sorted(directory.iterdir()) == sorted([path, folder])
    with h5py.File(path, "r") as f:
        linked = {f["panels"].get(name, getlink=True).filename for name in f["panels"]}
    assert {f"{path.name}.panels/{p.name}" for p in folder.iterdir()} == linked


def test_round_trip_two_panels_arrays_attrs_and_ragged_orbits(tmp_path):
    path = tmp_path / "s.h5"
    a0, t0 = make_panel(0, 7)
    commit_panel(path, 0, a0, t0, FILE_ATTRS)
    # panel 1 given directly as offsets + crossings
    a1, t1 = make_panel(1, 3)
    data, count = a1.pop("data"), a1["count"]
    a1["crossings"] = np.concatenate([data[i, :count[i]] for i in range(len(count))])
    a1["offsets"] = np.concatenate([[0], np.cumsum(count)])
    commit_panel(path, 1, a1, t1, FILE_ATTRS)

    s = read_store(path)
    assert sorted(s.panels) == [0, 1]
    assert_panel_equals(s.panels[0], 0, 7)
    assert_panel_equals(s.panels[1], 1, 3)
    p = s.panels[0]
    assert p.status_names == {int(k): v for k, v in store.STATUS_NAMES.items()}
    np.testing.assert_array_equal(p.points(), p.crossings[:, 1:3])
    assert set(p.arrays) == set(store.DATASETS) and p.arrays["crossings"] is p.crossings
    assert panel_hashes(path) == {0: p.hash, 1: s.panels[1].hash}


def test_nan_padding_inside_count_is_dropped_and_count_follows(tmp_path):
    a, t = make_panel(0, 1, n=3, k=4)
    a["count"] = np.array([0, 4, 4])
    a["data"][1] = np.arange(20.0).reshape(4, 5)
    a["data"][2] = np.arange(20.0).reshape(4, 5)
    a["data"][2, 3] = np.nan  # a NaN row is never stored
    commit_panel(tmp_path / "s.h5", 0, a, t, FILE_ATTRS)
    p = read_store(tmp_path / "s.h5").panels[0]
    np.testing.assert_array_equal(p.count, [0, 4, 3])
    np.testing.assert_array_equal(p.orbit(2), np.arange(15.0).reshape(3, 5))
    assert not np.isnan(p.crossings).any()


def test_replacing_a_panel_keeps_the_other_and_created(tmp_path):
    path = tmp_path / "s.h5"
    commit_panel(path, 0, *make_panel(0, 1), FILE_ATTRS)
    commit_panel(path, 1, *make_panel(1, 1), FILE_ATTRS)
    created = read_store(path).attrs["created"]
    commit_panel(path, 0, *make_panel(0, 2, n=10, k=30), FILE_ATTRS)
    s = read_store(path)
    assert sorted(s.panels) == [0, 1]
    assert_panel_equals(s.panels[0], 0, 2, n=10, k=30)
    assert_panel_equals(s.panels[1], 1, 1)
    assert s.attrs["created"] == created and s.attrs["updated"] >= created


def test_file_attrs_format_version_scene_and_provenance(tmp_path):
    path = tmp_path / "s.h5"
    fa = {"scene_name": "fig4", "scene": SCENE_TOML, "provenance": store.provenance({"seed": 1}),
          "sweep_parameter": "mu"}
    commit_panel(path, 0, *make_panel(0, 1), fa)
    s = read_store(path)
    assert s.attrs["format"] == "explorer.sections" == store.FORMAT
    assert s.attrs["format_version"] == store.FORMAT_VERSION == 2
    assert s.scene == SCENE_TOML and s.scene_name == "fig4"
    assert s.attrs["sweep_parameter"] == "mu"
    for key in ("created", "updated"):
        assert s.attrs[key].endswith("Z") and "T" in s.attrs[key]
    prov = json.loads(s.attrs["provenance"])
    assert prov == s.provenance
    for name in ("explorer", "numpy", "numba", "llvmlite", "h5py", "joblib", "matplotlib"):
        assert name in prov["versions"]
    assert prov["versions"]["numpy"] == np.__version__
    assert prov["versions"]["h5py"] == h5py.__version__
    rev = prov["git_revision"]
    assert rev == "unknown" or len(rev.split("+")[0]) == 40
    for key in ("python", "platform", "command_line", "date"):
        assert key in prov
    assert prov["seed"] == 1


def test_store_module_does_not_import_numba_or_matplotlib():
    code = ("import sys, explorer.io.store; "
            "print(any(m in sys.modules for m in ('numba', 'matplotlib')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == "False", out.stderr


def test_ragged_layout_readable_with_plain_h5py(tmp_path):
    path = tmp_path / "s.h5"
    arrays, attrs = make_panel(4, 9)
    commit_panel(path, 4, arrays, attrs, FILE_ATTRS)
    with h5py.File(path, "r") as f:  # no explorer code below
        g = f["panels/004"]
        offsets, crossings = g["offsets"][()], g["crossings"][()]
        assert list(g["crossings"].attrs["columns"]) in (["t", "p1", "p2", "M", "dH"],
                                                         [b"t", b"p1", b"p2", b"M", b"dH"])
        assert g.attrs["complete"] and g.attrs["index"] == 4
        names = json.loads(g["status"].attrs["status_names"])
        assert names["0"] == "done"
        assert g["seeds"].shape == (40, 2) and g["y0"].shape == (40, 5) and g["info"].shape == (40, 3)
        assert g["status"].dtype == np.int8 and offsets.dtype == np.int64
        count = g["count"][()]
    for i, c in enumerate(arrays["count"]):
        np.testing.assert_array_equal(crossings[offsets[i]:offsets[i + 1]], arrays["data"][i, :c])
    np.testing.assert_array_equal(count, arrays["count"])


def test_large_datasets_are_gzip_shuffle_fletcher32_small_ones_are_not(tmp_path):
    path = tmp_path / "s.h5"
    arrays, attrs = make_panel(0, 1, n=12, k=1000)
    arrays["count"][:] = 1000
    arrays["data"] = np.random.default_rng(0).normal(size=(12, 1000, 5))
    commit_panel(path, 0, arrays, attrs, FILE_ATTRS)
    with h5py.File(path, "r") as f:
        big = f["panels/000/crossings"]
        assert big.shape == (12000, 5)
        assert big.compression == "gzip" and big.compression_opts == 4
        assert big.shuffle and big.fletcher32 and big.chunks is not None
        small = f["panels/000/seeds"]
        assert small.compression is None and not small.fletcher32
    np.testing.assert_array_equal(read_store(path).panels[0].crossings, arrays["data"].reshape(-1, 5))


def test_replacing_a_panel_does_not_grow_the_file_and_keeps_the_others(tmp_path):
    """HDF5 never reclaims a deleted group's space: a store whose panel is replaced again and
    again is rebuilt compactly (no growth beyond a few percent), with every other panel, the
    root attributes and 'created' unchanged."""
    path = tmp_path / "s.h5"
    for i in range(3):
        commit_panel(path, i, *make_panel(i, 0), FILE_ATTRS)
    created = read_store(path).attrs["created"]
    for gen in range(1, 11):
        commit_panel(path, 1, *make_panel(1, gen), FILE_ATTRS)
    fresh = tmp_path / "fresh.h5"      # the same content written once
    for i, gen in ((0, 0), (1, 10), (2, 0)):
        commit_panel(fresh, i, *make_panel(i, gen), FILE_ATTRS)
    assert store_bytes(path) < 1.05 * store_bytes(fresh), (store_bytes(path), store_bytes(fresh))
    data = read_store(path)
    assert sorted(data.panels) == [0, 1, 2]
    assert_panel_equals(data.panels[0], 0, 0)
    assert_panel_equals(data.panels[1], 1, 10)
    assert_panel_equals(data.panels[2], 2, 0)
    assert data.attrs["created"] == created and data.attrs["scene"] == SCENE_TOML
    assert not list(tmp_path.glob("s.h5.tmp-*"))


def test_crash_before_replace_leaves_original_unchanged_and_readable(tmp_path, monkeypatch):
    path = tmp_path / "s.h5"
    commit_panel(path, 0, *make_panel(0, 1), FILE_ATTRS)
    before = path.read_bytes()
    seen = {}

    def boom(src, dst):
        with h5py.File(src, "r") as f:  # the temp file was fully written
            seen["panels"] = sorted(f["panels"])
        assert os.path.basename(src).startswith("s.h5.tmp-%d-" % os.getpid())
        raise OSError("simulated crash")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError, match="simulated crash"):
        commit_panel(path, 1, *make_panel(1, 1), FILE_ATTRS)
    monkeypatch.undo()
    assert seen["panels"] == ["000", "001"]
    assert path.read_bytes() == before
    s = read_store(path)
    assert sorted(s.panels) == [0]
    assert_panel_equals(s.panels[0], 0, 1)
    assert_only_the_store(tmp_path, path)  # the temporaries were removed


_KILL_CHILD = """
import sys
sys.path.insert(0, {tests!r})
from test_store import make_panel, FILE_ATTRS
from explorer.io.store import commit_panel
path, gen = sys.argv[1], int(sys.argv[2])
print("ready", flush=True)
while True:
    for k in range(3):
        commit_panel(path, k, *make_panel(k, gen), FILE_ATTRS)
        gen += 1
"""


def test_sigkill_at_random_moments_never_leaves_a_half_written_store(tmp_path):
    path = tmp_path / "s.h5"
    code = _KILL_CHILD.format(tests=TESTS_DIR)
    rnd = random.Random(12345)
    seen_panels = 0
    for run in range(10):
        proc = subprocess.Popen([sys.executable, "-c", code, str(path), str(run * 100000)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            assert proc.stdout.readline().strip() == "ready", proc.stderr.read()
            time.sleep(rnd.uniform(0.0, 0.3))
            assert proc.poll() is None, proc.stderr.read()
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            proc.stdout.close()
            proc.stderr.close()
        if path.exists():
            s = read_store(path)
            assert s.attrs["format"] == store.FORMAT
            for idx, p in s.panels.items():
                assert p.complete
                assert_panel_equals(p, idx, p.attrs["generation"])
            assert set(panel_hashes(path)) == set(s.panels)
            seen_panels = max(seen_panels, len(s.panels))
    assert seen_panels > 0
    store.clean_stale_temporaries(path)
    assert_only_the_store(tmp_path, path)


def test_stale_temporaries_are_cleaned_live_ones_and_other_files_kept(tmp_path):
    path = tmp_path / "s.h5"
    commit_panel(path, 0, *make_panel(0, 1, n=3, k=2), FILE_ATTRS)
    dead = tmp_path / "s.h5.tmp-999999999-abcd1234"
    own = tmp_path / f"s.h5.tmp-{os.getpid()}-00ff00ff"
    other = tmp_path / "s.h5.bak"
    for p in (dead, own, other):
        p.write_bytes(b"partial")
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        live = tmp_path / f"s.h5.tmp-{sleeper.pid}-deadbeef"
        live.write_bytes(b"in flight")
        removed = store.clean_stale_temporaries(path)
        assert sorted(removed) == sorted([str(dead), str(own)])
        assert not dead.exists() and not own.exists()
        assert live.exists() and other.exists() and path.exists()
    finally:
        sleeper.kill()
        sleeper.wait()
    store.clean_stale_temporaries(path)
    assert not live.exists()
    assert store.clean_stale_temporaries(tmp_path / "absent.h5") == []


def test_corrupt_file_gives_store_error_naming_path(tmp_path):
    path = tmp_path / "bad.h5"
    path.write_bytes(np.random.default_rng(0).bytes(4096))
    for fn in (lambda: read_store(path), lambda: panel_hashes(path),
               lambda: commit_panel(path, 0, *make_panel(0, 1, n=3, k=2), FILE_ATTRS)):
        with pytest.raises(StoreError) as exc:
            fn()
        msg = str(exc.value)
        assert str(path) in msg and "\n" not in msg
    assert "--force" in msg and "--out" in msg
    assert isinstance(exc.value, ValueError)
    # truncated HDF5 (a real store cut in half) is also refused
    good = tmp_path / "good.h5"
    commit_panel(good, 0, *make_panel(0, 1), FILE_ATTRS)
    cut = tmp_path / "cut.h5"
    cut.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(StoreError, match="cut.h5"):
        read_store(cut)
    # replace_corrupt starts a fresh store
    commit_panel(path, 2, *make_panel(2, 1), FILE_ATTRS, replace_corrupt=True)
    assert sorted(read_store(path).panels) == [2]


def test_hdf5_of_another_format_gives_store_error(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    before = path.read_bytes()
    with pytest.raises(StoreError, match="not an explorer store"):
        read_store(path)
    with pytest.raises(StoreError, match="other.h5"):
        commit_panel(path, 0, *make_panel(0, 1, n=3, k=2), FILE_ATTRS)
    assert path.read_bytes() == before


def test_missing_file_gives_store_error_and_no_hashes(tmp_path):
    path = tmp_path / "nope.h5"
    with pytest.raises(StoreError, match="nope.h5"):
        read_store(path)
    assert panel_hashes(path) == {}


def test_invalid_arrays_are_rejected_without_touching_the_file(tmp_path):
    path = tmp_path / "s.h5"
    commit_panel(path, 0, *make_panel(0, 1, n=3, k=2), FILE_ATTRS)
    before = path.read_bytes()
    arrays, attrs = make_panel(1, 1, n=3, k=2)
    arrays["seeds"] = arrays["seeds"][:2]
    with pytest.raises(ValueError, match="seeds"):
        commit_panel(path, 1, arrays, attrs, FILE_ATTRS)
    arrays, attrs = make_panel(1, 1, n=3, k=2)
    arrays["trajectory"] = np.zeros((3, 10, 5))
    with pytest.raises(ValueError, match="trajectory"):
        commit_panel(path, 1, arrays, attrs, FILE_ATTRS)
    assert path.read_bytes() == before
    assert_only_the_store(tmp_path, path)


def test_write_bytes_atomic_and_atomic_path(tmp_path):
    target = tmp_path / "fig.png"
    store.write_bytes_atomic(target, b"one")
    assert target.read_bytes() == b"one"
    with store.atomic_path(target) as tmp:
        assert tmp.endswith(".png") and os.path.dirname(tmp) == str(tmp_path)
        with open(tmp, "wb") as f:
            f.write(b"two")
        assert target.read_bytes() == b"one"
    assert target.read_bytes() == b"two"
    with pytest.raises(RuntimeError):
        with store.atomic_path(target) as tmp:
            with open(tmp, "wb") as f:
                f.write(b"half")
            raise RuntimeError("failed while saving")
    assert target.read_bytes() == b"two"
    assert list(tmp_path.iterdir()) == [target]


def test_a_map_panels_computed_mask_round_trips_and_a_map_stored_without_it_reads_as_all_computed(tmp_path):
    arrays, attrs = make_panel(0, 1, n=40, k=3)
    mask = np.arange(40) % 3 != 0
    arrays.update(megno=np.linspace(1.0, 9.0, 40), lyapunov_status=np.zeros(40, np.int8), map_computed=mask)
    attrs.update(map_resolution=8, map_p1=[0.0, 1.0], map_p2=[0.0, 1.0])
    commit_panel(tmp_path / "new.h5", 0, arrays, attrs, FILE_ATTRS)
    got = read_store(tmp_path / "new.h5").panels[0].extra["map_computed"]
    assert got.dtype == bool
    np.testing.assert_array_equal(got, mask)
    np.testing.assert_array_equal(store.read_panel_datasets(tmp_path / "new.h5", 0, ("map_computed",))[0]
                                  ["map_computed"], mask)
    del arrays["map_computed"]                          # a map written before the mask existed
    commit_panel(tmp_path / "old.h5", 0, arrays, attrs, FILE_ATTRS)
    old = read_store(tmp_path / "old.h5").panels[0].extra["map_computed"]
    assert old.dtype == bool and old.shape == (40,) and old.all()
    assert store.read_panel_datasets(tmp_path / "old.h5", 0, ("map_computed",))[0]["map_computed"].all()
    del attrs["map_resolution"]                         # not a map: no mask
    commit_panel(tmp_path / "seeds.h5", 0, arrays, attrs, FILE_ATTRS)
    assert "map_computed" not in read_store(tmp_path / "seeds.h5").panels[0].extra
