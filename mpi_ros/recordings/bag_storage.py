# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The storage files of a rosbag2 bag: find them, finish an unfinished mcap, refuse damaged ones.

A bag is a directory with ``metadata.yaml`` and one or more sqlite3 (``.db3``) or
mcap (``.mcap``) files, or one such file alone. :func:`locate_bag` finds what to
hand to rosbags' ``Reader``; :func:`finish_unfinished_mcap` makes a readable copy
of the mcap a killed recorder leaves; :func:`check_sqlite_file` and
:func:`check_message_counts` refuse a truncated or corrupt bag that would
otherwise read with changed or missing samples. Every refusal is a
:class:`~mpi_ros.errors.DataError` built by :func:`corrupt_bag`.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Any

from ..errors import DataError

__all__ = ['BAG_SUFFIXES', 'check_message_counts', 'check_sqlite_file', 'corrupt_bag',
           'finish_unfinished_mcap', 'locate_bag']

#: Suffixes of rosbag2 storage files.
BAG_SUFFIXES = ('.db3', '.mcap')


def locate_bag(bag: Path) -> tuple[Path, list[str]]:
    """Return the path to hand to rosbags' Reader and initial notes."""
    if not bag.exists():
        msg = (f'bag {bag} does not exist; check the path (a rosbag2 bag is a directory '
               'holding metadata.yaml and a .db3 or .mcap file)')
        raise DataError(msg)
    if bag.is_file() and bag.name == 'metadata.yaml':
        return bag.parent, []
    if bag.is_file():
        if bag.suffix.lower() in BAG_SUFFIXES:
            return bag, []
        msg = (f'{bag} is not a rosbag2 bag: expected a bag directory or a .db3/.mcap file, '
               f'found a {bag.suffix or "suffix-less"} file; use read_csv_signals for CSV')
        raise DataError(msg)
    if (bag / 'metadata.yaml').is_file():
        return bag, []
    files = sorted(p for p in bag.iterdir() if p.suffix.lower() in BAG_SUFFIXES)
    if len(files) == 1:
        note = (f'{bag} has no metadata.yaml (the recording was probably interrupted); '
                f'read the storage file {files[0].name} directly')
        return files[0], [note]
    if not files:
        msg = (f'{bag} is not a rosbag2 bag: it holds no metadata.yaml and no .db3/.mcap '
               'file; pass the bag directory that `ros2 bag record` created')
        raise DataError(msg)
    msg = (f'{bag} has no metadata.yaml and {len(files)} storage files; run '
           f'`ros2 bag reindex {bag}` or pass one of {[p.name for p in files]}')
    raise DataError(msg)


def corrupt_bag(bag: Path, err: BaseException) -> DataError:
    """Return the error for a bag that cannot be read: truncated or corrupt, how to repair it."""
    msg = (f'cannot read bag {bag}: {type(err).__name__}: {err}; the bag is truncated or '
           'corrupt (e.g. the recorder was killed); re-record it, or repair it '
           '(`sqlite3 in.db3 .recover | sqlite3 out.db3`, `mcap recover`) and retry')
    return DataError(msg)


#: The magic that starts and ends an mcap file.
_MCAP_MAGIC = b'\x89MCAP0\r\n'


def finish_unfinished_mcap(bag: Path, path: Path,
                           stack: contextlib.ExitStack) -> tuple[Path, str] | None:
    """
    Return a finished copy of an mcap a killed recorder left, and a note; None if finished.

    The copy ends after the last complete record (the chunks the recorder finished) with a
    data-end record and a footer without a summary, which the reader scans; each chunk's
    CRC is still checked as it is read.
    """
    import struct
    import tempfile
    try:
        data = path.read_bytes()
    except OSError as err:
        raise corrupt_bag(bag, err) from err
    if not data.startswith(_MCAP_MAGIC) or data.endswith(_MCAP_MAGIC):
        return None
    end = position = len(_MCAP_MAGIC)
    chunks = 0
    while position + 9 <= len(data):
        op, length = data[position], struct.unpack_from('<Q', data, position + 1)[0]
        if op == 0 or op > 0x10 or position + 9 + length > len(data):
            break                                   # zeros or a record cut short
        if op == 0x0F:                              # data end: the summary follows
            break
        position += 9 + length
        end = position
        chunks += op == 0x06
    footer = (b'\x0f' + struct.pack('<QI', 4, 0) + b'\x02' + struct.pack('<QQQI', 20, 0, 0, 0)
              + _MCAP_MAGIC)
    folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix='mpi_ros_mcap_')))
    copy = folder / path.name
    copy.write_bytes(data[:end] + footer)
    note = (f'{path.name} was not finished (the recorder was killed or is still running): '
            f'read its {chunks} complete chunk(s), {len(data) - end} byte(s) after them '
            'dropped')
    return copy, note


def check_sqlite_file(bag: Path, path: Path) -> None:
    """
    Refuse a sqlite3 storage file that is cut short or fails SQLite's ``quick_check``.

    SQLite reads the missing end of a truncated file as zeros, so a bag cut by one byte
    reads without an error and with a changed sample; its size is then no longer a whole
    number of pages, or smaller than the page count its header records.
    """
    import sqlite3
    try:
        size = path.stat().st_size
        with path.open('rb') as f:
            header = f.read(100)
    except OSError as err:
        raise corrupt_bag(bag, err) from err
    if len(header) < 100 or not header.startswith(b'SQLite format 3\x00'):
        raise corrupt_bag(bag, ValueError(f'{path.name} is not an SQLite database'))
    page_size = int.from_bytes(header[16:18], 'big')
    page_size = 65536 if page_size == 1 else page_size
    pages = int.from_bytes(header[28:32], 'big')
    header_valid = header[24:28] == header[92:96]       # the page count is kept up to date
    if page_size < 512 or size % page_size or (header_valid and pages * page_size > size):
        problem = (f'{path.name} holds {size} bytes, not the whole {page_size}-byte pages its '
                   f'header records ({pages} pages)')
        raise corrupt_bag(bag, ValueError(problem))
    try:
        connection = sqlite3.connect(f'{path.resolve().as_uri()}?mode=ro', uri=True)
        try:
            rows = connection.execute('PRAGMA quick_check').fetchmany(3)
        finally:
            connection.close()
    except sqlite3.Error as err:
        raise corrupt_bag(bag, err) from err
    if rows != [('ok',)]:
        found = '; '.join(str(row[0]) for row in rows)
        raise corrupt_bag(bag, ValueError(f'{path.name} fails the SQLite quick_check: {found}'))


def check_message_counts(bag: Path, connections: list[Any], counts: dict[str, int]) -> None:
    """Refuse a bag with fewer messages on a topic than its metadata.yaml records."""
    for topic, count in counts.items():
        recorded = sum(int(getattr(conn, 'msgcount', 0) or 0) for conn in connections
                       if conn.topic == topic)
        if count < recorded:
            problem = (f'topic {topic} has {count} messages, its metadata.yaml records '
                       f'{recorded}')
            raise corrupt_bag(bag, ValueError(problem))
