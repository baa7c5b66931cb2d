# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Parameter form of an MPI model: the keys the compensator node reads, and YAML I/O.

The forward model Gamma = S o H is stored in SI units (A, m) under

- ``model.hysteresis.thresholds`` (r_H, ascending from 0, A),
- ``model.hysteresis.weights`` (w_H, dimensionless),
- ``model.hysteresis.initial_states`` (z_H0, A),
- ``model.superposition.thresholds`` (r_S, ascending with exactly one 0, A),
- ``model.superposition.weights`` (w_S, m/A),

and its operating point (optional; not in the paper, whose actuator rests at the origin):

- ``model.input_offset`` (x0, A, default 0.0): the input at which H's plays are centred,
- ``model.output_offset`` (y0, m, default 0.0): the sensor reading the model adds,
- ``model.output_sign`` (+1 or -1, default +1): -1 for a sensor that falls as the
  actuator extends,

so that ``y = y0 + sign * S[H[x - x0]]``.

:func:`check_model_parameters` validates such a mapping completely (lengths,
ordering, finiteness, the constraints (8) and (19)) and names the offending key.
A ROS 2 parameter file nests these keys under ``<node>: ros__parameters:``.
"""

from collections.abc import Mapping
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import yaml

from .errors import DataError, ModelError

__all__ = [
    'HYSTERESIS_THRESHOLDS', 'HYSTERESIS_WEIGHTS', 'HYSTERESIS_INITIAL_STATES',
    'SUPERPOSITION_THRESHOLDS', 'SUPERPOSITION_WEIGHTS', 'MODEL_KEYS', 'INPUT_OFFSET',
    'OUTPUT_OFFSET', 'OUTPUT_SIGN', 'OPERATING_POINT_KEYS', 'OPERATING_POINT_DEFAULTS',
    'check_model_parameters', 'check_operating_point', 'write_params_yaml', 'read_params_yaml',
    'flatten_parameters',
]

HYSTERESIS_THRESHOLDS = 'model.hysteresis.thresholds'
HYSTERESIS_WEIGHTS = 'model.hysteresis.weights'
HYSTERESIS_INITIAL_STATES = 'model.hysteresis.initial_states'
SUPERPOSITION_THRESHOLDS = 'model.superposition.thresholds'
SUPERPOSITION_WEIGHTS = 'model.superposition.weights'
#: Gamma's five arrays (the nodes and every tool use this one definition).
MODEL_KEYS = (HYSTERESIS_THRESHOLDS, HYSTERESIS_WEIGHTS, HYSTERESIS_INITIAL_STATES,
              SUPERPOSITION_THRESHOLDS, SUPERPOSITION_WEIGHTS)
INPUT_OFFSET = 'model.input_offset'
OUTPUT_OFFSET = 'model.output_offset'
OUTPUT_SIGN = 'model.output_sign'
#: The operating point: optional keys, these defaults when absent (the paper's origin).
OPERATING_POINT_KEYS = (INPUT_OFFSET, OUTPUT_OFFSET, OUTPUT_SIGN)
OPERATING_POINT_DEFAULTS: dict[str, float | int] = {INPUT_OFFSET: 0.0, OUTPUT_OFFSET: 0.0,
                                                    OUTPUT_SIGN: 1}

FloatArray = npt.NDArray[np.float64]


def _vector(mapping: Mapping[str, Any], key: str) -> FloatArray:
    if key not in mapping:
        msg = f'{key} is missing; a model needs all of: {", ".join(MODEL_KEYS)}'
        raise ModelError(msg)
    value = mapping[key]
    if isinstance(value, (str, bytes)) or not hasattr(value, '__len__'):
        msg = f'{key} must be a list of floats; found {type(value).__name__} {value!r}'
        raise ModelError(msg)
    items = list(value)
    for i, item in enumerate(items):
        number = isinstance(item, (int, float, np.floating, np.integer))
        if isinstance(item, bool) or not number:
            msg = (f'{key} must be a list of floats; item {i} is'
                   f' {type(item).__name__} {item!r}')
            raise ModelError(msg)
    arr = np.array(items, dtype=np.float64)
    if arr.size == 0:
        msg = f'{key} must not be empty'
        raise ModelError(msg)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        msg = f'{key} must be finite; item {bad[0]} is {arr[bad[0]]}'
        raise ModelError(msg)
    return arr


def _strictly_ascending(arr: FloatArray, key: str) -> None:
    steps = np.diff(arr)
    if np.any(steps <= 0.0):
        i = int(np.flatnonzero(steps <= 0.0)[0])
        kind = 'duplicate' if steps[i] == 0.0 else 'unsorted'
        msg = (f'{key} must be strictly ascending; found {kind} values {float(arr[i])!r} and'
               f' {float(arr[i + 1])!r} at items {i} and {i + 1}')
        raise ModelError(msg)


def _scalar(mapping: Mapping[str, Any], key: str) -> float:
    value = mapping.get(key)
    if value is None:
        return float(OPERATING_POINT_DEFAULTS[key])
    number = isinstance(value, (int, float, np.floating, np.integer))
    if isinstance(value, bool) or not number:
        msg = f'{key} must be a number; found {type(value).__name__} {value!r}'
        raise ModelError(msg)
    if not math.isfinite(float(value)):
        msg = f'{key} must be finite; found {float(value)}'
        raise ModelError(msg)
    return float(value)


def check_operating_point(mapping: Mapping[str, Any]) -> tuple[float, float, int]:
    """
    Validate the operating point keys (absent or None: the defaults).

    Parameters
    ----------
    mapping : Mapping[str, Any]
        Flat parameters; ``model.input_offset`` [A], ``model.output_offset`` [m] and
        ``model.output_sign`` (+1 or -1) are read, other keys ignored.

    Returns
    -------
    (float, float, int)
        ``(x0, y0, sign)``.

    Raises
    ------
    ModelError
        Naming the key.

    """
    x0 = _scalar(mapping, INPUT_OFFSET)
    y0 = _scalar(mapping, OUTPUT_OFFSET)
    sign = _scalar(mapping, OUTPUT_SIGN)
    if sign not in (1.0, -1.0):
        msg = (f'{OUTPUT_SIGN} must be 1 (the sensor rises as the actuator extends) or -1'
               f' (it falls); found {sign:g}')
        raise ModelError(msg)
    return x0, y0, int(sign)


def check_model_parameters(mapping: Mapping[str, Any]) -> dict[str, FloatArray]:
    """
    Validate the parameter form of a forward MPI model and return its arrays.

    The operating point keys are checked by :func:`check_operating_point`.

    Parameters
    ----------
    mapping : Mapping[str, sequence of float]
        The five ``model.*`` keys (extra keys are ignored).

    Returns
    -------
    dict[str, ndarray of float]
        The five arrays, keyed as in ``MODEL_KEYS``.

    Raises
    ------
    ModelError
        Naming the key, what was expected, what was found and what to do.

    """
    r_h = _vector(mapping, HYSTERESIS_THRESHOLDS)
    w_h = _vector(mapping, HYSTERESIS_WEIGHTS)
    z_h0 = _vector(mapping, HYSTERESIS_INITIAL_STATES)
    r_s = _vector(mapping, SUPERPOSITION_THRESHOLDS)
    w_s = _vector(mapping, SUPERPOSITION_WEIGHTS)
    if w_h.size != r_h.size:
        msg = (f'{HYSTERESIS_WEIGHTS} must have one weight per threshold in'
               f' {HYSTERESIS_THRESHOLDS}: expected {r_h.size}, found {w_h.size}')
        raise ModelError(msg)
    if z_h0.size != r_h.size:
        msg = (f'{HYSTERESIS_INITIAL_STATES} must have one state per threshold in'
               f' {HYSTERESIS_THRESHOLDS}: expected {r_h.size}, found {z_h0.size}')
        raise ModelError(msg)
    if w_s.size != r_s.size:
        msg = (f'{SUPERPOSITION_WEIGHTS} must have one weight per threshold in'
               f' {SUPERPOSITION_THRESHOLDS}: expected {r_s.size}, found {w_s.size}')
        raise ModelError(msg)
    if r_h[0] != 0.0:
        msg = (f'{HYSTERESIS_THRESHOLDS} must start at exactly 0.0 (r_H0 = 0);'
               f' found {float(r_h[0])!r}; re-run identify or prepend 0.0')
        raise ModelError(msg)
    _strictly_ascending(r_h, HYSTERESIS_THRESHOLDS)
    zeros = int(np.count_nonzero(r_s == 0.0))
    if zeros != 1:
        found = 'none' if zeros == 0 else f'{zeros} zeros'
        msg = (f'{SUPERPOSITION_THRESHOLDS} must contain exactly one 0; found {found};'
               ' re-run identify or add 0.0')
        raise ModelError(msg)
    _strictly_ascending(r_s, SUPERPOSITION_THRESHOLDS)
    if not w_h[0] > 0.0:
        msg = (f'{HYSTERESIS_WEIGHTS} violates (8): the first weight w_H0 must be positive;'
               f' found {float(w_h[0])!r}')
        raise ModelError(msg)
    negative = np.flatnonzero(w_h[1:] < 0.0)
    if negative.size:
        i = int(negative[0]) + 1
        msg = (f'{HYSTERESIS_WEIGHTS} violates (8): weights after the first must be >= 0;'
               f' item {i} is {float(w_h[i])!r} ({negative.size} negative)')
        raise ModelError(msg)
    c = int(np.flatnonzero(r_s == 0.0)[0])
    slopes = np.empty_like(w_s)
    slopes[c:] = np.cumsum(w_s[c:])
    slopes[:c + 1] = np.cumsum(w_s[:c + 1][::-1])[::-1]
    bad = np.flatnonzero(slopes <= 0.0)
    if bad.size:
        i = int(bad[0])
        msg = (f'{SUPERPOSITION_WEIGHTS} violates (19): the static map must be strictly'
               f' increasing, but the piece at threshold {float(r_s[i])!r} (item {i}) has slope'
               f' {float(slopes[i])!r}')
        raise ModelError(msg)
    return {HYSTERESIS_THRESHOLDS: r_h, HYSTERESIS_WEIGHTS: w_h,
            HYSTERESIS_INITIAL_STATES: z_h0, SUPERPOSITION_THRESHOLDS: r_s,
            SUPERPOSITION_WEIGHTS: w_s}


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
