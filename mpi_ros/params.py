# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Parameter files: a model's parameter form as a ROS 2 YAML parameter file, and back.

The keys and their checks are the model's (:mod:`mpi_ros.operators.model`:
``MODEL_KEYS``, ``check_model_parameters``); a file nests them under
``<node>: ros__parameters:``, as ``ros2 param dump`` writes and ``ros2 param load`` and
``--params-file`` read.

A parameter file is read with limits (:func:`load_params_document`): at most
:data:`MAX_FILE_BYTES` bytes, mappings and lists nested at most :data:`MAX_DEPTH` deep,
and no YAML aliases (``*name``), so that neither a deeply nested file nor an alias bomb
(nested anchors that expand to billions of items) can exhaust the stack or the memory.
Every fault is one :class:`~mpi_ros.errors.DataError` line.
"""

from collections.abc import Iterable, Mapping
import difflib
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .errors import DataError, ModelError

__all__ = ['MAX_DEPTH', 'MAX_FILE_BYTES', 'closest_key', 'flatten_parameters',
           'load_params_document', 'params_yaml_text', 'read_params_yaml', 'unknown_keys',
           'write_params_yaml']

#: Deepest nesting of mappings and lists a parameter file may have (a model file has 5).
MAX_DEPTH = 32
#: Largest parameter file read [bytes] (a 16-axis model with effects is below 100 kB).
MAX_FILE_BYTES = 16 * 2**20


class _LimitedLoader(yaml.SafeLoader):
    """PyYAML's safe loader without aliases and with a nesting limit."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()  # type: ignore[no-untyped-call]
            raise yaml.composer.ComposerError(
                None, None, f'found the alias *{event.anchor}; YAML aliases are not allowed '
                'in a parameter file (write the values out)', event.start_mark)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                event = self.peek_event()  # type: ignore[no-untyped-call]
                raise yaml.composer.ComposerError(
                    None, None, f'found mappings or lists nested more than {MAX_DEPTH} deep (a '
                    'parameter file nests a few levels)',
                    event.start_mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def flatten_parameters(tree: Mapping[str, Any], prefix: str = '') -> dict[str, Any]:
    """
    Flatten nested YAML mappings into dotted ROS parameter names.

    Parameters
    ----------
    tree : Mapping
        E.g. ``{'model': {'hysteresis': {'weights': [...]}}}``.
    prefix : str
        Prefix for the names (used in recursion).

    Returns
    -------
    dict[str, Any]
        E.g. ``{'model.hysteresis.weights': [...]}``.

    """
    flat: dict[str, Any] = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, Mapping):
            flat.update(flatten_parameters(value, f'{name}.'))
        else:
            flat[name] = value
    return flat


def _nest(flat: Mapping[str, Any]) -> dict[str, Any]:
    tree: dict[str, Any] = {}
    for name, value in flat.items():
        node = tree
        parts = name.split('.')
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        if isinstance(value, np.ndarray):
            value = [float(v) for v in value]
        elif isinstance(value, (list, tuple)):
            value = [float(v) if isinstance(v, (float, np.floating)) else v for v in value]
        node[parts[-1]] = value
    return tree


def write_params_yaml(path: str | os.PathLike[str], parameters: Mapping[str, Any], *,
                      node_name: str = 'compensator', header: str | None = None) -> None:
    """
    Write a ROS 2 parameter file ``{node_name: {ros__parameters: ...}}`` atomically.

    Parameters
    ----------
    path : str or PathLike
        Target file; written to a temporary file beside it and renamed.
    parameters : Mapping[str, Any]
        Dotted parameter names to values (e.g. ``model.to_params()``).
    node_name : str
        Node the parameters are keyed by (``--params-file`` loads them into a
        node of that name).
    header : str, optional
        Comment lines written at the top of the file.

    Notes
    -----
    Written by :func:`mpi_ros.recordings.atomic_write`: a temporary file beside the
    target, synced and renamed over it; a symbolic link is written through (the link
    stays) and a file being replaced keeps its mode.

    """
    text = params_yaml_text(parameters, node_name=node_name, header=header)
    from .recordings.files import atomic_write   # lazy: the recordings layer loads rosbags
    with atomic_write(path) as handle:
        handle.write(text)


def params_yaml_text(parameters: Mapping[str, Any], *, node_name: str = 'compensator',
                     header: str | None = None) -> str:
    """
    Return the text of the parameter file :func:`write_params_yaml` writes.

    Parameters
    ----------
    parameters : Mapping[str, Any]
        Dotted parameter names to values.
    node_name : str
        Node the parameters are keyed by.
    header : str, optional
        Comment lines at the top of the file.

    Returns
    -------
    str
        The YAML text.

    Raises
    ------
    ModelError
        When a value is not finite.

    """
    for name, value in parameters.items():
        values = value if isinstance(value, (list, tuple, np.ndarray)) else [value]
        for v in values:
            if isinstance(v, float) and not math.isfinite(v):
                msg = f'refusing to write non-finite value {v} for parameter {name}'
                raise ModelError(msg)
    document = {node_name: {'ros__parameters': _nest(parameters)}}
    text = yaml.safe_dump(document, default_flow_style=None, sort_keys=False, width=99)
    if header:
        text = ''.join(f'# {line}\n' for line in header.splitlines()) + text
    return text


def load_params_document(path: str | os.PathLike[str]) -> Any:
    """
    Read a YAML parameter file with limits: its size, its nesting and no aliases.

    Parameters
    ----------
    path : str or PathLike
        The YAML file.

    Returns
    -------
    Any
        The document (a mapping for a parameter file; not checked here).

    Raises
    ------
    DataError
        When the file is missing, larger than :data:`MAX_FILE_BYTES`, not UTF-8, not
        YAML, nested deeper than :data:`MAX_DEPTH` or holds an alias; one line naming
        the file, the line and column, and what to do.

    """
    target = Path(path)
    try:
        with target.open('rb') as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError as err:
        msg = f'parameter file {target} does not exist'
        raise DataError(msg) from err
    except OSError as err:
        msg = f'cannot read parameter file {target}: {err.strerror or err}'
        raise DataError(msg) from err
    if len(raw) > MAX_FILE_BYTES:
        msg = (f'parameter file {target} is larger than {MAX_FILE_BYTES // 2**20} MiB; a '
               'parameter file is a few kB: check the path')
        raise DataError(msg)
    try:
        text = raw.decode('utf-8')
    except UnicodeDecodeError as err:
        msg = (f'cannot read parameter file {target}: byte {err.start} is not UTF-8 text; '
               'give a YAML parameter file')
        raise DataError(msg) from err
    loader = _LimitedLoader(text)
    try:
        return loader.get_single_data()
    except yaml.YAMLError as err:
        msg = f'cannot read parameter file {target}: not valid YAML: {_one_line(err)}'
        raise DataError(msg) from err
    except RecursionError as err:  # pragma: no cover - the depth limit comes first
        msg = f'parameter file {target} is nested too deeply'
        raise DataError(msg) from err
    finally:
        loader.dispose()


def unknown_keys(parameters: Iterable[str], known: Iterable[str], *,
                 prefixes: Iterable[str] = ()) -> list[str]:
    """
    Return the names of `parameters` that are neither in `known` nor under `prefixes`.

    Parameters
    ----------
    parameters : iterable of str
        Dotted parameter names (as :func:`read_params_yaml` returns).
    known : iterable of str
        The names a reader uses.
    prefixes : iterable of str
        Name prefixes accepted whatever follows (e.g. ``'qos_overrides.'``).

    Returns
    -------
    list of str
        The unknown names, in the order given.

    """
    names = set(known)
    starts = tuple(prefixes)
    return [name for name in parameters
            if name not in names and not (starts and name.startswith(starts))]


def closest_key(name: str, known: Iterable[str]) -> str | None:
    """
    Return the known name closest to `name` (a likely typo), or None when none is close.

    Parameters
    ----------
    name : str
        An unknown dotted parameter name, e.g. ``'model.output_ofset'``.
    known : iterable of str
        The names a reader uses.

    Returns
    -------
    str or None
        E.g. ``'model.output_offset'`` (``difflib``, similarity at least 0.6).

    """
    found = difflib.get_close_matches(name, list(known), n=1, cutoff=0.6)
    return found[0] if found else None


def _one_line(err: yaml.YAMLError) -> str:
    # PyYAML's message spans 4-7 lines (context, problem, a caret drawing); one line here.
    if isinstance(err, yaml.MarkedYAMLError):
        mark = err.problem_mark or err.context_mark
        where = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        what = ' '.join(part for part in (err.context, err.problem) if part)
        return f'{what}{where}'
    return ' '.join(str(err).split())


def read_params_yaml(path: str | os.PathLike[str], *,
                     node_name: str = 'compensator') -> dict[str, Any]:
    """
    Read a ROS 2 parameter file and return the flat parameters of one node.

    Parameters
    ----------
    path : str or PathLike
        The YAML file.
    node_name : str
        Node whose ``ros__parameters`` to return; ``/**`` (all nodes) entries
        are merged underneath.  If the file has exactly one node entry, that
        one is used whatever its name.

    Returns
    -------
    dict[str, Any]
        Dotted parameter names to values.

    Raises
    ------
    DataError
        When the file is missing, not YAML (or beyond the limits of
        :func:`load_params_document`), or has no parameters for the node.

    """
    target = Path(path)
    document = load_params_document(target)
    if not isinstance(document, Mapping):
        msg = f'parameter file {target} must map node names to ros__parameters'
        raise DataError(msg)
    keys = [k for k in document if isinstance(document[k], Mapping)
            and 'ros__parameters' in document[k]]
    chosen = [k for k in keys if str(k).lstrip('/') == node_name]
    if not chosen and len(keys) == 1:
        chosen = keys
    merged: dict[str, Any] = {}
    for key in [k for k in keys if k == '/**'] + [k for k in chosen if k != '/**']:
        merged.update(flatten_parameters(document[key]['ros__parameters']))
    if not merged:
        msg = (f'parameter file {target} has no ros__parameters for node {node_name!r};'
               f' found entries for: {", ".join(map(str, keys)) or "none"}')
        raise DataError(msg)
    return merged
