"""Atomic files: a whole file written to a temporary name beside the target, fsynced and
``os.replace``'d onto it, so a crash leaves the old file or the new one."""
from __future__ import annotations

import contextlib
import glob
import os
import secrets
from collections.abc import Iterator


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
    """Yield a temporary path beside ``path`` (same extension); when the block succeeds it is
    fsynced and ``os.replace``'d onto ``path``, otherwise removed and ``path`` untouched."""
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


