# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
numba's cache files of mpi_ros go to a per-user directory, never into the package.

A cache written into an installed package outlives the install and, after a later
``pip install -e .`` in the same environment, shadows the editable package. Each check
runs a fresh interpreter (numba reads its configuration once per process) that imports
mpi_ros and runs a compiled kernel, then looks at which cache files appeared where.
"""

import os
from pathlib import Path
import subprocess
import sys

import mpi_ros
from mpi_ros import numba_cache
import pytest

PACKAGE = Path(mpi_ros.__file__).resolve().parent

#: Imports mpi_ros, runs a compiled kernel (play operator), prints numba's cache directory.
RUN_KERNEL = (
    'import numpy as np\n'
    'import mpi_ros\n'
    'from mpi_ros.operators.play import play_operator\n'
    'import numba\n'
    'play_operator(np.linspace(0.0, 1.0, 50), [0.0, 0.1], [0.0, 0.0])\n'
    'print(numba.config.CACHE_DIR)\n'
)


def _cache_files(root):
    """Return {path: mtime} of numba's cache files under ``root``."""
    root = Path(root)
    return {path: path.stat().st_mtime_ns
            for pattern in ('*.nbi', '*.nbc') for path in root.rglob(pattern)}


def _run(code, env_updates, *, first=''):
    env = {key: value for key, value in os.environ.items()
           if key not in ('NUMBA_CACHE_DIR', 'XDG_CACHE_HOME')}
    env.update(env_updates)
    before = _cache_files(PACKAGE)
    result = subprocess.run([sys.executable, '-c', first + code], env=env, cwd=Path.home(),
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    after = _cache_files(PACKAGE)
    written = sorted(str(path) for path, mtime in after.items() if before.get(path) != mtime)
    assert written == [], f'numba wrote into the package: {written}'
    return result.stdout.strip().splitlines()[-1]


@pytest.mark.slow
@pytest.mark.parametrize('first', ['', 'import numba\n'])
def test_kernels_are_cached_under_xdg_cache_home(tmp_path, first):
    used = _run(RUN_KERNEL, {'XDG_CACHE_HOME': str(tmp_path)}, first=first)
    digest = numba_cache.sources_digest()
    assert Path(used) == tmp_path / 'mpi_ros' / 'numba' / f'sources-{digest}'
    assert _cache_files(tmp_path / 'mpi_ros' / 'numba'), 'no cache file written'


@pytest.mark.slow
def testnumba_cache_dir_set_by_the_user_is_kept(tmp_path):
    used = _run(RUN_KERNEL, {'NUMBA_CACHE_DIR': str(tmp_path / 'mine')})
    assert Path(used) == tmp_path / 'mine'
    assert _cache_files(tmp_path / 'mine')


@pytest.mark.slow
def test_an_unwritable_cache_home_falls_back_to_the_temporary_directory(tmp_path):
    blocker = tmp_path / 'not_a_directory'
    blocker.write_text('')
    temporary = tmp_path / 'tmp'
    temporary.mkdir()
    used = _run(RUN_KERNEL, {'XDG_CACHE_HOME': str(blocker), 'TMPDIR': str(temporary)})
    assert Path(used).parent.parent == temporary
    assert Path(used).parent.name.startswith('mpi_ros-numba-')
    assert _cache_files(temporary)


def test_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.delenv('NUMBA_CACHE_DIR', raising=False)
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path))
    assert numba_cache.cache_dir() == tmp_path / 'mpi_ros' / 'numba'
    monkeypatch.delenv('XDG_CACHE_HOME')
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    assert numba_cache.cache_dir() == tmp_path / 'home' / '.cache' / 'mpi_ros' / 'numba'
    monkeypatch.setenv('NUMBA_CACHE_DIR', str(tmp_path / 'given'))
    assert numba_cache.cache_dir() == tmp_path / 'given'


def test_this_process_caches_outside_the_package():
    import numba
    cache = Path(numba.config.CACHE_DIR).resolve()
    assert str(cache)
    assert PACKAGE not in (cache, *cache.parents)


def test_a_changed_source_file_gets_a_new_cache_directory(tmp_path):
    # numba checks a cached kernel against its own file only: a kernel calling a changed
    # law would run the old one from the cache.  Any change of any source file changes
    # the directory.
    tree = tmp_path / 'src'
    (tree / 'sub').mkdir(parents=True)
    (tree / 'play.py').write_text('rule = 1\n')
    (tree / 'sub' / 'kernels.py').write_text('calls the rule\n')
    first = numba_cache.sources_digest(tree)
    assert numba_cache.sources_digest(tree) == first
    (tree / 'play.py').write_text('rule = 22\n')
    assert numba_cache.sources_digest(tree) != first
    assert numba_cache.sources_digest() == numba_cache.sources_digest(PACKAGE)
