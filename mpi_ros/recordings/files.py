# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Atomic file writes: a file or bag appears at its path only when complete.

CSV files, JSON statistics, parameter files, reports and bags are written beside
their target and renamed over it, so a crash never leaves a half-written file: the
path holds the old file or the new one.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
import re
import shutil
import stat
import tempfile
from typing import Any, IO, Iterator, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from .recording import FloatArray, PathLike
from ..errors import DataError

__all__ = ['check_target', 'equal_length_arrays', 'install_directory', 'make_tmpdir',
           'atomic_write', 'atomic_writes', 'same_file', 'write_target']


@contextlib.contextmanager
def atomic_write(path: PathLike, *, binary: bool = False) -> Iterator[IO[Any]]:
    """
    Open a file for writing that appears at `path` only when complete.

    The data goes to a temporary file in the same directory, which is
    flushed, synced and renamed over `path` (``os.replace``) when the block
    ends normally; the directory is synced after the rename. If the block
    raises, the temporary file is removed and `path` is untouched. A process
    killed while writing leaves `path` as it was (and a temporary file
    ``.<name>.<pid>.<random>.tmp``, removed by the next write of `path` once
    that process is gone).

    A symbolic link at `path` is written through: its target is replaced and the
    link stays. A file being replaced keeps its mode (a 600 file stays 600). A
    device, pipe or socket (``/dev/null``, ``/dev/stdout``) is written in place.

    Parameters
    ----------
    path : str or os.PathLike
        File to create or replace.
    binary : bool, optional
        Yield a binary file instead of a UTF-8 text file (``newline=''``).

    Yields
    ------
    file object
        The open temporary file.

    Raises
    ------
    DataError
        If the directory of `path` does not exist, `path` is a directory, or
        the file cannot be created or renamed.

    """
    with atomic_writes([path], binary=binary) as handles:
        yield handles[0]


@contextlib.contextmanager
def atomic_writes(paths: Sequence[PathLike], *,
                  binary: bool = False) -> Iterator[list[IO[Any]]]:
    """
    Write several files that belong together; each appears only when all are complete.

    Each file is written as by :func:`atomic_write`. When the block ends
    normally, all are synced first and then renamed over their targets in the
    order given, so the last path is the one written last: a crash between the
    renames leaves the earlier files new and the later ones old. If the block
    raises, nothing is renamed and no temporary file is left.

    Parameters
    ----------
    paths : sequence of str or os.PathLike
        Files to create or replace, in the order they are renamed; all distinct.
    binary : bool, optional
        Yield binary files instead of UTF-8 text files (``newline=''``).

    Yields
    ------
    list of file object
        The open temporary files, in the order of `paths`.

    Raises
    ------
    DataError
        As :func:`atomic_write`, or when two paths name the same file.

    """
    special = [_is_special(Path(path)) for path in paths]
    targets = [Path(path) if device else write_target(Path(path))
               for path, device in zip(paths, special)]
    for target, device in zip(targets, special):
        if not device:
            check_target(target, overwrite=True, kind='file')
    if len({str(t) for t in targets}) != len(targets):
        msg = (f'cannot write {", ".join(map(str, paths))}: two of them are the same file; '
               'give each output its own path')
        raise DataError(msg)
    temps: list[tuple[Path | None, IO[Any]]] = []
    try:
        for target, device in zip(targets, special):
            try:
                if device:          # /dev/null, /dev/stdout, a pipe: written in place
                    device_handle: IO[Any] = (
                        open(target, 'wb') if binary
                        else open(target, 'w', encoding='utf-8', newline=''))
                    temps.append((None, device_handle))
                    continue
                _remove_stale_temps(target)
                fd, tmpname = tempfile.mkstemp(prefix=f'.{target.name}.{os.getpid()}.',
                                               suffix='.tmp', dir=target.parent)
            except OSError as err:
                msg = f'cannot write {target}: {err}'
                raise DataError(msg) from err
            if binary:
                handle: IO[Any] = os.fdopen(fd, 'wb')
            else:
                handle = os.fdopen(fd, 'w', encoding='utf-8', newline='')
            temps.append((Path(tmpname), handle))
        yield [handle for _, handle in temps]
        for (tmp, handle), target in zip(temps, targets):
            try:
                handle.flush()
                if tmp is not None:
                    os.fsync(handle.fileno())
                handle.close()
                if tmp is not None:
                    os.chmod(tmp, _new_file_mode(target))
            except OSError as err:
                msg = f'cannot write {target}: {err}'
                raise DataError(msg) from err
        for (tmp, _), target in zip(temps, targets):
            if tmp is None:
                continue
            try:
                os.replace(tmp, target)
            except OSError as err:
                msg = f'cannot write {target}: {err}'
                raise DataError(msg) from err
            _sync_directory(target.parent)
    finally:
        for tmp, handle in temps:
            with contextlib.suppress(OSError):
                handle.close()
            if tmp is not None:
                with contextlib.suppress(OSError):
                    tmp.unlink()


def write_target(path: Path) -> Path:
    """
    Return the file a write of `path` replaces: `path`, or a symbolic link's final target.

    Parameters
    ----------
    path : Path
        The path given by the user.

    Returns
    -------
    Path
        `path` itself, or for a symbolic link (even a dangling one) the file it points to,
        so that the link is kept and its target written.

    """
    if path.is_symlink():
        return Path(os.path.realpath(path))
    return path


def same_file(first: PathLike, second: PathLike) -> bool:
    """
    Tell whether two paths name the same file (through symbolic and hard links).

    Parameters
    ----------
    first, second : str or os.PathLike
        Paths; either may not exist yet.

    Returns
    -------
    bool
        True when both exist and are one file (``os.path.samefile``), or when their
        resolved paths are equal.

    """
    with contextlib.suppress(OSError):
        return os.path.samefile(first, second)
    return os.path.realpath(first) == os.path.realpath(second)


def _is_special(path: Path) -> bool:
    # A device, pipe or socket (e.g. /dev/null, /dev/stdout): renaming over it would
    # replace the device node, so it is written in place.
    try:
        mode = path.stat().st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def _remove_stale_temps(target: Path) -> None:
    # The temporary files of writers of `target` that were killed: their process is gone.
    pattern = re.compile(re.escape(f'.{target.name}.') + r'(\d+)\.[A-Za-z0-9_]+\.tmp')
    with contextlib.suppress(OSError):
        for entry in os.scandir(target.parent):
            found = pattern.fullmatch(entry.name)
            if found and entry.is_file(follow_symlinks=False) and not _alive(
                    int(found.group(1))):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:            # another user's process: alive
        return True
    return True


def _sync_directory(directory: Path) -> None:
    # The rename is durable only once the directory entry is on disk.
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def make_tmpdir(target: Path) -> Path:
    """Return a new temporary directory next to ``target`` (same file system)."""
    try:
        return Path(tempfile.mkdtemp(prefix=f'.{target.name}.', suffix='.tmp',
                                     dir=target.parent))
    except OSError as err:
        msg = f'cannot write {target}: {err}'
        raise DataError(msg) from err


def check_target(target: Path, *, overwrite: bool, kind: str) -> None:
    """Refuse a target whose directory is missing, or that exists without ``overwrite``."""
    parent = target.parent
    if not parent.is_dir():
        msg = f'cannot write {kind} {target}: directory {parent} does not exist; create it first'
        raise DataError(msg)
    if kind == 'file' and target.is_dir():
        msg = f'cannot write file {target}: it is a directory; choose a file name'
        raise DataError(msg)
    if not overwrite and (target.exists() or target.is_symlink()):
        msg = (f'cannot write {kind} {target}: it exists already; choose another path or '
               'pass overwrite=True')
        raise DataError(msg)


def install_directory(built: Path, target: Path, *, overwrite: bool) -> None:
    """Move the finished bag directory `built` to `target` (same file system)."""
    try:
        if not (target.exists() or target.is_symlink()):
            os.rename(built, target)
            return
        if not overwrite:
            msg = (f'cannot write bag {target}: it was created while recording; choose '
                   'another path or pass overwrite=True')
            raise DataError(msg)
        old = built.parent / f'{target.name}.replaced'
        os.rename(target, old)
        try:
            os.rename(built, target)
        except OSError:
            os.rename(old, target)
            raise
        if old.is_dir() and not old.is_symlink():
            shutil.rmtree(old, ignore_errors=True)
        else:
            old.unlink()
    except OSError as err:
        msg = f'cannot write bag {target}: {err}'
        raise DataError(msg) from err


def equal_length_arrays(
    columns: Mapping[str, npt.ArrayLike], *, what: str,
) -> dict[str, FloatArray]:
    """Return the columns as flat float arrays of one length (DataError names ``what``)."""
    arrays: dict[str, FloatArray] = {}
    for name, column in columns.items():
        try:
            arr = np.asarray(column, dtype=np.float64)
        except (TypeError, ValueError) as err:
            msg = f'{what}: {name} must be an array of numbers; {err}'
            raise DataError(msg) from err
        if arr.ndim != 1:
            msg = f'{what}: {name} must be one-dimensional; found shape {arr.shape}'
            raise DataError(msg)
        arrays[name] = arr
    lengths = {name: arr.size for name, arr in arrays.items()}
    if len(set(lengths.values())) > 1:
        msg = f'{what}: the arrays must have equal lengths; found {lengths}'
        raise DataError(msg)
    return arrays


def _new_file_mode(target: Path) -> int:
    """Keep the mode of a file being replaced; else the usual 0o666 minus umask."""
    with contextlib.suppress(OSError):
        return target.stat().st_mode & 0o7777
    umask = os.umask(0o022)  # reading the umask requires setting it; restore at once
    os.umask(umask)
    return 0o666 & ~umask
