"""The HDF5 store of computed panels: self-describing and crash-safe (docs/store.md).

A store ``X.h5`` links one file per panel in ``X.h5.panels/``; every write is one atomic
transaction (:func:`commit_panel`), so a kill at any instant leaves the old store or the new one.
Modules: :mod:`.format` (layout, reading), :mod:`.atomic`, :mod:`.commit` (the transaction),
:mod:`.panel` (the writer of computed panels), :mod:`.stream` (panels written block by block),
:mod:`.lock` (one writer per store), :mod:`.atlas`.
"""
from __future__ import annotations

from explorer.io.store.atomic import atomic_path, write_bytes_atomic
from explorer.io.store.commit import (
                                      RowSource,
                                      clean_stale_temporaries,
                                      commit_panel,
                                      provenance,
                                      remove_store,
                                      update_panel,
                                      update_panel_attrs,
)
from explorer.io.store.format import (
                                      COLUMNS,
                                      COMPRESS_ROWS,
                                      DATASETS,
                                      FORMAT,
                                      FORMAT_VERSION,
                                      INDICATOR_ATTRS,
                                      INDICATOR_DATASETS,
                                      OPTIONAL_DATASETS,
                                      PRODUCT_HASH_ATTRS,
                                      STATUS_NAMES,
                                      PanelAttrs,
                                      PanelData,
                                      StoreData,
                                      StoreError,
                                      iter_rows,
                                      panel_hashes,
                                      panel_product_hashes,
                                      panels_dir,
                                      read_panel_datasets,
                                      read_store,
                                      settings_hash,
                                      stored_scene_name,
)
from explorer.io.store.lock import StoreBusy, check_writable, store_lock
from explorer.io.store.panel import ORBIT_DATASETS, check_disk, file_attrs, write_panel, writing

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "COLUMNS",
    "COMPRESS_ROWS",
    "StoreError",
    "INDICATOR_ATTRS",
    "PanelAttrs",
    "PanelData",
    "StoreData",
    "commit_panel",
    "write_panel",
    "writing",
    "check_disk",
    "file_attrs",
    "ORBIT_DATASETS",
    "RowSource",
    "update_panel",
    "update_panel_attrs",
    "read_store",
    "iter_rows",
    "panel_hashes",
    "panel_product_hashes",
    "read_panel_datasets",
    "stored_scene_name",
    "remove_store",
    "panels_dir",
    "store_lock",
    "StoreBusy",
    "check_writable",
    "clean_stale_temporaries",
    "provenance",
    "settings_hash",
    "write_bytes_atomic",
    "atomic_path",
    "DATASETS",
    "OPTIONAL_DATASETS",
    "INDICATOR_DATASETS",
    "PRODUCT_HASH_ATTRS",
    "STATUS_NAMES",
]
