# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Atomic file writes: a file or bag appears at its path only when complete.

CSV files, JSON statistics and bags are written beside their target and
renamed over it, so a crash never leaves a half-written file.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
import shutil
import tempfile
from typing import Any, IO, Iterator, Mapping

import numpy as np
import numpy.typing as npt

from .recording import FloatArray, PathLike
from ..errors import DataError

__all__ = ['atomic_write']


@contextlib.contextmanager
def atomic_write(path: PathLike, *, binary: bool = False) -> Iterator[IO[Any]]:
    """
    Open a file for writing that appears at `path` only when complete.

    The data goes to a temporary file in the same directory, which is
    flushed, synced and renamed over `path` (``os.replace``) when the block
    ends normally. If the block raises, the temporary file is removed and
    `path` is untouched.

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
    target = Path(path)
    _check_target(target, overwrite=True, kind='file')
    directory = target.parent
    try:
        fd, tmpname = tempfile.mkstemp(prefix=f'.{target.name}.', suffix='.tmp',
                                       dir=directory)
    except OSError as err:
        msg = f'cannot write {target}: {err}'
        raise DataError(msg) from err
    tmp = Path(tmpname)
    try:
        if binary:
            handle: IO[Any] = os.fdopen(fd, 'wb')
        else:
            handle = os.fdopen(fd, 'w', encoding='utf-8', newline='')
        with handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        try:
            os.chmod(tmp, _new_file_mode(target))
            os.replace(tmp, target)
        except OSError as err:
            msg = f'cannot write {target}: {err}'
            raise DataError(msg) from err
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def _make_tmpdir(target: Path) -> Path:
    try:
        return Path(tempfile.mkdtemp(prefix=f'.{target.name}.', suffix='.tmp',
                                     dir=target.parent))
    except OSError as err:
        msg = f'cannot write {target}: {err}'
        raise DataError(msg) from err


def _check_target(target: Path, *, overwrite: bool, kind: str) -> None:
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


def _install(built: Path, target: Path, *, overwrite: bool) -> None:
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


def _equal_length_arrays(
    columns: Mapping[str, npt.ArrayLike], *, what: str,
) -> dict[str, FloatArray]:
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
