# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Read and write actuator signals as CSV files with a header row.

The readers name the line and column of every bad field; the writer is
atomic and writes floats so that they read back exactly.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
import math
from pathlib import Path
import re
from typing import Callable, Iterator, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from .files import atomic_write, equal_length_arrays
from .options import DataOptions
from .recording import check_magnitudes, FloatArray, in_si, MIN_SAMPLES, PathLike, Recording
from ..errors import DataError

__all__ = ['read_csv_signals', 'read_csv', 'read_csv_table', 'write_csv_columns']

# A decimal number as written by numeric software; float() alone would also take
# '1_000', non-ASCII digits and surrounding whitespace.
_NUMBER = re.compile(
    r'[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf|infinity)', re.IGNORECASE)


def read_csv_signals(
    path: PathLike,
    *,
    input_column: str | None = None,
    output_column: str | None = None,
    time_column: str | None = 'time',
    input_scale: float = 1.0,
    output_scale: float = 1.0,
    time_scale: float = 1.0,
    comment: str | None = '#',
    drop_nonfinite: bool = False,
) -> Recording:
    """
    Read input and output columns of a CSV file with a header row.

    Lines starting with `comment` (after leading blanks) and blank lines are
    skipped; the first other line is the header. Only the time, input and
    output columns must be numeric; other columns may hold text.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file (UTF-8, comma-separated, optional quotes).
    input_column : str, optional
        Column of the actuator input; default: the first column that is not
        the time column.
    output_column : str, optional
        Column of the actuator output; default: the first column after the
        input column that is not the time column.
    time_column : str or None, optional
        Column of the sample times; None if the file has none, in which case
        ``time`` is the sample index 0, 1, 2, ... (a note says so).
    input_scale : float, optional
        Factor converting the input column to A (to the input's SI unit).
    output_scale : float, optional
        Factor converting the output column to m, e.g. 1e-9 for nm.
    time_scale : float, optional
        Factor converting the time column to s, e.g. 1e-3 for ms.
    comment : str or None, optional
        Prefix of comment lines; None to disable.
    drop_nonfinite : bool, optional
        Drop rows with NaN/Inf or an empty field in the used columns (with a
        note) instead of raising. An empty field is a missing value (pandas
        writes NaN as one).

    Returns
    -------
    Recording
        ``time`` [s] as written times `time_scale`, ``current`` [A],
        ``displacement`` [m], ``source`` = the path, ``notes``.

    Raises
    ------
    DataError
        If the file is missing, empty, not UTF-8 or has no header row; a named
        column is missing (the message lists those present); a used field is
        not a number (the message gives line and column); rows are ragged;
        fewer than :data:`MIN_SAMPLES` rows remain; or a used field is NaN/Inf
        or empty (without `drop_nonfinite`); or a signal is too large or spans
        too little to compute with (:func:`~mpi_ros.recordings.recording.check_magnitudes`).
        The message names the first bad field in file order.

    Examples
    --------
    The measured PZT files write time in s, voltage in V and displacement in nm::

        rec = read_csv_signals('SLOW_table03_TEST_800V.csv', time_column='Time_s',
                               input_column='Vplus_V', output_column='D1_nm',
                               output_scale=1e-9)

    """
    options = DataOptions(input_column=input_column, output_column=output_column,
                          time_column=time_column, input_scale=input_scale,
                          output_scale=output_scale, time_scale=time_scale,
                          drop_nonfinite=drop_nonfinite)
    return read_csv(path, options, comment=comment)


def read_csv(path: PathLike, options: DataOptions, *, comment: str | None = '#') -> Recording:
    """
    Read a CSV file with the CSV options of `options` (see :func:`read_csv_signals`).

    Messages name the options in ``options.spelling``.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file.
    options : DataOptions
        Columns, scales and `drop_nonfinite`.
    comment : str or None, optional
        Prefix of comment lines; None to disable.

    Returns
    -------
    Recording
        As :func:`read_csv_signals`.

    Raises
    ------
    DataError
        As :func:`read_csv_signals`.

    """
    source = Path(path)
    time_column = options.time_column
    input_column, output_column = options.input_column, options.output_column
    table = _read_csv_rows(source, comment=comment)
    if time_column is not None:
        _column_index(table, time_column, option='time_column', options=options)
    candidates = [name for name in table.header if name != time_column]
    if input_column is None:
        if not candidates:
            msg = (f'CSV file {source} has no column besides the time column {time_column!r}; '
                   'add input and output columns')
            raise DataError(msg)
        input_column = candidates[0]
    i_in = _column_index(table, input_column, option='input_column', options=options)
    if output_column is None:
        after = [name for name in table.header[i_in + 1:] if name != time_column]
        if not after:
            msg = (f'CSV file {source}: no column after the input column {input_column!r} to '
                   f'use as output; pass {options.setting("output_column", "<name>")} '
                   f'(available: {_names(table.header)})')
            raise DataError(msg)
        output_column = after[0]
    i_out = _column_index(table, output_column, option='output_column', options=options)
    if i_out == i_in:
        msg = (f'CSV file {source}: {options.name("input_column")} and '
               f'{options.name("output_column")} are both {input_column!r}; choose two '
               'different columns')
        raise DataError(msg)
    used = {'input': i_in, 'output': i_out}
    if time_column is not None:
        used['time'] = _column_index(table, time_column, option='time_column', options=options)
    _check_row_count(table, len(table.rows))
    notes: list[str] = []
    columns, keep = _numeric_columns(
        table, sorted(set(used.values())), drop_nonfinite=options.drop_nonfinite, notes=notes,
        hint=f'pass {options.setting("drop_nonfinite")} to drop those rows')
    values = {role: columns[index][keep] for role, index in used.items()}
    n_rows = int(np.count_nonzero(keep))
    _check_row_count(table, n_rows, after_drop=n_rows != len(table.rows))
    if time_column is None:
        time = np.arange(n_rows, dtype=np.float64)
        notes.append('no time column: time is the sample index 0, 1, 2, ...')
    else:
        time = values['time'] * options.time_scale
        steps = np.diff(time)
        if np.any(steps <= 0):
            first = int(np.flatnonzero(steps <= 0)[0]) + 1
            line = int(np.asarray(table.line_numbers)[keep][first])
            notes.append(f'time column {time_column!r} is not strictly increasing (first at '
                         f'line {line}); samples are kept in file order')
    read = Recording(time, values['input'] * options.input_scale,
                     values['output'] * options.output_scale, source=str(source),
                     notes=tuple(notes), timed=time_column is not None)
    return check_magnitudes(in_si(read, options, time_name=time_column or '',
                                  input_name=input_column, output_name=output_column), options)


def read_csv_table(
    path: PathLike,
    *,
    comment: str | None = '#',
    drop_nonfinite: bool = False,
    nonfinite_hint: str = 'pass drop_nonfinite=True to drop those rows',
    select: Callable[[list[str], list[bool]], Sequence[str]] | None = None,
) -> tuple[list[str], FloatArray]:
    """
    Read a CSV file whose columns are all numeric (or the columns `select` names).

    Used by the command line: the input signal is the first column not named
    ``time``; a ``time`` column passes through to the output file.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file with a header row.
    comment : str or None, optional
        Prefix of comment lines; None to disable.
    drop_nonfinite : bool, optional
        Drop rows holding NaN/Inf or an empty field (instead of raising).
    nonfinite_hint : str, optional
        What the NaN/Inf error tells the user to do (callers name their own
        options).
    select : callable, optional
        Given the header and whether each column's first data field is a
        number, returns the names of the columns to read (it may raise with a
        message naming the option); the other columns may hold text and are
        ignored. Default: every column.

    Returns
    -------
    header : list of str
        Column names read, in file order.
    table : ndarray of float, shape (N, M)
        The values, one row per data line, in the units of the file.

    Raises
    ------
    DataError
        If the file is missing, empty or has no header; it has no column
        besides ``time``; a field is not a number (line and column named);
        rows are ragged; there is no data row; or a value is NaN/Inf or empty
        (without `drop_nonfinite`).

    """
    source = Path(path)
    table = _read_csv_rows(source, comment=comment)
    if not [name for name in table.header if name != 'time']:
        msg = (f'CSV file {source} has no column besides the time column; add a column '
               'with the input signal')
        raise DataError(msg)
    if not table.rows:
        msg = f'CSV file {source} has a header but no data rows; add the samples'
        raise DataError(msg)
    notes: list[str] = []
    header = list(table.header)
    numeric = [_NUMBER.fullmatch(field) is not None for field in table.rows[0]]
    # A first row without a single number (another delimiter, a second header line) is
    # reported by the numeric check of every column, not by the selection.
    chosen = (set(select(header, numeric)) if select is not None and any(numeric)
              else set(header))
    indices = [index for index, name in enumerate(header) if name in chosen]
    columns, keep = _numeric_columns(table, indices, drop_nonfinite=drop_nonfinite,
                                     notes=notes, hint=nonfinite_hint)
    if not np.any(keep):
        msg = f'CSV file {source}: every row holds NaN/Inf or an empty field; no data left'
        raise DataError(msg)
    data = np.column_stack([columns[index][keep] for index in indices])
    return [header[index] for index in indices], data.astype(np.float64)


def write_csv_columns(
    path: PathLike,
    columns: Mapping[str, npt.ArrayLike],
    *,
    comment: str | None = None,
) -> None:
    """
    Write equal-length columns to a CSV file atomically.

    Values are written with the shortest representation that reads back to
    the same float64 (``repr``), so a write/read round trip is exact.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file to create or replace (see :func:`atomic_write`).
    columns : mapping of str to array_like of float, shape (N,)
        Column name → values, in column order. Names must be non-empty and
        hold no comma, quote or line break.
    comment : str, optional
        Text written first, each line prefixed with ``'# '`` (e.g. provenance).

    Raises
    ------
    DataError
        If there are no columns, a name is invalid, the columns differ in
        length or are not one-dimensional numbers, or the file cannot be
        written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / 'out.csv'
    >>> write_csv_columns(out, {'time': [0.0, 0.5], 'current': [0.1, 0.2]})
    >>> print(out.read_text(), end='')
    time,current
    0.0,0.1
    0.5,0.2

    """
    target = Path(path)
    if not columns:
        msg = f'write_csv_columns({target}): no columns given; pass at least one column'
        raise DataError(msg)
    for name in columns:
        valid = isinstance(name, str) and bool(name) and name == name.strip()
        if not valid or any(char in name for char in ',"\r\n#'):
            msg = (f'write_csv_columns({target}): invalid column name {name!r}; use a '
                   'non-empty name without commas, quotes, line breaks or a leading #')
            raise DataError(msg)
    arrays = equal_length_arrays(dict(columns), what=f'write_csv_columns({target})')
    rows = np.column_stack(list(arrays.values())).tolist() if arrays else []
    with atomic_write(target) as handle:
        if comment is not None:
            for line in str(comment).splitlines() or ['']:
                handle.write(f'# {line}'.rstrip() + '\n')
        handle.write(','.join(arrays) + '\n')
        handle.writelines(','.join(map(repr, row)) + '\n' for row in rows)


@dataclass(frozen=True)
class _Table:
    path: Path
    header: list[str]
    header_line: int
    rows: list[list[str]]
    line_numbers: list[int]


def _read_csv_rows(source: Path, *, comment: str | None) -> _Table:
    """Split a CSV file into header and rows of stripped strings, with line numbers."""
    if not source.exists():
        msg = f'CSV file {source} does not exist; check the path'
        raise DataError(msg)
    if source.is_dir():
        msg = f'{source} is a directory, not a CSV file; pass a CSV file'
        raise DataError(msg)
    if source.is_char_device() or source.is_block_device():
        msg = (f'{source} is a device, not a CSV file (it may never end); pass a CSV file, '
               'or a pipe')
        raise DataError(msg)
    try:
        raw = source.read_bytes()
    except OSError as err:
        msg = f'cannot read CSV file {source}: {err}'
        raise DataError(msg) from err
    except MemoryError as err:
        msg = (f'CSV file {source} does not fit in memory; cut it into shorter records (or '
               'record a bag) and pass those')
        raise DataError(msg) from err
    try:
        text = raw.decode('utf-8-sig')
    except UnicodeDecodeError as err:
        line = raw[:err.start].count(b'\n') + 1
        msg = (f'CSV file {source} line {line} is not UTF-8 text (byte {err.start}: '
               f'{err.reason}); save the file as UTF-8 CSV')
        raise DataError(msg) from err
    if not text.strip():
        msg = (f'CSV file {source} is empty; expected a header row (e.g. '
               'time,current,displacement) followed by data rows')
        raise DataError(msg)
    kept: list[int] = []

    def lines() -> Iterator[str]:
        for number, line in enumerate(text.split('\n'), start=1):
            stripped = line.strip()
            if not stripped or (comment and stripped.startswith(comment)):
                continue
            kept.append(number)
            yield line.rstrip('\r')

    header: list[str] | None = None
    header_line = 0
    rows: list[list[str]] = []
    line_numbers: list[int] = []
    reader = csv.reader(lines(), strict=True)
    while True:
        try:
            fields = next(reader)
        except StopIteration:
            break
        except csv.Error as err:
            line = kept[-1] if kept else 1
            msg = f'CSV file {source} line {line} is not valid CSV ({err}); fix the line'
            raise DataError(msg) from err
        line = kept[reader.line_num - 1]
        fields = [field.strip() for field in fields]
        if header is None:
            header, header_line = fields, line
        else:
            rows.append(fields)
            line_numbers.append(line)
    if header is None:
        msg = (f'CSV file {source} has only comments; expected a header row (e.g. '
               'time,current,displacement) followed by data rows')
        raise DataError(msg)
    if all(_NUMBER.fullmatch(name) for name in header):
        msg = (f'CSV file {source} has no header row: line {header_line} holds numbers; '
               'add a first line naming the columns, e.g. time,current,displacement')
        raise DataError(msg)
    for position, name in enumerate(header, start=1):
        if not name:
            msg = (f'CSV file {source} header (line {header_line}) has an empty name for '
                   f'column {position}; name every column')
            raise DataError(msg)
    duplicates = sorted({name for name in header if header.count(name) > 1})
    if duplicates:
        msg = (f'CSV file {source} header (line {header_line}) repeats column name(s) '
               f'{_names(duplicates)}; make the names unique')
        raise DataError(msg)
    for fields, line in zip(rows, line_numbers):
        if len(fields) != len(header):
            msg = (f'CSV file {source} line {line} has {len(fields)} field(s) but the header '
                   f'(line {header_line}) has {len(header)}; fix the row or the header')
            raise DataError(msg)
    return _Table(source, header, header_line, rows, line_numbers)


def _names(names: Sequence[str]) -> str:
    return ', '.join(repr(name) for name in names)


def _column_index(table: _Table, name: str, *, option: str, options: DataOptions) -> int:
    if name in table.header:
        return table.header.index(name)
    msg = (f'CSV file {table.path} has no column {name!r} ({options.name(option)}); '
           f'available columns: {_names(table.header)}')
    if option == 'time_column':
        none = 'None' if options.spelling == 'keyword' else "''"
        msg += (f'; pass {options.setting(option, "<name>")}, or '
                f'{options.setting(option, none)} if the file has no time column')
    raise DataError(msg)


def _numeric_columns(
    table: _Table,
    indices: Sequence[int],
    *,
    drop_nonfinite: bool,
    notes: list[str],
    hint: str,
) -> tuple[dict[int, FloatArray], npt.NDArray[np.bool_]]:
    """
    Parse the columns `indices`; return them and the mask of the rows to keep.

    An empty field is a missing value, like NaN and Inf (pandas writes NaN as an empty
    field): such rows are dropped (with a note) when `drop_nonfinite`, else refused. Any
    other field that is not a number is refused. Without `drop_nonfinite` the message names
    the first bad field in file order (row by row, left to right), whichever kind it is.
    """
    n = len(table.rows)
    order = sorted(indices)
    values: dict[int, FloatArray] = {}
    bad = np.zeros(n, dtype=bool)                     # rows with NaN, Inf or an empty field
    text: tuple[int, int, str] | None = None          # first field that is not a number
    for index in order:
        fields = [row[index] for row in table.rows]
        empty = np.array([not field for field in fields], dtype=bool)
        number = np.array([_NUMBER.fullmatch(field) is not None for field in fields],
                          dtype=bool)
        column = np.full(n, np.nan)
        column[number] = np.array([f for f, ok in zip(fields, number) if ok], dtype=np.float64)
        values[index] = column
        bad |= empty | (number & ~np.isfinite(column))
        wrong = np.flatnonzero(~empty & ~number)
        if wrong.size and (text is None or wrong[0] < text[0]):   # left to right: ties keep
            text = (int(wrong[0]), index, fields[int(wrong[0])])  # the leftmost column
    first = int(np.flatnonzero(bad)[0]) if bad.any() else n
    if text is not None and (drop_nonfinite or text[0] <= first):
        row, index, field = text
        msg = (f'CSV file {table.path} line {table.line_numbers[row]}, column '
               f'{table.header[index]!r} (column {index + 1}): expected a number, found '
               f'{field[:40]!r}; fix the value or remove the row')
        raise DataError(msg)
    n_bad = int(np.count_nonzero(bad))
    if n_bad and not drop_nonfinite:
        index = next(i for i in order if not math.isfinite(values[i][first]))
        field = table.rows[first][index]
        found = 'an empty field' if not field else repr(field[:40])
        msg = (f'CSV file {table.path} has {n_bad} row(s) with non-finite values (NaN, Inf '
               f'or empty fields), the first at line {table.line_numbers[first]}, column '
               f'{table.header[index]!r} ({found}); fix the data or {hint}')
        raise DataError(msg)
    if n_bad:
        notes.append(f'dropped {n_bad} row(s) with non-finite values (NaN, Inf or empty '
                     'fields)')
    return values, ~bad


def _check_row_count(table: _Table, n_rows: int, *, after_drop: bool = False) -> None:
    if n_rows < MIN_SAMPLES:
        extra = ' after dropping non-finite rows' if after_drop else ''
        msg = (f'CSV file {table.path} has only {n_rows} data row(s){extra}; a recording '
               f'needs at least {MIN_SAMPLES}; record longer')
        raise DataError(msg)
