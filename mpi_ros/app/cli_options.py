# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Command-line pieces shared by ``mpi-ros`` and ``mpi-ros diagnose``.

* :class:`ArgumentParser`: argparse whose usage errors raise :class:`UsageError`
  (printed as ``error: ...``, exit status 1) instead of exiting with status 2.
* :func:`add_data_options` / :func:`data_options`: the data options of
  :data:`mpi_ros.recordings.DATA_OPTIONS` as ``--options``, turned into one
  :class:`~mpi_ros.recordings.DataOptions`.
* :func:`add_order_option` / :func:`order_option`: ``--order auto|N,L|N L``,
  parsed by :func:`mpi_ros.order.parse_order`.
* :func:`check_outputs`: no output replaces an input (or another output), before any work.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
import sys
from typing import Any, Mapping, NoReturn, Sequence

from ..errors import MPIError
from ..order import Order, parse_order
from ..recordings.options import DATA_OPTIONS, DataOptions, JOINT_FIELDS

__all__ = ['ArgumentParser', 'UsageError', 'add_data_options', 'data_options',
           'add_order_option', 'order_option', 'check_outputs']


class UsageError(MPIError, ValueError):
    """The command line is malformed (unknown option, missing argument, bad value)."""


class ArgumentParser(argparse.ArgumentParser):
    """
    An argparse parser whose usage errors exit with status 1, not 2.

    :meth:`error` prints the usage to stderr and raises :class:`UsageError`;
    the command's ``main`` prints ``error: ...`` and returns 1, as for every
    other error. Subcommand parsers made by ``add_subparsers`` are of this
    class too.
    """

    def error(self, message: str) -> NoReturn:
        """
        Print the usage and raise :class:`UsageError` with `message`.

        Parameters
        ----------
        message : str
            What is wrong, as argparse words it.

        Raises
        ------
        UsageError
            Always.

        """
        self.print_usage(sys.stderr)
        raise UsageError(f'{self.prog}: {message}')


def add_data_options(parser: argparse.ArgumentParser,
                     names: Sequence[str] | None = None, *,
                     descriptions: Mapping[str, str] | None = None) -> None:
    """
    Add the data options (``--input-topic`` ... ``--drop-nonfinite``) to a parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The (sub)command's parser.
    names : sequence of str, optional
        Only these options (attribute names, e.g. ``['input_column']``);
        default: all of :data:`~mpi_ros.recordings.DATA_OPTIONS`.
    descriptions : Mapping[str, str], optional
        Help texts that replace the shared ones for this command.

    """
    group = parser.add_argument_group(
        'data options', 'which signals of a bag or CSV file are the input and output')
    defaults = DataOptions()
    for option in DATA_OPTIONS:
        if names is not None and option.name not in names:
            continue
        unit = f' [{option.unit}]' if option.unit else ''
        default = getattr(defaults, option.name)
        shown = '' if default is None or option.kind == 'bool' else f' (default: {default})'
        description = (descriptions or {}).get(option.name, option.description)
        text = f'{description}{unit}{shown}'
        if option.applies != 'any' and names is None:
            text += f'; {option.applies} only'
        kwargs: dict[str, Any] = {'help': text, 'dest': option.name}
        if option.kind == 'bool':
            kwargs['action'] = 'store_true'
        elif option.kind == 'float':
            kwargs.update(type=float, default=default, metavar='F')
        elif option.kind == 'optional_int':
            kwargs.update(type=int, default=default, metavar='I')
        elif option.kind == 'optional_float':
            kwargs.update(type=float, default=default, metavar='S')
        elif option.kind == 'choice':
            kwargs.update(choices=JOINT_FIELDS, default=default)
        else:
            kwargs.update(default=default, metavar='NAME')
        group.add_argument(option.flag, **kwargs)


def data_options(args: argparse.Namespace) -> DataOptions:
    """
    Build the :class:`~mpi_ros.recordings.DataOptions` of parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        Arguments of a parser given :func:`add_data_options`.

    Returns
    -------
    DataOptions
        Spelled as on the command line (messages say ``--input-topic``).

    Raises
    ------
    mpi_ros.errors.DataError
        If an option value is invalid.

    """
    return DataOptions.from_mapping(vars(args), spelling='cli')


def add_order_option(parser: argparse.ArgumentParser, default: str) -> None:
    """
    Add ``--order auto|N,L|N L`` to a parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The (sub)command's parser.
    default : str
        The default, as the user would write it (``'auto'``, ``'14,7'``).

    """
    parser.add_argument('--order', nargs='+', default=[default], metavar='auto|N,L',
                        help="model order: 'auto' (chosen by the fit errors), N,L or N L "
                             f'(N play, L dead-zone operators; default {default})')


def order_option(args: argparse.Namespace) -> Order:
    """
    Parse the ``--order`` words of `args`, parsed by a parser given :func:`add_order_option`.

    Returns
    -------
    'auto' or tuple of (int, int)
        See :func:`mpi_ros.order.parse_order`.

    Raises
    ------
    mpi_ros.errors.IdentificationError
        If the words are not an order; the message names ``--order``.

    """
    return parse_order(args.order, option='--order')


def check_outputs(inputs: Sequence[tuple[str, str | None]],
                  outputs: Sequence[tuple[str, str | None]]) -> None:
    """
    Refuse, before any work, an output that would replace an input or another output.

    Paths are compared as files (``os.path.samefile``: through symbolic and hard links)
    and as resolved paths (for outputs not written yet); an output inside an input
    directory (a bag) counts as replacing it.

    Parameters
    ----------
    inputs : sequence of (option, path or None)
        The files and bag directories the command reads, e.g. ``('DATA', 'd.csv')``.
    outputs : sequence of (option, path or None)
        The files the command writes, e.g. ``('--output', 'p.yaml')``.

    Raises
    ------
    UsageError
        Naming both options and what to do; nothing has been written.

    """
    from ..recordings.files import same_file
    given = [(option, path) for option, path in outputs if path]
    for k, (option, path) in enumerate(given):
        real = os.path.realpath(path)
        for source, data in inputs:
            if not data:
                continue
            inside = _is_bag_folder(Path(data)) and Path(real).is_relative_to(
                os.path.realpath(data))
            if same_file(path, data):
                msg = (f'{option} {path} is the input {source} {data}: writing it would '
                       'destroy the input; choose another output path (nothing was written)')
                raise UsageError(msg)
            if inside:
                msg = (f'{option} {path} is inside the input bag {source} {data}: writing it '
                       'would change the input; choose another output path (nothing was '
                       'written)')
                raise UsageError(msg)
        for other, earlier in given[:k]:
            if same_file(path, earlier):
                msg = (f'{option} {path} and {other} {earlier} are the same file; give each '
                       'output its own path (nothing was written)')
                raise UsageError(msg)


def _is_bag_folder(path: Path) -> bool:
    # A folder the command reads as a bag (another folder is refused by the reader).
    try:
        return path.is_dir() and any(
            entry.name == 'metadata.yaml' or entry.suffix.lower() in ('.db3', '.mcap')
            for entry in path.iterdir())
    except OSError:
        return False
