"""The ``orbit`` command's two ways of handing out crossings as they are computed: rows printed
block by block (CSV or JSON), or a store written block by block that a rerun resumes after a
kill.  Memory is O(one block) either way, whatever the number of crossings asked
(:func:`explorer.analysis.sections.iter_crossings`)."""
from __future__ import annotations

import json
import os
import sys
import time
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis import sections
from explorer.app.interrupt import Interrupted, deferred_interrupt
from explorer.kernels import STATUS_NAMES
from explorer.model import ParameterError


@dataclass(frozen=True)
class OrbitReport:
    """What a streamed orbit did: crossings found, why it stopped, the largest |H - H0| of its
    crossings, blocks computed (``resumed_blocks`` of them in an earlier, interrupted run)."""

    crossings: int
    status: str
    max_dh: float
    blocks: int
    resumed_blocks: int = 0
    out: str | None = None
    settings: dict | None = None
    already_complete: bool = False


def _start(params, p1, p2, h, kw):
    """The start state on the section, as sections.crossings makes it from a section point (M from the energy,
    its sign from the crossing direction)."""
    direction = kw.get("direction", 1)
    return model.section_state(params, [p1], [p2], h, kw.get("phi0", np.pi), direction if direction != 0 else 1)


def check_request(params, p1, p2, h, n_crossings, **kw) -> None:
    """Validate a request of :func:`print_rows` / :func:`to_store` without running it
    (ParameterError naming the parameter otherwise)."""
    sections.crossing_settings(params, _start(params, p1, p2, h, kw), n_crossings=n_crossings, **kw)


def _identity(params, h, p1, p2, y0, settings) -> dict:
    return {"kind": "orbit", "params": params.as_dict(), "h": float(h), "seeds": [[float(p1), float(p2)]],
            "y0": [float(v) for v in y0[0]], "settings": settings}


def print_rows(params, p1, p2, h, n_crossings, *, as_json=False, block=sections.DEFAULT_BLOCK, file=None,
               **kw) -> OrbitReport:
    """Print the crossings of one orbit as they come, block after block: CSV ``k,t,p1,p2,M,dH``
    or one JSON object (``{"params", "h", "method", "settings", "crossings": [...], "status"}``)."""
    out = sys.stdout if file is None else file
    y0 = _start(params, p1, p2, h, kw)
    settings = sections.crossing_settings(params, y0, n_crossings=n_crossings, **kw)
    it = sections.iter_crossings(params, states=y0, n_crossings=n_crossings, block=block, **kw)
    if as_json:
        head = {"params": params.as_dict(), "h": h, "method": settings["method"], "settings": settings}
        out.write(json.dumps(head)[:-1] + ', "crossings": [')
    else:
        out.write("k,t,p1,p2,M,dH\n")
    k = 0
    max_dh = 0.0
    st = None
    for b in it:
        rows = b.rows(0) if b.count.size else np.zeros((0, 5))
        max_dh = max(max_dh, sections.max_energy_error(rows))
        if as_json:
            text = json.dumps(rows.tolist())[1:-1]   # the C encoder: floats as repr, as json.dumps writes them
            out.write((", " if k and text else "") + text)
        else:
            out.write("".join(f"{k + i + 1},{r[0]!r},{r[1]!r},{r[2]!r},{r[3]!r},{r[4]!r}\n"
                              for i, r in enumerate(rows.tolist())))
        k += len(rows)
        st = b.state
    status = STATUS_NAMES[int(st.status[0])] if st is not None else "done"
    if as_json:
        out.write(f'], "status": {json.dumps(status)}}}\n')
    out.flush()
    return OrbitReport(k, status, max_dh, st.blocks if st is not None else 0, settings=settings)


def to_store(path, params, p1, p2, h, n_crossings, *, block=sections.DEFAULT_BLOCK, force=False,
             on_block=None, **kw) -> OrbitReport:
    """Stream the crossings of one orbit into the one-panel store at ``path``, block by block; a
    rerun after a kill continues to the file of an uninterrupted run, and a store that holds this
    run is left alone (docs/commands/orbit.md).  ParameterError when the disk may not suffice or
    ``path`` holds another run (without ``force``)."""
    from explorer.io import store  # h5py only for a run that writes a store

    path = os.fspath(path)
    store.check_writable(os.path.dirname(os.path.abspath(path)), "--out", path)
    with deferred_interrupt() as stop, store.writing(path):
        return _to_store(path, params, p1, p2, h, n_crossings, block, force, on_block, stop, kw)


def _to_store(path, params, p1, p2, h, n_crossings, block, force, on_block, stop, kw) -> OrbitReport:
    """:func:`to_store` with the store locked and Ctrl-C deferred to ``stop.check()`` (between blocks)."""
    from explorer.io import store
    from explorer.io.store import stream

    phi0 = kw.get("phi0", np.pi)
    y0 = _start(params, p1, p2, h, kw)
    settings = sections.crossing_settings(params, y0, n_crossings=n_crossings, **kw)
    blocks = stream.BlockStream(path, _identity(params, h, p1, p2, y0, settings))
    if blocks.complete() and not force:
        blocks.discard()     # blocks of an interrupted --force rerun of a finished run: stale
        data = store.read_store(path).panels[0]
        return OrbitReport(int(data.count.sum()), STATUS_NAMES[int(data.status[0])],
                           sections.max_energy_error(data.crossings), int(data.attrs.get("blocks", 0)),
                           int(data.attrs.get("resumed_blocks", 0)), path, settings, True)
    if os.path.exists(path) and not force and not os.path.isdir(stream.blocks_dir(path)):
        raise ParameterError(f"{path} exists and holds another run; use --force to overwrite it or choose "
                             "another --out")
    need = stream.disk_needed(1, n_crossings)
    store.check_disk(os.path.dirname(os.path.abspath(path)), need,
                     f"crossings: {n_crossings} crossings ({sections.human_bytes(need / 2)} of rows, twice while "
                     "the store is written)")
    state, resumed = blocks.resume_state(params, y0, phi0=phi0, force=force)
    t0 = time.perf_counter()
    st = state
    for b in sections.iter_crossings(params, states=y0, n_crossings=n_crossings, block=block, state=state, **kw):
        blocks.append(b.state.blocks, b.index, b.start, b.count, b.data, [0], b.state.as_arrays())
        st = b.state
        if on_block is not None:
            on_block(b)
        if stop.requested:
            raise Interrupted(f"{st.blocks} blocks stored in {blocks.dir}; the same command continues from there")
    wall = time.perf_counter() - t0
    attrs = store.PanelAttrs(0, "orbit", float(h), params.as_dict(), settings, hash=blocks.hash).attrs()
    attrs.update(store.PanelAttrs.section_run(method=settings["method"], tol=settings.get("tol", np.nan),
                                              dt=settings.get("dt", np.nan), phi0=settings["phi0"],
                                              direction=settings["direction"], crossings=n_crossings, wall_time=wall),
                 block=int(block), blocks=int(st.blocks), resumed_blocks=int(resumed))
    result = {"count": st.done, "status": st.status, "final": st.y, "info": st.info}
    store.write_panel(path, 0, attrs, [[p1, p2]], y0, result, blocks=blocks, fresh=force,
                      file_attrs=store.file_attrs("orbit", json.dumps(blocks.identity, sort_keys=True),
                                                  {"command": "orbit"}))
    return OrbitReport(int(st.done[0]), STATUS_NAMES[int(st.status[0])], blocks.max_dh, int(st.blocks), resumed, path,
                       settings)
