"""HDF5 store of a Poincaré-section sweep: self-describing and crash-safe.

Only the parent process of a sweep writes the store; workers return arrays.
Every write is a whole-file transaction (:func:`commit_panel`): the new
contents are written to a temporary file in the same directory, fsynced and
``os.replace``'d onto the store, then the directory is fsynced.  After a
SIGKILL or power loss at any instant the store is either the old complete file
or the new complete file, never half-written; at worst a stale
``<path>.tmp-<pid>-<random>`` is left behind, which the next sweep removes
(:func:`clean_stale_temporaries`).

Layout (``format = "explorer.sections"``, ``format_version = 1``)
------------------------------------------------------------------
::

    /                               attrs: format = "explorer.sections", format_version = 1,
                                           scene_name, scene (the scene's TOML text),
                                           created, updated (ISO 8601 UTC),
                                           provenance (JSON text: package and dependency
                                           versions, python, platform, git revision,
                                           command line), plus any extra file attrs
                                           given by the caller
    /panels/000, /panels/001, ...   one group per panel (zero-padded index), attrs:
                                           index, label, parameter, value, h,
                                           params (JSON text of the model parameters),
                                           settings (JSON text), hash (sha256 of the settings),
                                           method, tol, dt, phi0, direction,
                                           crossings_requested, wall_time, complete = True
        seeds      (N, 2) float64   p1, p2 of each initial condition on the section
        y0         (N, 5) float64   full initial state (p1, p2, M, g1, g2)
        count      (N,)   int64     crossings stored for each orbit
        status     (N,)   int8      per-orbit status code;
                                    attrs: status_names = JSON {code: name}
        final      (N, 5) float64   state where each orbit stopped
        info       (N, 3) float64   final time, steps, final Casimir error
        offsets    (N+1,) int64     CSR offsets: orbit i's crossings are
                                    crossings[offsets[i]:offsets[i+1]]
        crossings  (total, 5) float64  rows t, p1, p2, M, dH;
                                    attrs: columns = ["t","p1","p2","M","dH"]

The ragged layout (``offsets`` + concatenated ``crossings`` rows) is made of
plain datasets that any HDF5 reader understands; no NaN padding is stored and
``count == diff(offsets)``.  Datasets with more than 10 000 rows are chunked,
gzip-compressed (level 4, shuffle filter) and carry fletcher32 checksums.
Nothing else is stored (no trajectories).  Attributes whose value is ``None``
are omitted (absent means "not applicable"); dict-valued attributes are stored
as JSON text.

Settings hash: ``hash = sha256`` of the settings serialized as canonical JSON
(:func:`settings_hash`: sorted keys, separators ``(",", ":")``), unless the
caller supplies ``hash`` explicitly.  A sweep compares it with
:func:`panel_hashes` to decide which panels are already done.

API
---
``commit_panel``, ``read_store`` (-> :class:`StoreData` / :class:`PanelData`),
``panel_hashes``, ``clean_stale_temporaries``, ``provenance``,
``settings_hash``, ``write_bytes_atomic``, ``atomic_path``; errors about a
store file raise :class:`StoreError` (a ``ValueError``) with a one-line message
naming the path.
"""
from __future__ import annotations

import contextlib
import datetime as _dt
import glob
import hashlib
import json
import numbers
import os
import platform as _platform
import secrets
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from typing import Iterator

import h5py
import numpy as np

from explorer.kernels import STATUS_NAMES

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "COLUMNS",
    "COMPRESS_ROWS",
    "StoreError",
    "PanelData",
    "StoreData",
    "commit_panel",
    "read_store",
    "panel_hashes",
    "clean_stale_temporaries",
    "provenance",
    "settings_hash",
    "write_bytes_atomic",
    "atomic_path",
]

FORMAT = "explorer.sections"
FORMAT_VERSION = 1
#: columns of a crossing row
COLUMNS = ("t", "p1", "p2", "M", "dH")
#: datasets with more rows than this are chunked + gzip(4) + shuffle + fletcher32
COMPRESS_ROWS = 10_000
GZIP_LEVEL = 4

#: dataset name -> (trailing shape, dtype); N = number of orbits
_PER_ORBIT = {
    "seeds": ((2,), np.float64),
    "y0": ((5,), np.float64),
    "count": ((), np.int64),
    "status": ((), np.int8),
    "final": ((5,), np.float64),
    "info": ((3,), np.float64),
}
DATASETS = tuple(_PER_ORBIT) + ("offsets", "crossings")
#: optional datasets, present when the scene computes them: chaos indicators per orbit and
#: the separatrices of the panel's fixed point (ragged polylines: points[offsets[k]:offsets[k+1]])
_OPTIONAL_PER_ORBIT = {
    "megno": ((), np.float64),
    "mlce": ((), np.float64),
    "fli": ((), np.float64),
    "lyapunov_status": ((), np.int8),
}
OPTIONAL_DATASETS = tuple(_OPTIONAL_PER_ORBIT) + ("separatrix_offsets", "separatrix_points")
_DEPENDENCIES = ("explorer", "numpy", "numba", "llvmlite", "h5py", "joblib", "matplotlib", "scipy")
_FORCE_HINT = "use --force to overwrite it or choose another --out"


class StoreError(ValueError):
    """A store file is missing, unreadable, corrupt or of another format."""


# --------------------------------------------------------------------------- helpers

def _utcnow() -> str:
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def _canonical_json(obj) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=_json_default)


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (set, frozenset)):
        return sorted(obj)
    return str(obj)


def settings_hash(settings) -> str:
    """sha256 (hex) of the settings: of the text itself if ``settings`` is a
    str (already-serialized JSON), else of its canonical JSON."""
    text = settings if isinstance(settings, str) else _canonical_json(settings)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _to_h5_attr(value):
    """Python value -> something h5py stores as an attribute (None -> skip)."""
    if value is None:
        return None
    if isinstance(value, (str, bool, np.bool_, numbers.Number, np.generic)):
        return value
    if isinstance(value, dict):
        return _canonical_json(value)
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "OUS":
            return np.array([str(v) for v in value.ravel()], dtype=h5py.string_dtype())
        return value
    if isinstance(value, (list, tuple)):
        if value and all(isinstance(v, str) for v in value):
            return np.array(list(value), dtype=h5py.string_dtype())
        if all(isinstance(v, (numbers.Number, np.generic)) and not isinstance(v, bool) for v in value):
            return np.asarray(value)
        return _canonical_json(list(value))
    return str(value)


def _from_h5_attr(value):
    """h5py attribute value -> plain Python (str, int, float, bool, list[str] or ndarray)."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "OSU":
            return [v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v) for v in value.ravel()]
        return value
    if isinstance(value, np.generic):
        return value.item()
    return value


def _set_attrs(obj, attrs: dict) -> None:
    for key, value in attrs.items():
        v = _to_h5_attr(value)
        if v is None:
            if key in obj.attrs:
                del obj.attrs[key]
            continue
        obj.attrs[key] = v


def _read_attrs(obj) -> dict:
    return {k: _from_h5_attr(v) for k, v in obj.attrs.items()}


def _fsync_path(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(directory: str) -> None:
    """Make a rename durable; silently skipped where directories cannot be fsynced."""
    try:
        fd = os.open(directory or ".", os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _tmp_name(path: str, suffix: str = "") -> str:
    return f"{path}.tmp-{os.getpid()}-{secrets.token_hex(4)}{suffix}"


def _remove_quietly(path: str) -> None:
    try:
        os.remove(path)
    except FileNotFoundError:
        pass


# --------------------------------------------------------------------------- atomic files

def write_bytes_atomic(path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically: temp file in the same directory,
    fsync, ``os.replace``, fsync of the directory."""
    path = os.fspath(path)
    tmp = _tmp_name(path)
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        _remove_quietly(tmp)
        raise
    _fsync_dir(os.path.dirname(os.path.abspath(path)))


@contextlib.contextmanager
def atomic_path(path) -> Iterator[str]:
    """Context manager yielding a temporary path next to ``path``; if the block
    succeeds the temporary file is fsynced and ``os.replace``'d onto ``path``,
    otherwise it is removed and ``path`` is untouched.  The temporary name keeps
    the extension of ``path`` (``fig.png.tmp-<pid>-<rand>.png``) so that tools
    inferring the format from it (matplotlib ``savefig``) work::

        with atomic_path("fig.png") as tmp:
            fig.savefig(tmp)
    """
    path = os.fspath(path)
    tmp = _tmp_name(path, os.path.splitext(path)[1])
    try:
        yield tmp
        if not os.path.exists(tmp):
            raise FileNotFoundError(f"atomic_path: the block did not create {tmp} (for {path})")
        _fsync_path(tmp)
        os.replace(tmp, path)
    except BaseException:
        _remove_quietly(tmp)
        raise
    _fsync_dir(os.path.dirname(os.path.abspath(path)))


def clean_stale_temporaries(path) -> list[str]:
    """Remove ``<path>.tmp-*`` files left by killed runs; returns the removed paths.

    Temporaries of another process that is still alive are kept (its commit may
    be in flight)."""
    path = os.fspath(path)
    removed = []
    for tmp in glob.glob(glob.escape(path) + ".tmp-*"):
        pid_text = tmp[len(path) + len(".tmp-"):].split("-", 1)[0]
        if pid_text.isdigit() and int(pid_text) != os.getpid() and _pid_alive(int(pid_text)):
            continue
        try:
            if os.path.isfile(tmp) or os.path.islink(tmp):
                os.remove(tmp)
                removed.append(tmp)
        except FileNotFoundError:
            pass
    return removed


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except OSError:
        return False
    return True


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


# --------------------------------------------------------------------------- reading

@dataclass
class PanelData:
    """One panel read from a store: every dataset as a numpy array plus the attrs."""

    index: int
    seeds: np.ndarray
    y0: np.ndarray
    count: np.ndarray
    status: np.ndarray
    final: np.ndarray
    info: np.ndarray
    offsets: np.ndarray
    crossings: np.ndarray
    attrs: dict = field(default_factory=dict)
    status_names: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)   # optional datasets present in the file

    def separatrices(self) -> list:
        """The stored separatrix polylines ((M, 2) arrays), [] if none."""
        if "separatrix_offsets" not in self.extra:
            return []
        off, pts = self.extra["separatrix_offsets"], self.extra["separatrix_points"]
        return [pts[off[k]:off[k + 1]] for k in range(len(off) - 1)]

    @property
    def arrays(self) -> dict:
        """The datasets by name (seeds, y0, count, status, final, info, offsets, crossings)."""
        return {name: getattr(self, name) for name in DATASETS}

    @property
    def n_orbits(self) -> int:
        return int(self.count.shape[0])

    @property
    def complete(self) -> bool:
        return bool(self.attrs.get("complete", False))

    @property
    def hash(self) -> str | None:
        return self.attrs.get("hash")

    @property
    def params(self) -> dict:
        """The model parameters (decoded from the ``params`` JSON attr)."""
        return _json_attr(self.attrs.get("params"))

    @property
    def settings(self) -> dict:
        """The settings (decoded from the ``settings`` JSON attr)."""
        return _json_attr(self.attrs.get("settings"))

    def orbit(self, i: int) -> np.ndarray:
        """Crossings of orbit i, shape (count_i, 5), columns t, p1, p2, M, dH."""
        n = self.n_orbits
        if not -n <= i < n:
            raise IndexError(f"orbit {i} out of range for a panel of {n} orbits")
        i %= n
        return self.crossings[self.offsets[i]:self.offsets[i + 1]]

    def points(self) -> np.ndarray:
        """All (p1, p2) crossing points of the panel, shape (total, 2)."""
        return self.crossings[:, 1:3]

    def orbit_index(self) -> np.ndarray:
        """For each crossing row, the orbit it belongs to (total,)."""
        return np.repeat(np.arange(self.n_orbits), np.diff(self.offsets))

    def padded(self, fill: float = np.nan) -> np.ndarray:
        """Crossings as (N, max count, 5), padded with ``fill``."""
        k = int(self.count.max()) if self.n_orbits else 0
        out = np.full((self.n_orbits, k, 5), fill)
        if self.crossings.shape[0]:
            rows = np.arange(self.crossings.shape[0]) - np.repeat(self.offsets[:-1], np.diff(self.offsets))
            out[self.orbit_index(), rows] = self.crossings
        return out


def _json_attr(text):
    if text is None:
        return {}
    if isinstance(text, dict):
        return text
    return json.loads(text)


@dataclass
class StoreData:
    """A whole store: file attrs and complete panels by index."""

    path: str
    attrs: dict
    panels: dict  # int -> PanelData

    @property
    def provenance(self) -> dict:
        return _json_attr(self.attrs.get("provenance"))

    @property
    def scene(self) -> str | None:
        return self.attrs.get("scene")

    @property
    def scene_name(self) -> str | None:
        return self.attrs.get("scene_name")


def _open_store(path: str):
    """Open an existing store read-only and check its format; StoreError otherwise."""
    if not os.path.exists(path):
        raise StoreError(f"{path}: no such store file")
    if os.path.isdir(path):
        raise StoreError(f"{path}: is a directory, not an explorer store")
    try:
        is_h5 = h5py.is_hdf5(path)
    except OSError as exc:
        raise StoreError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    if not is_h5:
        raise StoreError(f"{path}: not an HDF5 file (corrupt or another format); {_FORCE_HINT}")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise StoreError(f"{path}: corrupt HDF5 file ({_one_line(exc)}); {_FORCE_HINT}") from None
    try:
        fmt = _from_h5_attr(f.attrs.get("format"))
        version = _from_h5_attr(f.attrs.get("format_version"))
        if fmt != FORMAT:
            raise StoreError(f"{path}: not an explorer store (format attribute is {fmt!r}, "
                             f"expected {FORMAT!r}); {_FORCE_HINT}")
        if not isinstance(version, int) or version < 1:
            raise StoreError(f"{path}: invalid format_version {version!r}; {_FORCE_HINT}")
        if version > FORMAT_VERSION:
            raise StoreError(f"{path}: written by a newer explorer (format_version {version} > "
                             f"{FORMAT_VERSION}); upgrade explorer or choose another --out")
    except StoreError:
        f.close()
        raise
    except Exception as exc:  # damaged attribute heap and the like
        f.close()
        raise StoreError(f"{path}: corrupt HDF5 file ({_one_line(exc)}); {_FORCE_HINT}") from None
    return f


def _one_line(exc) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _panel_groups(f, path: str):
    """(index, group) of every panel group, sorted by index."""
    if "panels" not in f:
        return []
    out = []
    for name, grp in f["panels"].items():
        try:
            idx = int(name)
        except ValueError:
            raise StoreError(f"{path}: unexpected group /panels/{name}") from None
        if not isinstance(grp, h5py.Group):
            raise StoreError(f"{path}: /panels/{name} is not a group")
        out.append((idx, grp))
    return sorted(out, key=lambda t: t[0])


def _read_panel(idx: int, grp, path: str) -> PanelData:
    missing = [d for d in DATASETS if d not in grp]
    if missing:
        raise StoreError(f"{path}: panel {idx} lacks dataset(s) {', '.join(missing)}")
    arrays = {d: grp[d][()] for d in DATASETS}
    extra = {d: grp[d][()] for d in OPTIONAL_DATASETS if d in grp}
    names = _from_h5_attr(grp["status"].attrs.get("status_names"))
    status_names = {int(k): v for k, v in json.loads(names).items()} if names else dict(STATUS_NAMES)
    panel = PanelData(index=idx, attrs=_read_attrs(grp), status_names=status_names, extra=extra, **arrays)
    n = panel.count.shape[0]
    off = panel.offsets
    if (off.shape != (n + 1,) or off[0] != 0 or off[-1] != panel.crossings.shape[0]
            or np.any(np.diff(off) != panel.count)):
        raise StoreError(f"{path}: panel {idx} has inconsistent offsets/count/crossings")
    return panel


def read_store(path) -> StoreData:
    """Read a whole store (every panel group; see ``PanelData.complete``).

    Raises StoreError naming ``path`` if the file is missing, not HDF5, not an
    explorer store, or damaged (including fletcher32 checksum failures)."""
    path = os.fspath(path)
    f = _open_store(path)
    try:
        attrs = _read_attrs(f)
        panels = {idx: _read_panel(idx, grp, path) for idx, grp in _panel_groups(f, path)}
    except StoreError:
        raise
    except Exception as exc:
        raise StoreError(f"{path}: corrupt store ({_one_line(exc)}); {_FORCE_HINT}") from None
    finally:
        f.close()
    return StoreData(path=path, attrs=attrs, panels=panels)


def panel_hashes(path) -> dict:
    """{index: settings hash} of the complete panels; {} if ``path`` does not
    exist; StoreError if it exists but is not a readable explorer store."""
    path = os.fspath(path)
    if not os.path.exists(path):
        return {}
    f = _open_store(path)
    try:
        out = {}
        for idx, grp in _panel_groups(f, path):
            a = grp.attrs
            if bool(_from_h5_attr(a.get("complete", False))) and "hash" in a:
                out[idx] = _from_h5_attr(a["hash"])
        return out
    except StoreError:
        raise
    except Exception as exc:
        raise StoreError(f"{path}: corrupt store ({_one_line(exc)}); {_FORCE_HINT}") from None
    finally:
        f.close()


# --------------------------------------------------------------------------- writing

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
    crossings = np.ascontiguousarray(arrays["crossings"], dtype=np.float64)
    if crossings.ndim != 2 or crossings.shape[1] != len(COLUMNS):
        raise ValueError(f"crossings must have shape (total, {len(COLUMNS)}), got {crossings.shape}")
    if (offsets.shape != (n + 1,) or offsets[0] != 0 or np.any(np.diff(offsets) < 0)
            or offsets[-1] != crossings.shape[0]):
        raise ValueError("offsets must be (N+1,), start at 0, be non-decreasing and end at len(crossings)")
    if np.any(np.diff(offsets) != out["count"]):
        raise ValueError("count must equal diff(offsets)")
    out["offsets"] = offsets
    out["crossings"] = crossings
    for name, (tail, dtype) in _OPTIONAL_PER_ORBIT.items():
        if name in arrays:
            a = np.asarray(arrays[name])
            if a.shape != (n,) + tail:
                raise ValueError(f"{name} must have shape {(n,) + tail}, got {a.shape}")
            out[name] = np.ascontiguousarray(a, dtype=dtype)
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


def _create_dataset(grp, name: str, a: np.ndarray):
    kw = {}
    if a.ndim >= 1 and a.shape[0] > COMPRESS_ROWS:
        row = int(np.prod(a.shape[1:], dtype=np.int64)) if a.ndim > 1 else 1
        rows = max(1, min(a.shape[0], (1 << 15) // row))
        kw = dict(chunks=(rows,) + a.shape[1:], compression="gzip", compression_opts=GZIP_LEVEL,
                  shuffle=True, fletcher32=True)
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
    (the ragged arrays are then built, padding dropped).  ``attrs`` are the
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

    directory = os.path.dirname(os.path.abspath(path))
    tmp = _tmp_name(path)
    try:
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
        _fsync_path(tmp)
        os.replace(tmp, path)
    except BaseException:
        _remove_quietly(tmp)
        raise
    _fsync_dir(directory)
