"""The store's format (docs/store.md): layout constants, attribute encoding, the settings hash,
and reading; the writer (:mod:`explorer.io.store.commit`) produces this layout."""
from __future__ import annotations

import contextlib
import datetime as _dt
import hashlib
import json
import numbers
import os
from dataclasses import dataclass, field

import h5py
import numpy as np
from h5py import h5l

from explorer.kernels import STATUS_NAMES, indicator_table

FORMAT = "explorer.sections"
#: 2: one HDF5 file per panel in ``<store>.panels/``, joined by external links ``/panels/NNN`` in the
#: store file; 1: every panel a group inside the store file (still read; converted on the next write)
FORMAT_VERSION = 2
#: the folder of a store's panel files: ``<store>`` + this
PANELS_SUFFIX = ".panels"
#: columns of a crossing row
COLUMNS = ("t", "p1", "p2", "M", "dH")
#: datasets with more rows than this are chunked + gzip(4) + shuffle + fletcher32
COMPRESS_ROWS = 10_000
GZIP_LEVEL = 4

#: dataset name -> (trailing shape, dtype); N = number of orbits; -1: the state's width (5 for
#: Chaplygin's model, n for a System's panel, docs/store.md)
_PER_ORBIT = {
    "seeds": ((2,), np.float64),
    "y0": ((-1,), np.float64),
    "count": ((), np.int64),
    "status": ((), np.int8),
    "final": ((-1,), np.float64),
    "info": ((3,), np.float64),
}
DATASETS = tuple(_PER_ORBIT) + ("offsets", "crossings")
#: optional datasets, present when the scene computes them: chaos indicators per orbit and
#: the separatrices of the panel's fixed point (ragged polylines: points[offsets[k]:offsets[k+1]])
_OPTIONAL_PER_ORBIT = {
    **{i.name: ((), np.dtype(i.dtype)) for i in indicator_table.INDICATORS},   # the indicator registry
    "lyapunov_status": ((), np.dtype(np.int8)),
    "lyapunov_early": ((), np.dtype(np.int8)),
    "map_computed": ((), np.dtype(bool)),   # a chaos map's cell computed (True) or filled (docs/store.md)
    "map_chaotic": ((), np.dtype(bool)),    # an adaptive map's cell class, computed or filled
}
#: ``lyapunov_seeds`` (M, 2): the seeds of the indicators when they are not the panel's ``seeds``
#: (a chaos map's grid beside sections of the [seeds]); the indicator datasets then have M rows
OPTIONAL_DATASETS = tuple(_OPTIONAL_PER_ORBIT) + ("separatrix_offsets", "separatrix_points", "lyapunov_seeds")
#: the datasets of a panel's indicators product (kept or replaced together)
INDICATOR_DATASETS = tuple(_OPTIONAL_PER_ORBIT) + ("lyapunov_seeds",)
#: the attributes that name the hash of each product of a panel (explorer.io.scene.Scene.product_hashes)
PRODUCT_HASH_ATTRS = {"sections": "sections_hash", "indicators": "indicators_hash"}
_DEPENDENCIES = ("explorer", "numpy", "numba", "llvmlite", "h5py", "joblib", "matplotlib", "scipy")
_FORCE_HINT = "use --force to overwrite it or choose another --out"


class StoreError(ValueError):
    """A store file is missing, unreadable, corrupt or of another format."""


class PanelFileMissing(StoreError):
    """The file of a panel that the store links is not there."""


#: times :func:`read_store` reads again when a panel file vanished because a writer replaced the store
#: meanwhile (it removes the panel files it supersedes right after its commit)
READ_ATTEMPTS = 3


def _utcnow() -> str:
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


#: the panel attributes of the indicators product (kept with its datasets, replaced with them)
INDICATOR_ATTRS = ("indicators_hash", "chaotic_fraction", "chaotic_fraction_error", "class_indicator",
                   "class_threshold", "megno_threshold", "map_resolution", "map_p1", "map_p2", "indicators_wall_time")


@dataclass(frozen=True)
class PanelAttrs:
    """The attributes of a stored panel (docs/store.md) for every writer: :meth:`attrs` as the store
    writes them (``hash`` None: computed from ``settings``), :meth:`section_run` those of a run of
    crossings."""

    index: int
    label: str
    h: float
    params: dict
    settings: dict
    parameter: str = ""
    value: float = float("nan")
    hash: str | None = None

    def attrs(self) -> dict:
        """The attributes as the store writes them."""
        return {"index": int(self.index), "label": self.label, "parameter": self.parameter,
                "value": float(self.value), "h": self.h, "params": json.dumps(self.params, sort_keys=True),
                "settings": json.dumps(self.settings, sort_keys=True), "hash": self.hash}

    @staticmethod
    def section_run(*, method: str, tol: float, dt: float, phi0: float, direction: int, crossings: int,
                    wall_time: float) -> dict:
        """The attributes of a panel's crossings: the integration settings, the crossings asked
        for (``crossings_requested``) and the run's wall time."""
        return {"method": method, "tol": float(tol), "dt": float(dt), "phi0": float(phi0), "direction": int(direction),
                "crossings_requested": int(crossings), "wall_time": wall_time}


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


@dataclass(frozen=True)
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


def _json_attr(text):
    if text is None:
        return {}
    if isinstance(text, dict):
        return text
    return json.loads(text)


@dataclass(frozen=True)
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


def panels_dir(path) -> str:
    """The folder of the panel files of the store at ``path``: ``<path>.panels``."""
    return os.fspath(path) + PANELS_SUFFIX


def panel_links(f) -> dict:
    """{index: the file of panel ``index``'s external link (format 2), or None for a group inside
    the store file (format 1)} of the open store ``f``."""
    if "panels" not in f:
        return {}
    panels = f["panels"]
    links = panels.id.links       # h5py's low-level link API: no object is opened
    out = {}
    for name in panels:
        try:
            idx = int(name)
        except ValueError:
            raise StoreError(f"{f.filename}: unexpected entry /panels/{name}") from None
        raw = name.encode()
        external = links.get_info(raw).type == h5l.TYPE_EXTERNAL
        out[idx] = links.get_val(raw)[0].decode() if external else None
    return out


def _panel_group(f, path: str, idx: int, *, missing: str = "raise", links: dict | None = None):
    """The group of panel ``idx`` of the open store ``f`` (through its external link for format 2);
    a panel file that is missing is a StoreError naming it (``missing="raise"``) or None
    (``missing="skip"``: the panel counts as not stored, a sweep recomputes it)."""
    name = f"{idx:03d}"
    links = panel_links(f) if links is None else links
    if idx not in links:
        raise StoreError(f"{path}: no panel {idx}")
    target = links[idx]
    if target is None:              # format 1: a group inside the store file
        grp = f["panels"][name]
    else:
        found = panel_file(path, target)
        if found is None:
            if missing == "skip":
                return None
            raise PanelFileMissing(f"{path}: the file of panel {idx} ({target}) is missing (a store is its file "
                                   f"and the folder beside it, moved together); a sweep recomputes it, or "
                                   f"{_FORCE_HINT}")
        if found == os.path.join(os.path.dirname(os.path.abspath(path)), target):
            grp = f["panels"][name]
        else:   # the store and its folder were renamed: the link names the old folder
            panel = h5py.File(found, "r")
            grp = panel["/"]
            grp._explorer_file = panel      # open as long as the group is used
    if not isinstance(grp, h5py.Group):
        raise StoreError(f"{path}: /panels/{name} is not a group")
    return grp


def panel_file(path, target: str) -> str | None:
    """The panel file that the link ``target`` of the store at ``path`` names: in the store's own
    folder (after a move of store and folder), else relative to the store's directory; None if
    neither exists."""
    path = os.path.abspath(os.fspath(path))
    for candidate in (os.path.join(panels_dir(path), os.path.basename(target)),
                      os.path.join(os.path.dirname(path), target)):
        if os.path.isfile(candidate):
            return candidate
    return None


def _panel_groups(f, path: str, *, missing: str = "raise"):
    """(index, group) of every panel, sorted by index (``missing``: as :func:`_panel_group`)."""
    out = []
    links = panel_links(f)
    for idx in sorted(links):
        grp = _panel_group(f, path, idx, missing=missing, links=links)
        if grp is not None:
            out.append((idx, grp))
    return out


def _read_panel(idx: int, grp, path: str) -> PanelData:
    missing = [d for d in DATASETS if d not in grp]
    if missing:
        raise StoreError(f"{path}: panel {idx} lacks dataset(s) {', '.join(missing)}")
    arrays = {d: grp[d][()] for d in DATASETS}
    extra = _with_map_mask(grp, {d: grp[d][()] for d in OPTIONAL_DATASETS if d in grp})
    names = _from_h5_attr(grp["status"].attrs.get("status_names"))
    status_names = {int(k): v for k, v in json.loads(names).items()} if names else dict(STATUS_NAMES)
    panel = PanelData(index=idx, attrs=_read_attrs(grp), status_names=status_names, extra=extra, **arrays)
    n = panel.count.shape[0]
    off = panel.offsets
    if (off.shape != (n + 1,) or off[0] != 0 or off[-1] != panel.crossings.shape[0]
            or np.any(np.diff(off) != panel.count)):
        raise StoreError(f"{path}: panel {idx} has inconsistent offsets/count/crossings")
    return panel


def _with_map_mask(grp, extra: dict) -> dict:
    """``extra`` with ``map_computed`` all True for a map panel stored without the mask (every cell computed)."""
    if "map_resolution" in grp.attrs and "map_computed" not in extra and "lyapunov_status" in grp:
        extra["map_computed"] = np.ones(grp["lyapunov_status"].shape[0], bool)
    return extra


@contextlib.contextmanager
def _reading(path):
    """The open store at ``path``; any failure while reading it becomes one StoreError naming
    the file (a StoreError raised inside passes unchanged)."""
    f = _open_store(path)
    try:
        yield f
    except StoreError:
        raise
    except Exception as exc:
        raise StoreError(f"{path}: corrupt store ({_one_line(exc)}); {_FORCE_HINT}") from None
    finally:
        f.close()


def read_store(path) -> StoreData:
    """Read a whole store; StoreError naming ``path`` if it is missing, not an explorer store or
    damaged (fletcher32 checksums included)."""
    path = os.fspath(path)
    for attempt in range(READ_ATTEMPTS):
        before = _inode(path)
        try:
            with _reading(path) as f:
                attrs = _read_attrs(f)
                panels = {idx: _read_panel(idx, grp, path) for idx, grp in _panel_groups(f, path)}
            return StoreData(path=path, attrs=attrs, panels=panels)
        except PanelFileMissing:
            if attempt + 1 == READ_ATTEMPTS or _inode(path) == before:   # not a writer's commit meanwhile
                raise
    raise AssertionError("unreachable")


def _inode(path: str):
    try:
        return os.stat(path).st_ino
    except OSError:
        return None


def iter_rows(path, index: int, rows: int = 1 << 18):
    """The crossing rows of panel ``index`` in stored order, in pieces of at most ``rows``: a panel
    too large for memory.  StoreError as :func:`read_store`."""
    path = os.fspath(path)
    with _reading(path) as f:
        dset = _panel_group(f, path, int(index))["crossings"]
        for lo in range(0, dset.shape[0], int(rows)):
            yield dset[lo: lo + int(rows)]


def panel_hashes(path) -> dict:
    """{index: settings hash} of the complete panels; {} if ``path`` does not
    exist; StoreError if it exists but is not a readable explorer store."""
    path = os.fspath(path)
    if not os.path.exists(path):
        return {}
    out = {}
    with _reading(path) as f:
        for idx, grp in _panel_groups(f, path, missing="skip"):
            a = grp.attrs
            if bool(_from_h5_attr(a.get("complete", False))) and "hash" in a:
                out[idx] = _from_h5_attr(a["hash"])
    return out


def stored_scene_name(path) -> str | None:
    """The ``scene_name`` attribute of the store at ``path`` (None: no file, or no name);
    StoreError if it exists but is not a readable explorer store."""
    path = os.fspath(path)
    if not os.path.exists(path):
        return None
    with _reading(path) as f:
        name = _from_h5_attr(f.attrs.get("scene_name"))
    return None if name is None else str(name)


def panel_product_hashes(path) -> dict:
    """{index: the hash attributes present} of the complete panels; {} when ``path`` does not exist;
    StoreError as :func:`panel_hashes`."""
    path = os.fspath(path)
    if not os.path.exists(path):
        return {}
    keys = ("hash",) + tuple(PRODUCT_HASH_ATTRS.values())
    out = {}
    with _reading(path) as f:
        for idx, grp in _panel_groups(f, path, missing="skip"):
            a = grp.attrs
            if bool(_from_h5_attr(a.get("complete", False))):
                out[idx] = {k: _from_h5_attr(a[k]) for k in keys if k in a}
    return out


def read_panel_datasets(path, index: int, names) -> tuple[dict, dict]:
    """(datasets, attrs) of panel ``index``: only the datasets ``names`` that it holds (not the
    crossings unless asked), and all its attributes.  StoreError as :func:`read_store`."""
    path = os.fspath(path)
    with _reading(path) as f:
        grp = _panel_group(f, path, int(index))
        got = {d: grp[d][()] for d in names if d in grp}
        return _with_map_mask(grp, got) if "map_computed" in names else got, _read_attrs(grp)
