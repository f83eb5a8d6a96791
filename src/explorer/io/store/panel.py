"""The one writer of a computed panel, shared by ``orbit --out`` and the sweep (docs/store.md).

:func:`writing` holds a store for a run; :func:`write_panel` commits one panel of section runs in
one atomic transaction, its rows given whole or read from the blocks of a streamed run.
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil

import numpy as np

from explorer.io.store.commit import clean_stale_temporaries, commit_panel, provenance
from explorer.io.store.format import COLUMNS
from explorer.io.store.lock import StoreBusy, store_lock
from explorer.model import ParameterError

#: the per-orbit datasets of every panel (docs/store.md, "Layout")
ORBIT_DATASETS = ("count", "status", "final", "info")


@contextlib.contextmanager
def writing(path):
    """Hold the store at ``path`` for one run: its lock, and what killed runs left beside it
    removed.  A store another process writes is a ParameterError naming the holder."""
    try:
        with store_lock(path):
            clean_stale_temporaries(path)
            yield
    except StoreBusy as exc:
        raise ParameterError(str(exc)) from None


def check_disk(directory, need: int, what: str, hint: str = "") -> None:
    """Refuse (ParameterError) a run that may need ``need`` bytes where ``directory`` has less
    free; ``what`` says what needs them, ``hint`` which setting to lower."""
    from explorer.analysis.sections import human_bytes

    os.makedirs(directory, exist_ok=True)
    free = shutil.disk_usage(directory).free
    if need > free:
        raise ParameterError(f"{what} may need {human_bytes(need)} on disk; {human_bytes(free)} free in {directory}"
                             + (f"; {hint}" if hint else ""))


def file_attrs(scene_name: str, scene: str, origin: dict) -> dict:
    """The store file's attributes: the scene's name and text, and the provenance of the run
    (``origin``: what made it, e.g. ``{"command": "orbit"}``)."""
    return {"scene_name": scene_name, "scene": scene,
            "provenance": json.dumps(provenance(origin), sort_keys=True)}


def write_panel(path, index: int, attrs: dict, seeds, y0, result: dict, *, rows=None, blocks=None,
                extra: dict | None = None, file_attrs: dict | None = None, fresh: bool = False) -> float:
    """Commit panel ``index`` of the store at ``path`` in one transaction (a kill at any instant
    leaves the old store or the new one).

    ``seeds`` (N, 2) and ``y0`` (N, 5): the orbits' starts; ``result``: their
    :data:`ORBIT_DATASETS`; the crossings either ``rows`` ((N, K, 5), NaN past each orbit's
    count) or the stored blocks of ``blocks`` (a :class:`~explorer.io.store.stream.BlockStream`,
    removed once committed); ``extra``: further
    datasets (indicators, separatrices); ``attrs``: the panel's attributes (:class:`PanelAttrs`);
    ``fresh``: the store becomes this one panel.  Returns the largest ``|H - H0|`` of the rows."""
    payload = {"seeds": np.asarray(seeds, float), "y0": np.asarray(y0, float)}
    payload.update({k: result[k] for k in ORBIT_DATASETS})
    payload.update(extra or {})
    if blocks is not None:
        blocks.finish(payload, attrs, file_attrs, fresh=fresh)
        return blocks.max_dh
    payload["data"] = rows
    commit_panel(path, index, payload, attrs, file_attrs, fresh=fresh)
    dh = np.abs(np.asarray(rows, dtype=np.float64)[..., COLUMNS.index("dH")])
    dh = dh[np.isfinite(dh)]
    return float(dh.max()) if dh.size else 0.0
