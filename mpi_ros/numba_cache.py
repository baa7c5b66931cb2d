# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Where numba caches the compiled kernels of mpi_ros: a per-user directory, never the package.

``@numba.njit(cache=True)`` writes its ``*.nbi``/``*.nbc`` files next to the source file
(``__pycache__`` inside the installed package) unless ``numba.config.CACHE_DIR`` is set
when the decorator runs: the decorator builds its cache locator right away, and numba
takes the first locator that answers, ``CACHE_DIR`` before the source tree. Files written
into ``site-packages`` by one install outlive it (``pip`` removes only the files it
installed) and can shadow a later editable install of the same package. So
``mpi_ros/__init__.py`` imports this module first, and importing it calls
:func:`configure` (the result is :data:`CACHE_DIR`).

The directory is ``$NUMBA_CACHE_DIR`` when that is set (numba's own variable), else
``$XDG_CACHE_HOME/mpi_ros/numba/sources-<digest>`` or ``~/.cache/mpi_ros/numba/...``; if
that cannot be created or written, ``<tempdir>/mpi_ros-numba-<uid>/sources-<digest>``.

Why the digest: numba checks a cached kernel against its own source file only, not the
files of the kernels it calls.  After ``play.py`` or ``inverse.py`` changes (an update of
a source checkout or a ``--symlink-install``), the cached compensator kernels would go on
running the old play rule or law (14).  The digest covers the size and modification
time of every source file of the package, so any change starts a fresh cache directory;
directories of other sources that were not used for 30 days are removed.
"""

import hashlib
import os
from pathlib import Path
import shutil
import sys
import tempfile
import time

__all__ = ['CACHE_DIR', 'cache_dir', 'configure', 'sources_digest']


def cache_dir() -> Path:
    """
    Return the directory for numba's cache files of mpi_ros (not created here).

    Returns
    -------
    pathlib.Path
        ``$NUMBA_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/mpi_ros/numba`` (default
        ``~/.cache/mpi_ros/numba``).

    """
    given = os.environ.get('NUMBA_CACHE_DIR')
    if given:
        return Path(given)
    base = os.environ.get('XDG_CACHE_HOME') or os.path.join(os.path.expanduser('~'), '.cache')
    return Path(base) / 'mpi_ros' / 'numba'


def configure() -> Path:
    """
    Point numba's cache at :func:`cache_dir` (or a temporary one if that is not writable).

    Sets ``NUMBA_CACHE_DIR`` in ``os.environ`` (numba reads it on import and again when
    it compiles; child processes inherit it) and, if numba is already imported,
    ``numba.config.CACHE_DIR``. A ``NUMBA_CACHE_DIR`` set by the user is kept.

    Returns
    -------
    pathlib.Path
        The directory in use.

    """
    path = cache_dir()
    if not os.environ.get('NUMBA_CACHE_DIR'):
        if not _writable(path):
            path = Path(tempfile.gettempdir()) / f'mpi_ros-numba-{_uid()}'
        path = _for_these_sources(path)
    os.environ['NUMBA_CACHE_DIR'] = str(path)
    config = sys.modules.get('numba.core.config')
    if config is not None:
        setattr(config, 'CACHE_DIR', str(path))  # set at import time, not declared
    return path


#: Cache directories of other sources unused for this long [s] are removed.
_UNUSED = 30 * 24 * 3600.0


def sources_digest(root: Path | None = None) -> str:
    """
    Return a digest of the package's source files (paths, sizes, modification times).

    Parameters
    ----------
    root : pathlib.Path, optional
        The source tree; the installed mpi_ros package by default.

    Returns
    -------
    str
        16 hexadecimal digits; changes whenever any ``*.py`` file of mpi_ros changes.

    """
    root = Path(__file__).resolve().parent if root is None else root
    digest = hashlib.sha1(usedforsecurity=False)
    for path in sorted(root.rglob('*.py')):
        stat = path.stat()
        digest.update(f'{path.relative_to(root)}:{stat.st_size}:{stat.st_mtime_ns};'.encode())
    return digest.hexdigest()[:16]


def _for_these_sources(base: Path) -> Path:
    path = base / f'sources-{sources_digest()}'
    now = time.time()
    try:
        path.mkdir(parents=True, exist_ok=True)
        os.utime(path, (now, now))                         # in use: not pruned
        for other in base.glob('sources-*'):
            if other != path and now - other.stat().st_mtime > _UNUSED:
                shutil.rmtree(other, ignore_errors=True)
    except OSError:
        pass                                               # numba reports unwritable dirs
    return path


def _writable(path: Path) -> bool:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(path, os.W_OK | os.X_OK)


def _uid() -> str:
    getuid = getattr(os, 'getuid', None)
    return str(getuid()) if getuid is not None else os.environ.get('USERNAME', 'user')


#: The directory numba caches mpi_ros's kernels in (set on import).
CACHE_DIR = configure()
