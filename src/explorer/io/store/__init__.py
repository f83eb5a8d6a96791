"""HDF5 store of a Poincaré-section sweep: self-describing, crash-safe, and a commit costs its panel.

Only the parent process of a sweep writes the store; workers return arrays.
A store ``X.h5`` is a small **store file** (root attributes, one HDF5 external link
``/panels/NNN`` per panel) and the **panel folder** ``X.h5.panels/`` with one HDF5 file per panel.
Every write is a transaction (:func:`commit_panel`): the panel is written into a new file of the
folder (a name no store links yet) and fsynced, then a new store file linking it is written to a
temporary name, fsynced and ``os.replace``'d onto ``X.h5`` (the commit point), the directory is
fsynced and the panel file it replaced is removed.  It writes the panel and the store file, not the
other panels.  After a SIGKILL or power loss at any instant the store is either the old complete
store or the new one, never half-written; at worst a stale ``<path>.tmp-<pid>-<random>`` or a panel
file that no store links is left behind, which the next sweep removes (:func:`clean_stale_temporaries`).

Layout (``format = "explorer.sections"``, ``format_version = 2``), read through the store file
(h5py follows the links; format 1, still read and converted at its next write, held the panel
groups inside the store file)
--------------------------------------------------------------------------------------------------
::

    /                               attrs: format = "explorer.sections", format_version = 2,
                                           scene_name, scene (the scene's TOML text),
                                           created, updated (ISO 8601 UTC),
                                           provenance (JSON text: package and dependency
                                           versions, python, platform, git revision,
                                           command line), plus any extra file attrs
                                           given by the caller
    /panels/000, /panels/001, ...   one external link per panel (zero-padded index) to the root
                                    group of ``X.h5.panels/NNN-<pid>-<random>.h5``, attrs:
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
caller supplies ``hash`` explicitly.  A sweep panel has two products, each with
its own hash attribute (:data:`PRODUCT_HASH_ATTRS`): ``sections_hash`` (the
datasets above) and ``indicators_hash`` (:data:`INDICATOR_DATASETS`, whose seeds
are ``lyapunov_seeds`` when given, else ``seeds``); a sweep compares them
(:func:`panel_product_hashes`) to decide what is already done, and replaces the
indicators beside stored crossings with :func:`update_panel`.  A panel with
``hash`` only was written before products had their own hashes.

Modules: :mod:`~explorer.io.store.format` (layout constants, reading),
:mod:`~explorer.io.store.atomic` (crash-safe file replacement),
:mod:`~explorer.io.store.commit` (provenance, the panel transaction, cleaning).

API
---
Streamed panels (rows written block by block, resumable after a kill):
:mod:`~explorer.io.store.stream`.

``commit_panel``, ``update_panel``, ``remove_store``, ``panels_dir``,
``read_store`` (-> :class:`StoreData` / :class:`PanelData`),
``read_panel_datasets``, ``panel_hashes``, ``panel_product_hashes``, ``stored_scene_name``,
``clean_stale_temporaries``, ``provenance``,
``store_lock`` (one writer per store, :mod:`~explorer.io.store.lock`), ``check_writable``,
``settings_hash``, ``write_bytes_atomic``, ``atomic_path``; errors about a
store file raise :class:`StoreError` (a ``ValueError``) with a one-line message
naming the path.
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
