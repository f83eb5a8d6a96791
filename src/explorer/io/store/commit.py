"""Writing the store: provenance, and :func:`commit_panel`, the transaction that adds or
replaces one panel at the cost of that panel (docs/store.md, "Committing a panel")."""
from __future__ import annotations

import os
import platform as _platform
import secrets
import shutil
import subprocess
import sys

import h5py
import numpy as np

from explorer.io.store.atomic import _fsync_dir, _fsync_path, _pid_alive, _remove_quietly, atomic_path
from explorer.io.store.atomic import clean_stale_temporaries as _clean_temporaries
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
    PANELS_SUFFIX,
    StoreError,
    _canonical_json,
    _open_store,
    _panel_group,
    _set_attrs,
    _utcnow,
    panel_file,
    panel_links,
    panels_dir,
    settings_hash,
)
from explorer.kernels import STATUS_NAMES


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
    """Where a result comes from: package ``versions`` (from metadata), ``python``, ``platform``,
    ``git_revision`` (``+dirty`` when modified), ``command_line``, ``date``; plus
    ``extra``."""
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


class RowSource:
    """Crossing rows written into the ``crossings`` dataset piece by piece, not held in memory:
    ``fill(dataset)`` writes all ``total`` rows."""

    def __init__(self, total: int, fill):
        self.shape = (int(total), len(COLUMNS))
        self.ndim = 2
        self.fill = fill


def _ragged_from_padded(data, count):
    """(N, K, 5) NaN-padded rows + count -> (count, offsets, crossings); rows with NaN are dropped,
    so count == diff(offsets)."""
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
        if a.ndim != 1 + len(tail) or a.shape[0] != n or any(t >= 0 and s != t for s, t in zip(a.shape[1:], tail)):
            raise ValueError(f"{name} must have shape {(n,) + tail} (-1: any width), got {a.shape}")
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


def _fill_panel(grp, index: int, arrays: dict, attrs: dict, status_names: dict) -> None:
    """Write panel ``index`` (its datasets and attributes, ``complete`` last) into the empty group ``grp``."""
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


def _copy_panel(src, dst, *, skip=(), attrs: dict | None = None) -> None:
    """Copy the panel group ``src`` into the empty group ``dst`` by HDF5's object copy (rows not
    read), datasets and attributes except ``skip``, then set ``attrs``; ``complete`` last."""
    for d in src:
        if d not in skip:
            src.copy(src[d], dst, name=d)
    for k, v in src.attrs.items():
        if k not in skip and k != "complete":
            dst.attrs[k] = v
    _set_attrs(dst, attrs or {})
    dst.attrs["complete"] = True  # last: the panel is whole


def _store_dir(path: str) -> str:
    return os.path.dirname(os.path.abspath(path))


def _new_panel_file(path: str, index: int, write, written: list) -> str:
    """Write a new, uniquely named panel file for panel ``index`` (``write(root group)``), fsynced;
    returns its name relative to the store's directory, also appended to ``written``."""
    name = f"{os.path.basename(path)}{PANELS_SUFFIX}/{index:03d}-{os.getpid()}-{secrets.token_hex(4)}.h5"
    full = os.path.join(_store_dir(path), name)
    written.append(full)
    with h5py.File(full, "w") as f:
        write(f)
    _fsync_path(full)
    return name


def _write_top(tmp: str, old, links: dict, file_attrs: dict) -> None:
    """The store file at ``tmp``: the root attributes of ``old`` (the open store, or None) updated
    by ``file_attrs`` and the managed ones, and one external link ``/panels/NNN`` per panel."""
    with h5py.File(tmp, "w") as f:
        panels = f.create_group("panels")
        if old is not None:
            for key, value in old.attrs.items():
                f.attrs[key] = value
            if "panels" in old:
                for key, value in old["panels"].attrs.items():
                    panels.attrs[key] = value
        now = _utcnow()
        if "created" not in f.attrs:
            f.attrs["created"] = now
        if "provenance" not in file_attrs and "provenance" not in f.attrs:
            file_attrs = dict(file_attrs, provenance=_canonical_json(provenance()))
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        _set_attrs(f, file_attrs)
        f.attrs["updated"] = now
        for idx in sorted(links):
            panels[f"{idx:03d}"] = h5py.ExternalLink(links[idx], "/")


def _linked_files(path: str) -> dict:
    """{index: absolute path of its panel file} of the store at ``path`` ({} if there is none or it
    cannot be read)."""
    try:
        f = _open_store(path)
    except StoreError:
        return {}
    with f:
        found = {i: panel_file(path, t) for i, t in panel_links(f).items() if t is not None}
    return {i: name for i, name in found.items() if name is not None}


def _transaction(path, index: int, write, file_attrs: dict | None = None, *, fresh: bool = False,
                 replace_corrupt: bool = False, existing_panel: bool = False) -> None:
    """The one way a store changes (docs/store.md): ``write(new group, old group or None)`` fills a
    new panel file, then a new store file linking it replaces ``path`` (the commit point) and the
    superseded panel file is removed.  ``fresh``: the store becomes this one panel;
    ``existing_panel``: the panel must be stored already."""
    path = os.fspath(path)
    superseded = _linked_files(path) if fresh else {}
    old = None
    if os.path.exists(path) and not fresh:
        try:
            old = _open_store(path)
        except StoreError:
            if not replace_corrupt:
                raise
    written: list = []
    try:
        links = panel_links(old) if old is not None else {}
        if existing_panel and index not in links:
            raise StoreError(f"{path}: no panel {index} to update")
        old_grp = _panel_group(old, path, index, missing="skip", links=links) if index in links else None
        if existing_panel and old_grp is None:
            _panel_group(old, path, index, links=links)   # raises: the panel's file is missing
        os.makedirs(panels_dir(path), exist_ok=True)
        new = {}
        for idx, target in links.items():
            if idx != index and target is None:   # format 1: the panel moves into a file of its own
                grp = _panel_group(old, path, idx, links=links)
                new[idx] = _new_panel_file(path, idx, lambda f, grp=grp: _copy_panel(grp, f), written)
            elif idx != index and os.path.dirname(target) == os.path.basename(panels_dir(path)):
                new[idx] = target    # kept
            elif idx != index:       # kept, named in this store's folder (the store and folder were renamed)
                found = panel_file(path, target)
                new[idx] = target if found is None else os.path.relpath(found, _store_dir(path))
        new[index] = _new_panel_file(path, index, lambda f: write(f, old_grp), written)
        _fsync_dir(panels_dir(path))
        with atomic_path(path) as tmp:
            _write_top(tmp, old, new, file_attrs or {})
    except BaseException:
        for name in written:
            _remove_quietly(name)
        raise
    finally:
        if old is not None:
            old.close()
    replaced = panel_file(path, links[index]) if links.get(index) is not None else None
    if replaced is not None:
        superseded[index] = replaced
    own = os.path.normpath(panels_dir(os.path.abspath(path)))
    for name in superseded.values():   # only files of this store's folder (a copied store file links another's)
        if os.path.dirname(os.path.normpath(name)) == own:
            _remove_quietly(name)


def commit_panel(path, index: int, arrays: dict, attrs: dict, file_attrs: dict | None = None, *,
                 replace_corrupt: bool = False, status_names: dict | None = None, fresh: bool = False) -> None:
    """Atomically add or replace panel ``index`` of the store at ``path`` (docs/store.md, "Committing
    a panel"): the panel goes into a new file of the panel folder, then a new store file linking it
    replaces ``path``; the cost is the panel plus the small store file.

    ``arrays``: seeds, y0, count, status, final, info and either ``offsets`` + ``crossings`` (maybe a
    :class:`RowSource`) or ``data`` ((N, K, 5), NaN-padded); ``attrs``: the panel's attributes
    (``hash`` defaults to :func:`settings_hash` of ``settings``); ``file_attrs``: merged into the
    root's (``format``, ``created``, ``updated`` are managed here, ``provenance`` computed when
    absent); ``fresh``: the store becomes this one panel.  A ``path`` that is not a store is a
    StoreError unless ``replace_corrupt``."""
    index = int(index)
    if index < 0:
        raise ValueError(f"panel index must be >= 0, got {index}")
    prepared = _prepare_arrays(arrays)
    file_attrs = dict(file_attrs or {})
    for key in ("format", "format_version", "created", "updated"):
        file_attrs.pop(key, None)
    if isinstance(file_attrs.get("provenance"), dict):
        file_attrs["provenance"] = _canonical_json(file_attrs["provenance"])
    names = STATUS_NAMES if status_names is None else status_names
    _transaction(path, index, lambda grp, old: _fill_panel(grp, index, prepared, attrs or {}, names), file_attrs,
                 fresh=fresh, replace_corrupt=replace_corrupt)


def update_panel_attrs(path, index: int, attrs: dict) -> None:
    """Atomically set attributes of an existing panel (its datasets copied unchanged, as in
    :func:`commit_panel`)."""
    _transaction(path, int(index), lambda grp, old: _copy_panel(old, grp, attrs=attrs), existing_panel=True)


def update_panel(path, index: int, arrays: dict, attrs: dict, *, remove=()) -> None:
    """Atomically replace or add the indicator datasets and attributes of stored panel ``index``,
    its other datasets copied by HDF5 (not read); ``remove``: datasets and attributes to delete."""
    path = os.fspath(path)
    index = int(index)
    unknown = sorted(set(arrays) - set(INDICATOR_DATASETS))
    if unknown:
        raise ValueError(f"update_panel replaces only {list(INDICATOR_DATASETS)}, got {unknown}")
    with _open_store(path) as f:
        grp = _panel_group(f, path, index)
        kept_seeds = "lyapunov_seeds" in grp and "lyapunov_seeds" not in remove
        n = grp["lyapunov_seeds" if kept_seeds else "count"].shape[0]   # rows of the indicator datasets
    prepared = _indicator_arrays(arrays, n)

    def write(grp, old):
        for d, a in prepared.items():
            _create_dataset(grp, d, a)
        _copy_panel(old, grp, skip=set(prepared) | set(remove), attrs=attrs)

    _transaction(path, index, write, existing_panel=True)


def remove_store(path) -> None:
    """Remove the store at ``path`` and its panel files (the store file first: a kill in between
    leaves panel files that nothing links, which :func:`clean_stale_temporaries` removes)."""
    path = os.fspath(path)
    _remove_quietly(path)
    _fsync_dir(_store_dir(path))
    shutil.rmtree(panels_dir(path), ignore_errors=True)


def clean_stale_temporaries(path) -> list[str]:
    """Remove what killed runs left beside the store at ``path`` (``<path>.tmp-*`` and panel files
    the store does not link), except the files of a live process; returns them.  Call it under the
    store's lock."""
    path = os.fspath(path)
    removed = _clean_temporaries(path)
    folder = panels_dir(path)
    if not os.path.isdir(folder):
        return removed
    if os.path.exists(path):
        try:
            with _open_store(path) as f:
                found = [panel_file(path, t) for t in panel_links(f).values() if t is not None]
            linked = {os.path.normpath(os.path.abspath(name)) for name in found if name is not None}
        except StoreError:
            return removed
    else:
        linked = set()
    for name in sorted(os.listdir(folder)):
        full = os.path.join(folder, name)
        pid_text = name.split("-")[1] if name.count("-") >= 2 else ""
        if os.path.normpath(os.path.abspath(full)) in linked or not os.path.isfile(full):
            continue
        if pid_text.isdigit() and int(pid_text) != os.getpid() and _pid_alive(int(pid_text)):
            continue
        _remove_quietly(full)
        removed.append(full)
    if not os.path.exists(path) and not os.listdir(folder):
        os.rmdir(folder)
    return removed
