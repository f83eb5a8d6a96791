"""Writing the store: provenance, and :func:`commit_panel`, the transaction that adds or
replaces one panel (a copy of the file is extended, fsynced and ``os.replace``'d onto the
old one; replacing a panel rebuilds the file without the old panel's bytes)."""
from __future__ import annotations

import os
import platform as _platform
import shutil
import subprocess
import sys

import h5py
import numpy as np

from explorer.io.store.atomic import atomic_path
from explorer.io.store.format import (
    _DEPENDENCIES,
    _OPTIONAL_PER_ORBIT,
    _PER_ORBIT,
    COLUMNS,
    COMPRESS_ROWS,
    DATASETS,
    FORMAT,
    FORMAT_VERSION,
    GZIP_LEVEL,
    INDICATOR_DATASETS,
    OPTIONAL_DATASETS,
    StoreError,
    _canonical_json,
    _open_store,
    _set_attrs,
    _utcnow,
    settings_hash,
)
from explorer.kernels import STATUS_NAMES

# --------------------------------------------------------------------------- provenance

def _git_revision(directory: str) -> str:
    env = dict(os.environ, GIT_OPTIONAL_LOCKS="0", LC_ALL="C")
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=directory, env=env,
                             capture_output=True, text=True, timeout=20)
        if rev.returncode != 0 or not rev.stdout.strip():
            return "unknown"
        revision = rev.stdout.strip()
        st = subprocess.run(["git", "status", "--porcelain"], cwd=directory, env=env,
                            capture_output=True, text=True, timeout=60)
        if st.returncode == 0 and st.stdout.strip():
            revision += "+dirty"
        return revision
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _version_of(name: str):
    if name == "explorer":
        from explorer import __version__
        return __version__
    from importlib import metadata
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def provenance(extra: dict | None = None) -> dict:
    """Where a result comes from: ``versions`` (explorer, numpy, numba, llvmlite,
    h5py, joblib, matplotlib, scipy if installed; read from package metadata,
    nothing is imported), ``python``, ``platform``, ``git_revision`` (``git
    rev-parse HEAD`` in the explorer package directory, ``+dirty`` if ``git
    status --porcelain`` is non-empty, ``"unknown"`` outside a git checkout),
    ``command_line`` (sys.argv), ``date`` (ISO 8601 UTC); plus ``extra``."""
    versions = {}
    for name in _DEPENDENCIES:
        v = _version_of(name)
        if v is not None or name != "scipy":
            versions[name] = v
    info = {
        "versions": versions,
        "python": sys.version.split()[0],
        "python_implementation": _platform.python_implementation(),
        "platform": _platform.platform(),
        "machine": _platform.machine(),
        "git_revision": _git_revision(os.path.dirname(os.path.abspath(__file__))),
        "command_line": list(sys.argv),
        "date": _utcnow(),
    }
    if extra:
        info.update(extra)
    return info


# --------------------------------------------------------------------------- writing

class RowSource:
    """Crossing rows that are written into the panel's ``crossings`` dataset piece by piece
    instead of being held in memory (a streamed panel, :mod:`explorer.io.store.stream`):
    ``fill(dataset)`` writes all ``total`` rows into the (total, 5) dataset created for them."""

    def __init__(self, total: int, fill):
        self.shape = (int(total), len(COLUMNS))
        self.ndim = 2
        self.fill = fill


def _ragged_from_padded(data, count):
    """(N, K, 5) NaN-padded rows + count -> (count, offsets, crossings).

    Rows k < count[i] are kept unless they contain NaN (padding); the returned
    count is the number of rows kept, so count == diff(offsets)."""
    data = np.asarray(data, dtype=np.float64)
    count = np.asarray(count).astype(np.int64, copy=False)
    if data.ndim != 3 or data.shape[2] != len(COLUMNS):
        raise ValueError(f"data must have shape (N, K, {len(COLUMNS)}), got {data.shape}")
    if count.shape != (data.shape[0],):
        raise ValueError(f"count must have shape ({data.shape[0]},), got {count.shape}")
    if np.any(count < 0):
        raise ValueError("count must be >= 0")
    mask = np.arange(data.shape[1])[None, :] < count[:, None]
    mask &= ~np.isnan(data).any(axis=2)
    crossings = np.ascontiguousarray(data[mask])
    kept = mask.sum(axis=1).astype(np.int64)
    offsets = np.zeros(data.shape[0] + 1, np.int64)
    np.cumsum(kept, out=offsets[1:])
    return kept, offsets, crossings


def _prepare_arrays(arrays: dict) -> dict:
    arrays = dict(arrays)
    if "data" in arrays:
        if "count" not in arrays:
            raise ValueError("arrays: 'data' needs 'count'")
        count, offsets, crossings = _ragged_from_padded(arrays.pop("data"), arrays["count"])
        arrays.update(count=count, offsets=offsets, crossings=crossings)
    missing = [d for d in DATASETS if d not in arrays]
    if missing:
        raise ValueError(f"arrays lacks {', '.join(missing)} (give offsets+crossings or data+count)")
    unknown = sorted(set(arrays) - set(DATASETS) - set(OPTIONAL_DATASETS))
    if unknown:
        raise ValueError(f"arrays has unknown entries {unknown}; the store holds only "
                         f"{list(DATASETS) + list(OPTIONAL_DATASETS)}")
    n = np.asarray(arrays["count"]).shape[0] if np.ndim(arrays["count"]) == 1 else -1
    if n < 0:
        raise ValueError("count must be one-dimensional")
    out = {}
    for name, (tail, dtype) in _PER_ORBIT.items():
        a = np.asarray(arrays[name])
        if a.shape != (n,) + tail:
            raise ValueError(f"{name} must have shape {(n,) + tail}, got {a.shape}")
        if dtype is np.int8 and a.size and (a.min() < -128 or a.max() > 127):
            raise ValueError("status codes must fit in int8")
        out[name] = np.ascontiguousarray(a, dtype=dtype)
    offsets = np.ascontiguousarray(arrays["offsets"], dtype=np.int64)
    crossings = arrays["crossings"]
    if not isinstance(crossings, RowSource):
        crossings = np.ascontiguousarray(crossings, dtype=np.float64)
    if crossings.ndim != 2 or crossings.shape[1] != len(COLUMNS):
        raise ValueError(f"crossings must have shape (total, {len(COLUMNS)}), got {crossings.shape}")
    if (offsets.shape != (n + 1,) or offsets[0] != 0 or np.any(np.diff(offsets) < 0)
            or offsets[-1] != crossings.shape[0]):
        raise ValueError("offsets must be (N+1,), start at 0, be non-decreasing and end at len(crossings)")
    if np.any(np.diff(offsets) != out["count"]):
        raise ValueError("count must equal diff(offsets)")
    out["offsets"] = offsets
    out["crossings"] = crossings
    out.update(_indicator_arrays(arrays, n))
    if ("separatrix_offsets" in arrays) != ("separatrix_points" in arrays):
        raise ValueError("separatrix_offsets and separatrix_points go together")
    if "separatrix_offsets" in arrays:
        so = np.ascontiguousarray(arrays["separatrix_offsets"], dtype=np.int64)
        sp = np.ascontiguousarray(arrays["separatrix_points"], dtype=np.float64).reshape(-1, 2)
        if so.ndim != 1 or so[0] != 0 or so[-1] != sp.shape[0] or np.any(np.diff(so) < 0):
            raise ValueError("separatrix_offsets must start at 0, be non-decreasing and end at len(points)")
        out["separatrix_offsets"] = so
        out["separatrix_points"] = sp
    return out


def _indicator_arrays(arrays: dict, n: int) -> dict:
    """The indicator datasets of ``arrays``, checked: one row per seed of ``lyapunov_seeds`` if
    given, else per orbit (``n``)."""
    out = {}
    if "lyapunov_seeds" in arrays:
        ls = np.ascontiguousarray(arrays["lyapunov_seeds"], dtype=np.float64)
        if ls.ndim != 2 or ls.shape[1] != 2:
            raise ValueError(f"lyapunov_seeds must have shape (M, 2), got {ls.shape}")
        out["lyapunov_seeds"] = ls
        n = ls.shape[0]
    for name, (tail, dtype) in _OPTIONAL_PER_ORBIT.items():
        if name in arrays:
            a = np.asarray(arrays[name])
            if a.shape != (n,) + tail:
                raise ValueError(f"{name} must have shape {(n,) + tail}, got {a.shape}")
            out[name] = np.ascontiguousarray(a, dtype=dtype)
    return out


def _create_dataset(grp, name: str, a):
    kw = {}
    if a.ndim >= 1 and a.shape[0] > COMPRESS_ROWS:
        row = int(np.prod(a.shape[1:], dtype=np.int64)) if a.ndim > 1 else 1
        rows = max(1, min(a.shape[0], (1 << 15) // row))
        kw = dict(chunks=(rows,) + a.shape[1:], compression="gzip", compression_opts=GZIP_LEVEL,
                  shuffle=True, fletcher32=True)
    if isinstance(a, RowSource):
        dset = grp.create_dataset(name, shape=a.shape, dtype=np.float64, **kw)
        a.fill(dset)
        return dset
    return grp.create_dataset(name, data=a, **kw)


def _write_panel(f, index: int, arrays: dict, attrs: dict, status_names: dict) -> None:
    panels = f.require_group("panels")
    name = f"{index:03d}"
    if name in panels:
        del panels[name]
    grp = panels.create_group(name)
    for d in DATASETS + OPTIONAL_DATASETS:
        if d in arrays:
            _create_dataset(grp, d, arrays[d])
    grp["status"].attrs["status_names"] = _canonical_json({str(int(k)): str(v) for k, v in status_names.items()})
    grp["crossings"].attrs["columns"] = np.array(COLUMNS, dtype=h5py.string_dtype())
    attrs = dict(attrs)
    attrs.pop("complete", None)
    for key in ("params", "settings"):
        if isinstance(attrs.get(key), dict):
            attrs[key] = _canonical_json(attrs[key])
    if attrs.get("hash") is None and attrs.get("settings") is not None:
        attrs["hash"] = settings_hash(attrs["settings"])
    attrs["index"] = int(index)
    _set_attrs(grp, attrs)
    grp.attrs["complete"] = True  # last: the panel is whole


def _copy_without_panel(src_path: str, dst_path: str, index: int) -> None:
    """Write to dst_path a compact copy of the store at src_path without panel ``index``:
    root attributes, every top-level object and every other panel group (datasets with their
    chunking, filters and attributes, via HDF5's object copy)."""
    skip = f"{index:03d}"
    with h5py.File(src_path, "r") as src, h5py.File(dst_path, "w") as dst:
        for key, value in src.attrs.items():
            dst.attrs[key] = value
        for name in src:
            if name != "panels":
                src.copy(src[name], dst, name=name)
        if "panels" in src:
            panels = dst.create_group("panels")
            for key, value in src["panels"].attrs.items():
                panels.attrs[key] = value
            for name in src["panels"]:
                if name != skip:
                    src.copy(src["panels"][name], panels, name=name)


def commit_panel(path, index: int, arrays: dict, attrs: dict, file_attrs: dict | None = None, *,
                 replace_corrupt: bool = False, status_names: dict | None = None) -> None:
    """Atomically add or replace panel ``index`` of the store at ``path``.

    ``arrays`` holds seeds, y0, count, status, final, info and either
    ``offsets`` + ``crossings`` or ``data`` (N, K, 5, NaN-padded) + ``count``
    (the ragged arrays are then built, padding dropped); ``crossings`` may be a
    :class:`RowSource` that writes the rows into the dataset piece by piece.  ``attrs`` are the
    panel attrs (``params``/``settings`` may be dicts: stored as JSON text;
    ``hash`` defaults to :func:`settings_hash` of the settings; ``index`` and
    ``complete = True`` are set here).  ``file_attrs`` (scene_name, scene,
    provenance, extras) are merged into the root attrs; ``format``,
    ``format_version``, ``created`` (kept from the existing file) and
    ``updated`` are managed here, and ``provenance`` is computed if neither the
    caller nor the existing file gives one.  ``status_names`` ({code: name})
    defaults to ``explorer.kernels.STATUS_NAMES``.

    ``path`` is never modified in place: the new file is built as
    ``<path>.tmp-<pid>-<random>`` (a copy of ``path`` if it exists), fsynced and
    ``os.replace``'d onto ``path``; the directory is then fsynced.

    Raises StoreError if ``path`` exists but is not a readable explorer store,
    unless ``replace_corrupt=True`` (a fresh file then replaces it).
    """
    path = os.fspath(path)
    index = int(index)
    if index < 0:
        raise ValueError(f"panel index must be >= 0, got {index}")
    prepared = _prepare_arrays(arrays)
    file_attrs = dict(file_attrs or {})
    for key in ("format", "format_version", "created", "updated"):
        file_attrs.pop(key, None)
    if isinstance(file_attrs.get("provenance"), dict):
        file_attrs["provenance"] = _canonical_json(file_attrs["provenance"])

    existing = os.path.exists(path)
    replacing = False
    if existing:
        try:
            with _open_store(path) as f:
                replacing = "panels" in f and f"{index:03d}" in f["panels"]
        except StoreError:
            if not replace_corrupt:
                raise
            existing = False

    with atomic_path(path) as tmp:
        if replacing:
            # replacing a panel: copy everything else into a fresh file, so the file does not
            # keep the old panel's bytes (HDF5 never reclaims the space of a deleted group)
            _copy_without_panel(path, tmp, index)
        elif existing:
            shutil.copyfile(path, tmp)
        with h5py.File(tmp, "r+" if existing else "w") as f:
            now = _utcnow()
            if "created" not in f.attrs:
                f.attrs["created"] = now
            if "provenance" not in file_attrs and "provenance" not in f.attrs:
                file_attrs["provenance"] = _canonical_json(provenance())
            f.attrs["format"] = FORMAT
            f.attrs["format_version"] = FORMAT_VERSION
            _set_attrs(f, file_attrs)
            f.attrs["updated"] = now
            _write_panel(f, index, prepared, attrs or {},
                         STATUS_NAMES if status_names is None else status_names)



def update_panel_attrs(path, index: int, attrs: dict) -> None:
    """Atomically set attributes of an existing panel (the data are not touched): a copy of
    the store is changed, fsynced and ``os.replace``'d onto ``path``, as in
    :func:`commit_panel`.  Used when a setting outside the panel hash changes a derived
    attribute (the MEGNO threshold -> ``chaotic_fraction``)."""
    path = os.fspath(path)
    index = int(index)
    with _open_store(path) as f:
        if "panels" not in f or f"{index:03d}" not in f["panels"]:
            raise StoreError(f"{path}: no panel {index} to update")
    with atomic_path(path) as tmp:
        shutil.copyfile(path, tmp)
        with h5py.File(tmp, "r+") as f:
            _set_attrs(f["panels"][f"{index:03d}"], attrs)
            f.attrs["updated"] = _utcnow()


def update_panel(path, index: int, arrays: dict, attrs: dict, *, remove=()) -> None:
    """Atomically replace or add indicator datasets (``megno``, ..., ``lyapunov_seeds``: the
    indicators product) and attributes of the stored panel ``index``, keeping its other datasets
    (the crossings are not read into memory); ``remove``: datasets and attributes to delete.  As
    :func:`commit_panel`, the file is rebuilt in a temporary copy without the old bytes, fsynced and
    ``os.replace``'d onto ``path``."""
    path = os.fspath(path)
    index = int(index)
    name = f"{index:03d}"
    unknown = sorted(set(arrays) - set(INDICATOR_DATASETS))
    if unknown:
        raise ValueError(f"update_panel replaces only {list(INDICATOR_DATASETS)}, got {unknown}")
    with _open_store(path) as f:
        if "panels" not in f or name not in f["panels"]:
            raise StoreError(f"{path}: no panel {index} to update")
        grp = f["panels"][name]
        kept_seeds = "lyapunov_seeds" in grp and "lyapunov_seeds" not in remove
        n = grp["lyapunov_seeds" if kept_seeds else "count"].shape[0]   # rows of the indicator datasets
    prepared = _indicator_arrays(arrays, n)
    with atomic_path(path) as tmp:
        _copy_without_panel(path, tmp, index)
        with h5py.File(path, "r") as src, h5py.File(tmp, "r+") as dst:
            old = src["panels"][name]
            grp = dst.require_group("panels").create_group(name)
            for d in old:
                if d not in prepared and d not in remove:
                    src.copy(old[d], grp, name=d)
            for d, a in prepared.items():
                _create_dataset(grp, d, a)
            for k, v in old.attrs.items():
                if k not in remove and k not in attrs and k != "complete":
                    grp.attrs[k] = v
            _set_attrs(grp, attrs)
            grp.attrs["complete"] = True  # last: the panel is whole
            dst.attrs["updated"] = _utcnow()
