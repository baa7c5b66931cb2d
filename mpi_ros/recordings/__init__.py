# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Recorded actuator signals: rosbag2 bags and CSV files.

An MPI model Γ = S∘H (26) is identified from pairs of samples of the actuator
input x (coil current [A]) and output s (displacement [m]). This package reads
such pairs from rosbag2 bags (sqlite3 or mcap, through rosbags) and from CSV
files into a :class:`Recording`, writes them back, and provides the atomic
file writes every command-line output goes through.

Modules: :mod:`.recording` (the :class:`Recording`), :mod:`.options` (the
:class:`DataOptions` shared by the command line, the identifier node and the
diagnosis), :mod:`.bag_reader` (pairs the two topics of a bag), :mod:`.messages`
(one reader per message type, in the registry :data:`MESSAGE_READERS`),
:mod:`.bag_storage` (finding and checking a bag's storage files), :mod:`.bag_writer`,
:mod:`.csv_files`, :mod:`.reading` (:func:`read_recording`: bag or CSV by the path) and
:mod:`.files` (atomic writes).

The package is ROS-free: it uses the pure-Python ``rosbags`` library and never
imports ``rclpy``, so bags can be read and written on machines without ROS.

Every problem with a file or its content raises :class:`~mpi_ros.errors.DataError`
with a message naming the file, the topic or column, what was found and what to
do about it.
"""

from .bag_reader import read_bag_signals
from .bag_writer import BagRecorder, write_bag_signals
from .csv_files import read_csv_signals, read_csv_table, write_csv_columns
from .files import atomic_write, atomic_writes, same_file, write_target
from .messages import MESSAGE_READERS, MessageReader, Selection, SelectionError
from .options import DATA_OPTIONS, DataOption, DataOptions, JOINT_FIELDS
from .reading import read_recording, read_signals
from .recording import join_recordings, MIN_SAMPLES, Recording

__all__ = [
    'MIN_SAMPLES',
    'Recording',
    'join_recordings',
    'BagRecorder',
    'DataOptions',
    'DataOption',
    'DATA_OPTIONS',
    'JOINT_FIELDS',
    'MessageReader',
    'MESSAGE_READERS',
    'Selection',
    'SelectionError',
    'read_recording',
    'read_signals',
    'read_bag_signals',
    'write_bag_signals',
    'read_csv_signals',
    'read_csv_table',
    'write_csv_columns',
    'atomic_write',
    'atomic_writes',
    'same_file',
    'write_target',
]
