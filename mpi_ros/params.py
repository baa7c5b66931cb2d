# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Parameter files: a model's parameter form as a ROS 2 YAML parameter file, and back.

The keys and their checks are the model's (:mod:`mpi_ros.operators.model`:
``MODEL_KEYS``, ``check_model_parameters``); a file nests them under
``<node>: ros__parameters:``, as ``ros2 param dump`` writes and ``ros2 param load`` and
``--params-file`` read.
"""

from collections.abc import Mapping
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .errors import DataError, ModelError

__all__ = ['flatten_parameters', 'read_params_yaml', 'write_params_yaml']


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
    target = Path(path)
    tmp = target.with_name(f'.{target.name}.tmp{os.getpid()}')
    try:
        tmp.write_text(text, encoding='utf-8')
        os.replace(tmp, target)
    finally:
        if tmp.exists():
            tmp.unlink()


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
        When the file is missing, not YAML, or has no parameters for the node.

    """
    target = Path(path)
    try:
        document = yaml.safe_load(target.read_text(encoding='utf-8'))
    except FileNotFoundError as err:
        msg = f'parameter file {target} does not exist'
        raise DataError(msg) from err
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
        msg = f'cannot read parameter file {target}: {err}'
        raise DataError(msg) from err
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
