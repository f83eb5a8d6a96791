"""The HDF5 file of a two-parameter atlas: the chaotic fraction per cell, written whole and
atomically, resumable from its ``done`` cells (docs/store.md, "Atlas files")."""
from __future__ import annotations

import datetime as _dt
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from explorer.io.store.atomic import atomic_path

FORMAT = "explorer.atlas"
FORMAT_VERSION = 1


@dataclass(frozen=True)
class AtlasData:
    """A stored atlas (:func:`read_atlas`)."""

    row_parameter: str
    column_parameter: str
    row_values: np.ndarray
    column_values: np.ndarray
    fraction: np.ndarray
    error: np.ndarray
    orbits: np.ndarray
    wall_time: np.ndarray
    threshold: float
    hash: str
    attrs: dict
    done: np.ndarray | None = None
    computed: np.ndarray | None = None     # per cell: the fraction of its map's cells computed (None: all)
    indicator: str = "megno"               # the indicator that classifies, at ``threshold``

    @property
    def complete(self) -> bool:
        """Every cell is stored."""
        return self.done is None or bool(np.all(self.done))


def write_atlas(path, *, scene_name: str, scene_text: str, hash: str, row_parameter: str, column_parameter: str,
                row_values, column_values, fraction, error, orbits, wall_time, threshold: float,
                provenance: dict | None = None, done=None, computed=None, indicator: str = "megno") -> Path:
    """Write the atlas file at ``path`` whole and atomically; ``done`` (R, C booleans, default all)
    marks the cells it holds; ``computed`` (R, C, optional): the fraction of each cell's map
    computed, not filled (an adaptive map, docs/scenes.md); ``indicator`` classifies at ``threshold``."""
    import h5py

    path = Path(path)
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs.update(format=FORMAT, format_version=FORMAT_VERSION, scene_name=scene_name, scene=scene_text,
                           hash=hash, row_parameter=row_parameter, column_parameter=column_parameter,
                           threshold=float(threshold), indicator=str(indicator),
                           created=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
                           provenance=json.dumps(provenance or {}, sort_keys=True),
                           complete=bool(done is None or np.all(done)))
            f["row_values"] = np.asarray(row_values, float)
            f["column_values"] = np.asarray(column_values, float)
            f["fraction"] = np.asarray(fraction, float)
            f["error"] = np.asarray(error, float)
            f["orbits"] = np.asarray(orbits, np.int64)
            f["wall_time"] = np.asarray(wall_time, float)
            f["done"] = np.ones(np.shape(fraction), np.int8) if done is None else np.asarray(done, np.int8)
            if computed is not None:
                f["computed"] = np.asarray(computed, float)
    return path


def read_atlas(path) -> AtlasData:
    """The atlas stored at ``path`` (OSError / ValueError when it is not one)."""
    import h5py

    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"{path}: not an explorer atlas file (format {f.attrs.get('format')!r})")
        attrs = {k: (v.item() if hasattr(v, "item") else v) for k, v in f.attrs.items()}
        return AtlasData(str(attrs["row_parameter"]), str(attrs["column_parameter"]), f["row_values"][()],
                         f["column_values"][()], f["fraction"][()], f["error"][()], f["orbits"][()],
                         f["wall_time"][()], float(attrs["threshold"]), str(attrs["hash"]), attrs,
                         f["done"][()].astype(bool) if "done" in f else None,
                         f["computed"][()] if "computed" in f else None, str(attrs.get("indicator", "megno")))
