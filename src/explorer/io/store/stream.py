"""Streamed panels: the crossings of a long run written block by block into ``<path>.blocks/``,
each block atomically, resumable after a kill to the numbers of an uninterrupted run, then
committed as one panel (docs/store.md, "Streamed panels").  Memory is O(one block)."""
from __future__ import annotations

import json
import os
import re
import shutil

import numpy as np

from explorer.io.store.atomic import atomic_path, write_bytes_atomic
from explorer.io.store.commit import RowSource, commit_panel
from explorer.io.store.format import COLUMNS, StoreError, _canonical_json, panel_hashes, settings_hash

#: arrays of a block file besides the state
BLOCK_ARRAYS = ("index", "start", "count", "rows")
#: the per-orbit state arrays stored with each block for the orbits it covers
#: (sections.StreamState.as_arrays), and the run's block counter
STATE_ARRAYS = ("y", "carry", "done", "finished", "status", "info")
_BLOCK_NAME = re.compile(r"^(\d{6})\.npz$")
ROW_BYTES = 8 * len(COLUMNS)
_DH = COLUMNS.index("dH")


def blocks_dir(path, index: int | None = None) -> str:
    """The directory of the blocks of a store being streamed (``index``: of that panel of a
    store of several panels)."""
    return os.fspath(path) + (".blocks" if index is None else f".panel{int(index):03d}.blocks")


def panel_block_dirs(path) -> dict:
    """{panel index: directory} of the block folders ``<path>.panel<NNN>.blocks`` beside the store."""
    import glob

    base = os.fspath(path) + ".panel"
    out = {}
    for d in glob.glob(glob.escape(base) + "*.blocks"):
        number = d[len(base):-len(".blocks")]
        if number.isdigit() and os.path.isdir(d):
            out[int(number)] = d
    return out


def remove_stale_blocks(path, keep=()) -> list:
    """Remove the block folders of the panels of the store at ``path`` that are not in ``keep`` (a
    finished, replaced or no longer streamed panel: nothing will resume from them); returns them."""
    removed = []
    for index, d in sorted(panel_block_dirs(path).items()):
        if index not in keep:
            shutil.rmtree(d, ignore_errors=True)
            removed.append(d)
    return removed


def disk_needed(n_orbits: int, n_crossings: int) -> int:
    """Bytes a streamed run of ``n_orbits`` x ``n_crossings`` rows may need on disk at its peak:
    its uncompressed blocks plus the store being written from them."""
    return 2 * int(n_orbits) * int(n_crossings) * ROW_BYTES


class BlockStream:
    """The blocks of one streamed panel of the store at ``path``; ``identity`` is everything that
    determines the run's numbers, so the same command continues the run and another is refused."""

    def __init__(self, path, identity: dict, *, index: int | None = None):
        self.path = os.fspath(path)
        self.index = 0 if index is None else int(index)
        self.dir = blocks_dir(self.path, index)
        self.identity = json.loads(_canonical_json(identity))
        self.hash = settings_hash(self.identity)
        #: largest |dH| of the rows of the stored blocks (kept with each block, so a resumed run
        #: knows it without reading the rows again)
        self.max_dh = 0.0

    def _block_files(self) -> list[tuple[int, str]]:
        if not os.path.isdir(self.dir):
            return []
        out = []
        for name in os.listdir(self.dir):
            m = _BLOCK_NAME.match(name)
            if m:
                out.append((int(m.group(1)), os.path.join(self.dir, name)))
        return sorted(out)

    def complete(self) -> bool:
        """The store at ``path`` already holds this run, whole (its panel hash is this run's)."""
        try:
            return panel_hashes(self.path).get(self.index) == self.hash
        except StoreError:
            return False

    def resume_state(self, params, y0, *, phi0: float, force: bool = False, initial=None):
        """The StreamState the run of ``y0`` continues from (:meth:`resume`) and the number of blocks
        stored; blocks of another run (without ``force``) are a ParameterError.  ``initial``: the run's
        state before its first block (default Chaplygin's, of ``params`` at ``phi0``)."""
        from explorer.analysis import sections
        from explorer.model import ParameterError

        if initial is None:
            initial = sections.StreamState.initial(params, y0, phi0=phi0)
        try:
            saved, n = self.resume(initial.as_arrays(), force=force)
        except StoreError as exc:
            raise ParameterError(str(exc)) from None
        return sections.StreamState.from_arrays(dict(saved, blocks=n)), n

    def resume(self, initial: dict, *, force: bool = False) -> tuple[dict, int]:
        """Prepare the blocks directory and return (state arrays, blocks stored): ``initial`` with every
        stored block's state applied in order.  Blocks of another run are a StoreError unless ``force``
        (then removed); block numbers must run 1, 2, ... without a gap."""
        run_file = os.path.join(self.dir, "run.json")
        if os.path.isdir(self.dir):
            try:
                with open(run_file, encoding="utf-8") as f:
                    on_disk = json.load(f)
                same = on_disk.get("hash") == self.hash
            except (OSError, ValueError):
                same = False
            if not same:
                if not force:
                    raise StoreError(f"{self.dir} holds the blocks of another run (or is damaged); "
                                     "use --force to discard them or choose another --out")
                shutil.rmtree(self.dir)
        state = {a: np.array(initial[a]) for a in STATE_ARRAYS}
        if not os.path.isdir(self.dir):
            os.makedirs(self.dir)
            write_bytes_atomic(run_file, json.dumps({"hash": self.hash, "identity": self.identity},
                                                    sort_keys=True).encode())
            return state, 0
        for name in os.listdir(self.dir):   # temporaries of a block being written when killed
            if name != "run.json" and not _BLOCK_NAME.match(name):
                os.remove(os.path.join(self.dir, name))
        files = self._block_files()
        numbers = [k for k, _ in files]
        if numbers != list(range(1, len(files) + 1)):
            raise StoreError(f"{self.dir}: blocks {numbers[:5]}... do not follow each other; "
                             "use --force to start again")
        for _, name in files:
            try:
                with np.load(name) as z:
                    orbits = z["orbits"]
                    for a in STATE_ARRAYS:
                        state[a][orbits] = z[a]
                    self.max_dh = max(self.max_dh, float(z["max_dh"]))
            except Exception as exc:  # a damaged block cannot come from a kill (atomic writes)
                raise StoreError(f"{name}: unreadable block ({exc}); use --force to start again") from None
        return state, len(files)

    def append(self, number: int, index, start, count, data, orbits, state: dict) -> None:
        """Store block ``number`` (1, 2, ...) atomically: ``data[i, :count[i]]`` are the new rows of
        orbit ``index[i]``, ``state`` the state arrays after it of the orbits ``orbits``."""
        count = np.asarray(count, np.int64)
        rows = np.concatenate([data[i, : count[i]] for i in range(len(count))]) if len(count) else \
            np.zeros((0, len(COLUMNS)))
        arrays = {"index": np.asarray(index, np.int64), "start": np.asarray(start, np.int64), "count": count,
                  "rows": np.ascontiguousarray(rows, dtype=np.float64)}
        arrays.update({a: np.asarray(state[a]) for a in STATE_ARRAYS})
        arrays["orbits"] = np.asarray(orbits, np.int64)
        dh = float(np.max(np.abs(rows[:, _DH]))) if len(rows) else 0.0
        arrays["max_dh"] = np.array(dh)
        # written straight to the temporary file (no copy of the rows in memory), then renamed
        with atomic_path(os.path.join(self.dir, f"{int(number):06d}.npz")) as tmp:
            np.savez(tmp, **arrays)
        self.max_dh = max(self.max_dh, dh)

    def _fill(self, offsets):
        def fill(dset):
            for _, name in self._block_files():
                with np.load(name) as z:
                    index, start, count, rows = (z[a] for a in BLOCK_ARRAYS)
                pos = 0
                for j, s, c in zip(index, start, count):
                    if c:
                        lo = offsets[j] + s
                        dset[lo: lo + c] = rows[pos: pos + c]
                    pos += c
        return fill

    def finish(self, arrays: dict, attrs: dict, file_attrs: dict | None = None, *, fresh: bool = False) -> None:
        """Write the panel of the store from the blocks, atomically, and remove them.

        ``arrays``: the per-orbit datasets (seeds, y0, count, status, final, info, and optional
        ones); the rows come from the blocks.  ``attrs['hash']`` defaults to this run's hash;
        ``fresh``: the store becomes this one panel."""
        count = np.asarray(arrays["count"], np.int64)
        offsets = np.zeros(count.size + 1, np.int64)
        np.cumsum(count, out=offsets[1:])
        payload = dict(arrays, offsets=offsets, crossings=RowSource(int(offsets[-1]), self._fill(offsets)))
        attrs = dict(attrs)
        attrs.setdefault("hash", self.hash)
        commit_panel(self.path, self.index, payload, attrs, file_attrs, fresh=fresh)
        self.discard()

    def discard(self) -> None:
        """Remove the blocks directory (after the store holds the run, or to start again)."""
        shutil.rmtree(self.dir, ignore_errors=True)


class PanelStreams:
    """The sweep's ``streamer`` (:func:`explorer.analysis.sweep.run`): one :class:`BlockStream` per
    streamed panel, identified by the panel's hash so a killed sweep resumes it; ``force``: stored
    blocks are discarded."""

    def __init__(self, out, hashes, phi0: float, force: bool):
        self.out, self.hashes, self.phi0, self.force = out, hashes, phi0, force
        self.streams: dict = {}
        #: {panel index: blocks stored by an earlier run}
        self.resumed: dict = {}

    def resume(self, panel, initial=None):
        """The state ``panel`` continues from (blocks of another setting are stale: removed);
        ``initial``: its state before the first block (:meth:`BlockStream.resume_state`)."""
        bs = BlockStream(self.out, {"panel_hash": self.hashes[panel.index]}, index=panel.index)
        if self.force:
            bs.discard()
        state, n = bs.resume_state(panel.P, panel.y0, phi0=self.phi0, force=True, initial=initial)
        self.streams[panel.index] = bs
        self.resumed[panel.index] = n
        return state

    def block(self, panel, number, index, start, count, data, orbits, state):
        """Store block ``number`` of ``panel`` (:meth:`BlockStream.append`)."""
        self.streams[panel.index].append(number, index, start, count, data, orbits, state)

    def take(self, index: int) -> BlockStream:
        """The stream of panel ``index``, finished by the caller (:func:`~explorer.io.store.write_panel`)."""
        return self.streams.pop(index)
