# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Read a recording from a bag or a CSV file, chosen by the path.

:func:`read_recording` is the one reading function of the command line, the
identifier node and the diagnosis: it takes a :class:`DataOptions` and uses
the bag options for a bag, the CSV options for a CSV file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .bag_reader import read_bag, read_bag_signals
from .bag_storage import BAG_SUFFIXES
from .csv_files import read_csv, read_csv_signals
from .options import DataOptions
from .recording import PathLike, Recording
from ..errors import DataError

__all__ = ['read_recording', 'read_signals', 'source_kind', 'BAG_KEYWORDS', 'CSV_KEYWORDS']

#: Keyword options of :func:`read_bag_signals` (listed, not inspected).
BAG_KEYWORDS = ('input_topic', 'output_topic', 'input_joint', 'output_joint', 'input_field',
                'output_field', 'input_index', 'output_index', 'array_axes', 'sample_period',
                'time_source', 'time_scale', 'drop_nonfinite')
#: Keyword options of :func:`read_csv_signals` (listed, not inspected).
CSV_KEYWORDS = ('input_column', 'output_column', 'time_column', 'input_scale', 'output_scale',
                'time_scale', 'comment', 'drop_nonfinite')


def source_kind(path: PathLike) -> str:
    """
    Tell whether a path is a bag or a CSV file.

    Parameters
    ----------
    path : str or os.PathLike
        An existing path.

    Returns
    -------
    {'bag', 'csv'}
        ``'bag'`` for a directory, a ``.db3``/``.mcap`` file or a
        ``metadata.yaml``; ``'csv'`` for a ``.csv`` file.

    Raises
    ------
    DataError
        If the path does not exist or is of another kind.

    """
    source = Path(path)
    if not source.exists():
        msg = f'{source} does not exist; check the path'
        raise DataError(msg)
    if (source.is_dir() or source.suffix.lower() in BAG_SUFFIXES
            or source.name == 'metadata.yaml'):
        return 'bag'
    if source.suffix.lower() == '.csv':
        return 'csv'
    msg = (f'{source}: unknown file type {source.suffix!r}; expected a rosbag2 bag '
           '(directory, .db3 or .mcap) or a .csv file')
    raise DataError(msg)


def read_recording(path: PathLike, options: DataOptions | None = None) -> Recording:
    """
    Read a recording from a bag or a CSV file with one set of data options.

    Parameters
    ----------
    path : str or os.PathLike
        A bag directory, a ``.db3``/``.mcap`` storage file or its
        ``metadata.yaml``, or a ``.csv`` file.
    options : DataOptions, optional
        Which signals to read; the bag options apply to a bag, the CSV
        options to a CSV file, the scales and ``drop_nonfinite`` to both.
        Default: ``DataOptions()``.

    Returns
    -------
    Recording
        The paired samples, input times ``input_scale`` and output times
        ``output_scale``.

    Raises
    ------
    DataError
        If the path is missing or of an unknown kind, or the reader rejects
        the data (the message names the options as ``options.spelling``
        writes them).

    """
    options = DataOptions() if options is None else options
    if source_kind(path) == 'bag':
        return read_bag(path, options)
    return read_csv(path, options)


def read_signals(path: PathLike, **options: Any) -> Recording:
    """
    Read a recording from a bag or a CSV file with keyword options.

    Parameters
    ----------
    path : str or os.PathLike
        A bag (read by :func:`read_bag_signals`) or a ``.csv`` file (read by
        :func:`read_csv_signals`).
    **options
        Keyword options of the chosen reader (:data:`BAG_KEYWORDS` or
        :data:`CSV_KEYWORDS`); options of the other reader are rejected.

    Returns
    -------
    Recording
        The paired samples.

    Raises
    ------
    DataError
        If the path is missing, of an unknown kind, an option does not apply
        to that kind of file, or the reader rejects the data.

    See Also
    --------
    read_recording : the same with a :class:`DataOptions`.

    """
    source = Path(path)
    accepted: tuple[str, ...]
    if source_kind(source) == 'bag':
        accepted, kind = BAG_KEYWORDS, 'rosbag2 bag'
        unknown = sorted(set(options) - set(accepted))
        if not unknown:
            return read_bag_signals(source, **options)
    else:
        accepted, kind = CSV_KEYWORDS, 'CSV file'
        unknown = sorted(set(options) - set(accepted))
        if not unknown:
            return read_csv_signals(source, **options)
    msg = (f'option(s) {", ".join(unknown)} do not apply to {kind} {source}; '
           f'options for a {kind}: {", ".join(accepted)}')
    raise DataError(msg)
