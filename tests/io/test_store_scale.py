"""explorer.store format 2: a commit writes its panel and a small store file, whatever the number of
panels stored; format-1 stores (every panel inside the store file) still read and are converted on
their next write; the store stays readable with plain h5py through its external links."""
import os
import shutil

import h5py
import numpy as np
import pytest
from test_store import FILE_ATTRS, assert_only_the_store, assert_panel_equals, make_panel, store_bytes

from explorer.io import store
from explorer.io.store import StoreError, commit_panel, read_store

#: panels committed by the scaling test
N_COMMITS = 40
#: the store file: root attributes and one external link per panel, a few kB however many panels
STORE_FILE_BYTES = 16_000


def _files(directory):
    """{path: (inode, mtime, size)} of every file under ``directory``."""
    out = {}
    for root, _dirs, names in os.walk(directory):
        for name in names:
            st = os.stat(os.path.join(root, name))
            out[os.path.join(root, name)] = (st.st_ino, st.st_mtime_ns, st.st_size)
    return out


def _written(before, after):
    """Bytes of the files created or changed between two :func:`_files` snapshots, and those files."""
    touched = [p for p, v in after.items() if before.get(p) != v]
    return sum(after[p][2] for p in touched), touched


def test_a_commit_writes_its_panel_and_the_small_store_file_not_the_panels_already_stored(tmp_path):
    path = tmp_path / "s.h5"
    written = []
    for i in range(N_COMMITS):
        before = _files(tmp_path)
        commit_panel(path, i, *make_panel(i, 0, n=20, k=100), FILE_ATTRS)
        nbytes, touched = _written(before, _files(tmp_path))
        # the store file and the new panel's file, nothing else
        assert len(touched) == 2 and str(path) in touched, touched
        panel = next(p for p in touched if p != str(path))
        assert os.path.dirname(panel) == str(path) + ".panels" and os.path.basename(panel).startswith(f"{i:03d}-")
        panel = os.path.getsize(panel)
        assert nbytes - panel == path.stat().st_size <= STORE_FILE_BYTES
        written.append(nbytes)
    # the whole sweep wrote about the store once (format 1 copied the file each time: ~N/2 times)
    assert sum(written) < 1.5 * store_bytes(path), (sum(written), store_bytes(path))
    assert max(written) < 1.5 * min(written), written
    # replacing a panel and replacing its indicators cost that panel too
    for change in (lambda: commit_panel(path, 3, *make_panel(3, 1, n=20, k=100), FILE_ATTRS),
                   lambda: store.update_panel(path, 3, {"megno": np.full(20, 2.0)}, {"indicators_hash": "x"}),
                   lambda: store.update_panel_attrs(path, 3, {"chaotic_fraction": 0.5})):
        before = _files(tmp_path)
        change()
        nbytes, touched = _written(before, _files(tmp_path))
        assert nbytes < 1.5 * max(written)
    assert_only_the_store(tmp_path, path)
    data = read_store(path)
    assert sorted(data.panels) == list(range(N_COMMITS))
    assert_panel_equals(data.panels[N_COMMITS - 1], N_COMMITS - 1, 0, n=20, k=100)
    p3 = data.panels[3]
    np.testing.assert_array_equal(p3.extra["megno"], 2.0)
    assert p3.attrs["chaotic_fraction"] == 0.5 and p3.attrs["indicators_hash"] == "x"
    np.testing.assert_array_equal(p3.crossings, read_store(path).panels[3].crossings)
    assert_panel_equals(p3, 3, 1, n=20, k=100)


def _as_format_1(src, dst):
    """Write at ``dst`` the store ``src`` in the layout of format 1: every panel a group inside the
    one file (root attributes kept, ``format_version = 1``), with plain h5py."""
    with h5py.File(src, "r") as s, h5py.File(dst, "w") as d:
        for key, value in s.attrs.items():
            d.attrs[key] = value
        d.attrs["format_version"] = 1
        panels = d.create_group("panels")
        for name in s["panels"]:
            s.copy(s["panels"][name], panels, name=name)   # the linked group's contents, copied in


def test_a_format_1_store_reads_and_its_next_write_moves_every_panel_into_a_file(tmp_path):
    new = tmp_path / "new" / "s.h5"
    new.parent.mkdir()
    for i in range(3):
        commit_panel(new, i, *make_panel(i, 0), FILE_ATTRS)
    old = tmp_path / "old" / "s.h5"
    old.parent.mkdir()
    _as_format_1(new, old)
    assert sorted(old.parent.iterdir()) == [old]
    with h5py.File(old, "r") as f:
        assert not any(isinstance(f["panels"].get(n, getlink=True), h5py.ExternalLink) for n in f["panels"])
    s = read_store(old)
    assert s.attrs["format_version"] == 1 and sorted(s.panels) == [0, 1, 2]
    for i in range(3):
        assert_panel_equals(s.panels[i], i, 0)
    assert store.panel_hashes(old) == store.panel_hashes(new)
    rows = np.concatenate(list(store.iter_rows(old, 1, rows=100)))
    np.testing.assert_array_equal(rows, s.panels[1].crossings)
    created = s.attrs["created"]

    commit_panel(old, 1, *make_panel(1, 5), FILE_ATTRS)    # the first write converts the store
    s = read_store(old)
    assert s.attrs["format_version"] == store.FORMAT_VERSION == 2 and s.attrs["created"] == created
    assert_panel_equals(s.panels[0], 0, 0)
    assert_panel_equals(s.panels[1], 1, 5)
    assert_panel_equals(s.panels[2], 2, 0)
    with h5py.File(old, "r") as f:
        assert all(isinstance(f["panels"].get(n, getlink=True), h5py.ExternalLink) for n in f["panels"])
    assert_only_the_store(old.parent, old)
    assert old.stat().st_size <= STORE_FILE_BYTES


def test_update_panel_of_a_format_1_store_keeps_its_crossings(tmp_path):
    new = tmp_path / "new.h5"
    for i in range(2):
        commit_panel(new, i, *make_panel(i, 0), FILE_ATTRS)
    old = tmp_path / "old.h5"
    _as_format_1(new, old)
    store.update_panel(old, 0, {"megno": np.full(40, 3.0)}, {"indicators_hash": "y"})
    s = read_store(old)
    assert_panel_equals(s.panels[0], 0, 0)
    assert_panel_equals(s.panels[1], 1, 0)
    np.testing.assert_array_equal(s.panels[0].extra["megno"], 3.0)


def test_plain_h5py_reads_the_panels_through_the_store_file_from_anywhere(tmp_path, monkeypatch):
    """The external links are relative to the store's directory: the store reads with plain h5py
    from another working directory, and after the directory holding the store and its panel
    folder is moved."""
    path = tmp_path / "a" / "s.h5"
    path.parent.mkdir()
    arrays, _ = make_panel(0, 1)
    commit_panel(path, 0, *make_panel(0, 1), FILE_ATTRS)
    commit_panel(path, 1, *make_panel(1, 1), FILE_ATTRS)
    shutil.move(tmp_path / "a", tmp_path / "b")
    elsewhere = tmp_path / "cwd"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    with h5py.File(tmp_path / "b" / "s.h5", "r") as f:   # no explorer code below
        assert sorted(f["panels"]) == ["000", "001"]
        crossings, offsets = f["panels/000/crossings"][()], f["panels/000/offsets"][()]
        assert f["panels/000"].attrs["complete"]
    for i in range(len(arrays["count"])):
        np.testing.assert_array_equal(crossings[offsets[i]:offsets[i + 1]], arrays["data"][i, :arrays["count"][i]])
    assert_panel_equals(read_store(tmp_path / "b" / "s.h5").panels[1], 1, 1)


def test_a_missing_panel_file_is_named_and_counts_as_not_stored(tmp_path):
    path = tmp_path / "s.h5"
    for i in range(2):
        commit_panel(path, i, *make_panel(i, 0, n=3, k=2), FILE_ATTRS)
    with h5py.File(path, "r") as f:
        lost = f["panels"].get("001", getlink=True).filename
    os.remove(tmp_path / lost)
    with pytest.raises(StoreError, match=r"file of panel 1 .*missing"):
        read_store(path)
    assert set(store.panel_hashes(path)) == {0}       # a sweep recomputes panel 1
    assert set(store.panel_product_hashes(path)) == {0}
    commit_panel(path, 1, *make_panel(1, 2, n=3, k=2), FILE_ATTRS)
    assert_panel_equals(read_store(path).panels[1], 1, 2, n=3, k=2)


def test_unlinked_panel_files_of_dead_runs_are_cleaned_live_ones_kept(tmp_path):
    """A run killed between writing a panel file and replacing the store file leaves a file the
    store does not link: the next writer removes it (unless its process still runs)."""
    import subprocess
    import sys

    path = tmp_path / "s.h5"
    commit_panel(path, 0, *make_panel(0, 1, n=3, k=2), FILE_ATTRS)
    folder = tmp_path / "s.h5.panels"
    dead = folder / "001-999999999-abcd1234.h5"
    dead.write_bytes(b"half a panel")
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        live = folder / f"002-{sleeper.pid}-deadbeef.h5"
        live.write_bytes(b"in flight")
        assert store.clean_stale_temporaries(path) == [str(dead)]
        assert live.exists() and not dead.exists()
    finally:
        sleeper.kill()
        sleeper.wait()
    store.clean_stale_temporaries(path)
    assert_only_the_store(tmp_path, path)
    assert_panel_equals(read_store(path).panels[0], 0, 1, n=3, k=2)


def test_remove_store_and_a_fresh_commit_leave_no_panel_files_behind(tmp_path):
    path = tmp_path / "s.h5"
    for i in range(3):
        commit_panel(path, i, *make_panel(i, 0, n=3, k=2), FILE_ATTRS)
    commit_panel(path, 0, *make_panel(0, 7, n=3, k=2), FILE_ATTRS, fresh=True)
    assert sorted(read_store(path).panels) == [0]
    assert_only_the_store(tmp_path, path)
    store.remove_store(path)
    assert list(tmp_path.iterdir()) == []


def test_a_reader_racing_a_commit_that_replaces_a_panel_reads_again(tmp_path, monkeypatch):
    """A writer removes the panel file it replaces right after its commit; a reader that listed the
    old store's links just before reads the new store instead of failing."""
    from explorer.io.store import format as fmt

    path = tmp_path / "s.h5"
    for i in range(2):
        commit_panel(path, i, *make_panel(i, 0, n=3, k=2), FILE_ATTRS)
    links, calls = fmt.panel_links, []

    def racing(f):
        out = links(f)
        if not calls:
            calls.append(1)
            commit_panel(path, 1, *make_panel(1, 9, n=3, k=2), FILE_ATTRS)   # the old file of panel 1 goes
        return out

    monkeypatch.setattr(fmt, "panel_links", racing)
    s = read_store(path)
    assert calls and sorted(s.panels) == [0, 1]
    assert_panel_equals(s.panels[1], 1, 9, n=3, k=2)


def test_a_store_renamed_with_its_folder_still_reads_and_its_next_commit_relinks_it(tmp_path, monkeypatch):
    """The links name the folder ``<old name>.panels``; explorer finds the panel files in the
    renamed folder, cleaning removes none of them, and the next commit links them by their new
    place (then plain h5py reads it again)."""
    old = tmp_path / "old.h5"
    for i in range(2):
        commit_panel(old, i, *make_panel(i, 0, n=3, k=2), FILE_ATTRS)
    new = tmp_path / "new.h5"
    old.rename(new)
    (tmp_path / "old.h5.panels").rename(tmp_path / "new.h5.panels")
    monkeypatch.chdir(tmp_path)                      # a relative path to the store, too
    assert store.clean_stale_temporaries("new.h5") == []
    s = read_store("new.h5")
    assert sorted(s.panels) == [0, 1] and set(store.panel_hashes("new.h5")) == {0, 1}
    assert_panel_equals(s.panels[1], 1, 0, n=3, k=2)
    commit_panel("new.h5", 2, *make_panel(2, 0, n=3, k=2), FILE_ATTRS)
    assert_only_the_store(tmp_path, new)
    with h5py.File(new, "r") as f:
        assert f["panels/001"].attrs["complete"]
    assert_panel_equals(read_store(new).panels[0], 0, 0, n=3, k=2)
