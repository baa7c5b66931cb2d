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
``$XDG_CACHE_HOME/mpi_ros/numba`` or ``~/.cache/mpi_ros/numba``; if that cannot be
created or written, ``<tempdir>/mpi_ros-numba-<uid>``.
"""

import os
from pathlib import Path
import sys
import tempfile

__all__ = ['CACHE_DIR', 'cache_dir', 'configure']


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
    if not os.environ.get('NUMBA_CACHE_DIR') and not _writable(path):
        path = Path(tempfile.gettempdir()) / f'mpi_ros-numba-{_uid()}'
    os.environ['NUMBA_CACHE_DIR'] = str(path)
    config = sys.modules.get('numba.core.config')
    if config is not None:
        setattr(config, 'CACHE_DIR', str(path))  # set at import time, not declared
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
