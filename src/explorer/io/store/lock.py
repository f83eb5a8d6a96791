"""Guards of a store: its directory must be writable (:func:`check_writable`) and one process at
a time writes it (:func:`store_lock`, an OS lock that dies with its holder; docs/store.md,
"Beside the store")."""
from __future__ import annotations

import contextlib
import datetime as _dt
import os
import socket
import sys
from collections.abc import Iterator
from pathlib import Path

from explorer.io.store.format import StoreError
from explorer.model import ParameterError, validation


class StoreBusy(StoreError):
    """Another process holds the lock of the store."""


def lock_path(path) -> str:
    """The lock file of the store at ``path``: ``<path>.lock``."""
    return os.fspath(path) + ".lock"


def check_writable(directory, option: str, target) -> None:
    """Refuse (:class:`~explorer.model.ParameterError`, one line naming ``option``, ``target`` and
    the reason) a ``directory`` that cannot be created or written into."""
    directory = Path(directory)
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{option} {target}: cannot write into the directory '{directory}' "
                             f"({exc.strerror or exc})") from None
    validation.writable_directory(option, target, directory)


def _holder_text() -> str:
    """Who holds the lock: the line a refused writer prints, then the holder's command line."""
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return f"pid {os.getpid()} on {socket.gethostname()} since {now}\ncommand: {' '.join(sys.argv)}\n"


@contextlib.contextmanager
def store_lock(path) -> Iterator[str]:
    """Hold the lock of the store at ``path`` for the ``with`` block (yields the lock file's path);
    StoreBusy, naming the holder, when another process holds it.  Nothing is locked without
    ``fcntl``."""
    try:
        import fcntl
    except ImportError:
        yield lock_path(path)
        return

    name = lock_path(path)
    while True:
        fd = os.open(name, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            text = os.read(fd, 4096).decode("utf-8", "replace").strip()
            holder = text.splitlines()[0] if text else "another process"
            os.close(fd)
            raise StoreBusy(f"{os.fspath(path)} is being written by {holder}; wait for it to finish or "
                            "choose another --out") from None
        except BaseException:
            os.close(fd)
            raise
        try:   # the holder before us may have removed the file between our open and our lock
            same = os.fstat(fd).st_ino == os.stat(name).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, _holder_text().encode())
        yield name
    finally:
        try:
            os.remove(name)     # still under the lock: nobody else holds this file
        except FileNotFoundError:
            pass
        os.close(fd)            # releases the lock
