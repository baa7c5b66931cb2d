# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Several actuators served together.

One :class:`~mpi_ros.compensation.Compensator` per axis (models, limits, bumpless handover);
blocks of samples x axes in and out through one compiled loop over every axis
(:func:`~mpi_ros.compensation.kernels.compensate_axes`), which runs each axis's own step
on its slices of a few packed arrays: the columns are exactly the single-axis results.

What a multi-axis node keeps between its callbacks, on plain values: each axis's validated
model until every axis has one (:class:`AxisModels`), the inputs it refused
(:class:`InputCounts`), the counters it reports (:func:`reported_counters`) and the check
of its ros2_control wiring (:func:`joint_input`).  The stream times of its chunks are
:class:`mpi_ros.compensation.message_time.MessageClock`'s.
"""

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from .compensator import (
    check_sample_period, Compensator, COMPILED_COUNTERS, kind_of, loop_block, pack,
)
from .kernels import compensate_axes, COMPILED, LAST_COMMAND, TABLE_COLUMNS
from .screening import FAULT_KEYS
from ..errors import DataError, ModelError, ParameterRejected
from ..operators.memory import TurningPointMemory
from ..operators.model import MPIModel

__all__ = ['AxisModels', 'InputCounts', 'JointOrder', 'MultiAxisCompensator',
           'REPORTED_COUNTERS', 'joint_input', 'joint_names', 'reported_counters']

FloatArray = npt.NDArray[np.float64]

#: The core's counters a multi-axis node reports, summed over the axes (``bad_time``: the
#: lags of the axes with an effect).
REPORTED_COUNTERS = FAULT_KEYS + ('bad_time',)


class MultiAxisCompensator:
    """
    Several actuators, each with its own model and :class:`Compensator`, served together.

    A block of desired displacements, ``samples x axes`` (one row per sample, one column
    per axis, as in a ``Float64MultiArray`` chunk), gives a block of commands of the same
    shape; each column is exactly what that axis's single-axis compensator gives.

    Every plain, enabled axis runs in one compiled loop over the block: its thresholds,
    weights, play states, operating point, limits and turning points are packed into a
    few shared arrays (the axis's :class:`Compensator` keeps views of them, so its state
    is the packed one).  Axes with an effect, a predicted dead time or disabled
    are served by their own
    :class:`Compensator` (:meth:`Compensator.command_batch`, sample by sample, with the
    block's ``times`` for an effect's lags).  The pack is rebuilt on the next block after
    any axis changes (:meth:`install`, :meth:`set_limits`, :attr:`enabled`, or anything
    done to :attr:`axes`).

    Parameters
    ----------
    models : sequence of MPIModel or extended models
        One forward model per axis.
    output_min, output_max : float or sequence of float
        Safe current range [A], one for all axes or one per axis.
    enabled : bool
        False: the best linear maps instead of the inverses.
    sample_period : float
        Nominal command interval [s] (effects with lags only).
    memory_capacity : int
        Turning points kept per axis (see :class:`~mpi_ros.operators.memory.TurningPointMemory`).
    inverses : sequence of MPIModel or None, optional
        Gamma^-1 of each axis's model where already built (None: built here).
    start : StartState or str
        Where every axis starts (see :class:`Compensator`; default ``rest_low``).
    dead_time_prediction : bool
        Compensate an axis's dead time by prediction (see :class:`Compensator`; such an
        axis is served sample by sample).
    input_units : sequence of str, optional
        Each axis's input unit in its start's words (``'A'`` or ``'V'``); ``'A'`` by default.

    """

    def __init__(self, models: Sequence[Any], *, output_min: float | Sequence[float],
                 output_max: float | Sequence[float], enabled: bool = True,
                 sample_period: float = 1e-3, memory_capacity: int = 4096,
                 inverses: Sequence[MPIModel | None] | None = None,
                 start: Any = 'rest_low', dead_time_prediction: bool = True,
                 input_units: Sequence[str] | None = None) -> None:
        if len(models) == 0:
            msg = 'a multi-axis compensator needs at least one axis model'
            raise ModelError(msg)
        count = len(models)
        lows = _per_axis(output_min, count, 'output.min')
        highs = _per_axis(output_max, count, 'output.max')
        built = list(inverses) if inverses is not None else [None] * count
        units = list(input_units) if input_units is not None else ['A'] * count
        self._memory = np.zeros((count, memory_capacity + 1))
        self._memory_state = np.zeros((count, 2), dtype=np.int64)
        self._axes = [
            Compensator(model, output_min=lo, output_max=hi, enabled=enabled,
                        sample_period=sample_period, inverse=built[k], start=start,
                        dead_time_prediction=dead_time_prediction, input_unit=units[k],
                        memory=TurningPointMemory(memory_capacity, points=self._memory[k],
                                                  state=self._memory_state[k]))
            for k, (model, lo, hi) in enumerate(zip(models, lows, highs))]
        self._pack: tuple[Any, ...] | None = None
        self._counts = np.zeros((count, len(COMPILED_COUNTERS)), dtype=np.int64)
        for axis in self._axes:
            axis.before_change = self._unpack
        self.warm_up()

    def __len__(self) -> int:
        """Return the number of axes."""
        return len(self._axes)

    @property
    def axes(self) -> list[Compensator]:
        """
        Return the axes' compensators, up to date (packed counters and commands handed back).

        Changing an axis through them (``install``, ``set_limits``, ``enabled``) is safe:
        the pack is rebuilt on the next block.
        """
        self._unpack()
        return list(self._axes)

    @property
    def counters(self) -> dict[str, int]:
        """Return the counters of :class:`Compensator`, summed over the axes."""
        totals = dict.fromkeys(self._axes[0].counters, 0)
        for axis in self._axes:
            for key, value in axis.counters.items():
                totals[key] += value
        for key, value in zip(COMPILED_COUNTERS, self._counts.sum(axis=0).tolist()):
            totals[key] += value
        return totals

    @property
    def slow_states(self) -> list[Any]:
        """Return each axis's slow states (None for an axis without an effect)."""
        return [axis.slow_state if axis.has_effect else None for axis in self.axes]

    def install(self, axis: int, model: Any) -> None:
        """Switch one axis to a new (validated) model, bumplessly (:meth:`Compensator.install`)."""
        self._axes[axis].install(model)

    def set_limits(self, output_min: float, output_max: float, *,
                   axis: int | None = None) -> None:
        """
        Give every axis, or one, the safe current range [A] (validated, all or none).

        Parameters
        ----------
        output_min, output_max : float
            Lowest and highest current command [A]; finite, ``output_min < output_max``.
        axis : int, optional
            Only this axis (0 to N-1); None: every axis.

        Raises
        ------
        ModelError
            When the range is not finite and ordered, or ``axis`` is not an axis.

        """
        if axis is None:
            targets = self._axes
        elif isinstance(axis, int) and 0 <= axis < len(self._axes):
            targets = [self._axes[axis]]
        else:
            msg = (f'axis must be an axis index from 0 to {len(self._axes) - 1}; found '
                   f'{axis!r}; pass None to set every axis')
            raise ModelError(msg)
        for target in targets:
            target._check_limits(output_min, output_max)
        for target in targets:
            target.set_limits(output_min, output_max)

    @property
    def sample_period(self) -> float:
        """
        Return the interval [s] an effect's lags assume when a command has no usable time.

        Setting it (finite, > 0) sets every axis's; plain axes do not use it.
        """
        return self._axes[0].sample_period

    @sample_period.setter
    def sample_period(self, value: float) -> None:
        check_sample_period(value)
        for axis in self._axes:
            axis.sample_period = float(value)

    @property
    def enabled(self) -> bool:
        """Tell whether every axis applies its inverse (False: best linear maps)."""
        return all(axis.enabled for axis in self._axes)

    @enabled.setter
    def enabled(self, value: bool) -> None:
        for axis in self._axes:
            axis.enabled = value

    def command(self, desired: npt.ArrayLike,
                times: npt.ArrayLike | None = None) -> FloatArray:
        """
        Return the commands for a block of desired displacements.

        Parameters
        ----------
        desired : array_like of float, shape (K, N) or (N,)
            Desired displacements [m]: K samples of N axes (one sample: shape (N,)).
        times : array_like of float, shape (K,), optional
            Time stamp [s] of each sample (row), for the lags of the axes with an effect
            (:meth:`Compensator.command_batch`); the plain axes do not use them.  None:
            ``sample_period`` between samples.

        Returns
        -------
        ndarray of float, same shape as ``desired``
            Current commands [A].

        Raises
        ------
        DataError
            When the block does not have one column per axis, or ``times`` does not give
            one time per sample.

        """
        block = np.asarray(desired, dtype=np.float64)
        single = block.ndim == 1
        rows = block.reshape(1, -1) if single else block
        if rows.ndim != 2 or rows.shape[1] != len(self._axes):
            msg = (f'desired displacements must be samples x axes with {len(self._axes)}'
                   f' axes; found shape {tuple(block.shape)}')
            raise DataError(msg)
        stamps = None
        if times is not None:
            stamps = np.asarray(times, dtype=np.float64).reshape(-1)
            if stamps.size != rows.shape[0]:
                msg = (f'times must give one time per sample ({rows.shape[0]}); found '
                       f'{stamps.size}; pass one time stamp [s] per row, or None')
                raise DataError(msg)
        rows = loop_block(rows)
        pack = self._pack if self._pack is not None else self._build()
        coefficients, states, index, table, others = pack
        out = np.empty(rows.shape)
        compensate_axes(rows, out, coefficients, states, index, table, self._counts,
                        self._memory, self._memory_state)
        for axis in others:
            out[:, axis] = self._axes[axis].command_batch(rows[:, axis], stamps)
        return out[0] if single else out

    def warm_up(self) -> None:
        """Run the compiled loop once on copies (the first block does not compile it)."""
        coefficients, states, index, table, _ = self._build()
        start = table[:, TABLE_COLUMNS.index('displacement_lo')].reshape(1, -1)
        compensate_axes(start.copy(), np.empty(start.shape), coefficients, states.copy(),
                        index, table.copy(), np.zeros_like(self._counts),
                        np.zeros((len(self._axes), 4)), np.zeros_like(self._memory_state))

    def _build(self) -> tuple[Any, ...]:
        """Pack the axes (:func:`~mpi_ros.compensation.compensator.pack`); note the others."""
        coefficients, states, index, table = pack(self._axes)
        others = [a for a, axis in enumerate(self._axes) if not axis.compiled]
        self._pack = (coefficients, states, index, table, others)
        return self._pack

    def _unpack(self) -> None:
        """Hand the packed counters and last commands back to the axes; repack later."""
        pack, self._pack = self._pack, None
        if pack is None:
            return
        table = pack[3]
        for a, axis in enumerate(self._axes):
            axis.add_counts(self._counts[a])
            if pack[2][a, COMPILED]:
                axis.last_command = float(table[a, LAST_COMMAND])
        self._counts[:] = 0


def joint_names(names: Any, axes: int) -> tuple[str, ...]:
    """
    Check the ``joints`` parameter against the axis count.

    Parameters
    ----------
    names : list of str or None
        The parameter's value (None or empty: no names).
    axes : int
        Number of axes.

    Returns
    -------
    tuple of str
        The names, one per axis; empty when none are given.

    Raises
    ------
    ParameterRejected
        When the count differs from ``axes``, a name is empty or repeated.

    Examples
    --------
    >>> joint_names(['a', 'b'], 2)
    ('a', 'b')
    >>> joint_names(None, 3)
    ()

    """
    given = tuple(names or ())
    if not given:
        return ()
    if len(given) != axes:
        msg = (f'joints names {len(given)} joints ({", ".join(given)}) but axes is {axes}; '
               f'give one name per axis (axes:={len(given)}, or as many joints as axes)')
        raise ParameterRejected(msg)
    empty = [str(k) for k, name in enumerate(given) if not name.strip()]
    if empty:
        msg = f'joints: the name of axis {", ".join(empty)} is empty; name every joint'
        raise ParameterRejected(msg)
    repeated = sorted({name for name in given if given.count(name) > 1})
    if repeated:
        msg = f'joints names {", ".join(repeated)} more than once; each joint once'
        raise ParameterRejected(msg)
    return given


def joint_input(joints: Sequence[str], input_message: str) -> bool:
    """
    Tell whether the node reads JointState messages; check that it can map them.

    Parameters
    ----------
    joints : sequence of str
        The checked ``joints`` (:func:`joint_names`; empty: none).
    input_message : str
        The ``input_message`` parameter: ``array`` or ``joint_state``.

    Returns
    -------
    bool
        True for ``joint_state``.

    Raises
    ------
    ParameterRejected
        For ``joint_state`` without ``joints``.

    """
    if input_message != 'joint_state':
        return False
    if not joints:
        msg = ('input_message joint_state needs the joints parameter (one name per axis, '
               'in axis order) to map the JointState names to the axes')
        raise ParameterRejected(msg)
    return True


def _per_axis(value: float | Sequence[float], count: int, name: str) -> list[float]:
    if isinstance(value, (int, float)):
        values = [float(value)] * count
    else:
        values = [float(v) for v in value]
    if len(values) != count:
        msg = f'{name} must be one value or one per axis ({count}); found {len(values)}'
        raise ModelError(msg)
    return values


class JointOrder:
    """
    Put the positions of a ``sensor_msgs/JointState`` in axis (``joints``) order.

    The index of each axis's joint is kept per name order (at most :attr:`MEMORY` orders,
    then forgotten at once), so a stream in one order costs one lookup per message.

    Parameters
    ----------
    joints : sequence of str
        The joint of each axis, in axis order.

    """

    #: At most this many name orders are remembered (their index arrays).
    MEMORY = 64

    def __init__(self, joints: Sequence[str]) -> None:
        self.joints = tuple(joints)
        self._index: dict[tuple[str, ...], npt.NDArray[np.intp]] = {}

    def block(self, names: Sequence[str], position: Sequence[float],
              ) -> tuple[FloatArray | None, str, str]:
        """
        Return the 1 x N block of one JointState, or why it is refused.

        Parameters
        ----------
        names, position : sequence
            The message's ``name`` and ``position``.

        Returns
        -------
        block : ndarray of float, shape (1, N), or None
            The positions in axis order; None when refused.
        fault : str
            ``''``, ``'missing_joints'`` (a joint of ``joints`` is not named) or
            ``'malformed'`` (a joint named twice, or not one position per name).
        reason : str
            What was wrong, for ``/diagnostics``.

        """
        names = tuple(names)
        index = self._index.get(names)
        if index is None:
            position_of = {name: i for i, name in enumerate(names)}
            missing = [joint for joint in self.joints if joint not in position_of]
            if missing:
                return None, 'missing_joints', (
                    f'JointState without {", ".join(missing)} (it names '
                    f'{", ".join(names[:8]) or "no joint"}{" ..." if len(names) > 8 else ""})')
            if len(position_of) != len(names):
                return None, 'malformed', 'JointState names a joint more than once'
            if len(self._index) >= self.MEMORY:
                self._index.clear()
            index = np.array([position_of[joint] for joint in self.joints], dtype=np.intp)
            self._index[names] = index
        if len(position) != len(names):
            return None, 'malformed', (f'JointState with {len(names)} names and '
                                       f'{len(position)} positions; each joint needs its '
                                       'position')
        return np.asarray(position, dtype=np.float64)[index].reshape(1, -1), '', ''


class AxisModels:
    """
    The validated model of each axis of a multi-axis node, until every axis has one.

    Parameters
    ----------
    axes : int
        Number of axes.

    Attributes
    ----------
    models : list
        Each axis's model (None: none yet).
    inverses : list
        Gamma^-1 of each axis's model where the parameter rule built it (None: not built).
    versions : list of int
        How many models each axis was given (kept across :meth:`reset`).
    dead_time_prediction : bool
        Whether the compensator predicts over a dead time (how a dead time is named).

    """

    def __init__(self, axes: int, *, dead_time_prediction: bool = True) -> None:
        self.dead_time_prediction = dead_time_prediction
        self.versions = [0] * axes
        self.models: list[Any] = [None] * axes
        self.inverses: list[MPIModel | None] = [None] * axes

    def reset(self) -> None:
        """Forget every model and inverse (the node's cleanup); the versions go on."""
        self.models = [None] * len(self.versions)
        self.inverses = [None] * len(self.versions)

    def note(self, axis: int, model: Any) -> None:
        """Note a new model of ``axis`` (its version goes up)."""
        self.models[axis] = model
        self.versions[axis] += 1

    @property
    def missing(self) -> list[int]:
        """Return the axes without a model."""
        return [axis for axis, model in enumerate(self.models) if model is None]

    def applied(self, models: Mapping[int, Any], running: bool) -> str:
        """
        Say which models were applied and whether the node compensates (its log line).

        Parameters
        ----------
        models : mapping of int to model
            The models just applied, by axis.
        running : bool
            The core runs (every axis has a model).

        Returns
        -------
        str
            e.g. ``model applied to axis 0 (none), 2 (creep) (compensating)``.

        """
        axes = ', '.join(
            f'{axis} ({kind_of(models[axis], dead_time_prediction=self.dead_time_prediction)})'
            for axis in sorted(models))
        state = 'compensating' if running else f'{len(self.missing)} axes still without a model'
        return f'model applied to axis {axes} ({state})'


class InputCounts:
    """
    What came in on a multi-axis node's input: samples, and the messages it refused.

    Attributes
    ----------
    samples : int
        Samples received (rows of the accepted blocks).
    malformed, missing_joints : int
        Messages refused: not a samples x axes block (or a JointState whose names and
        positions do not match), and JointStates without a joint of ``joints``.
    last_malformed, last_missing : str
        Why the last one of each kind was refused (``''``: none yet).

    """

    def __init__(self) -> None:
        self.samples = 0
        self.malformed = 0
        self.missing_joints = 0
        self.last_malformed = ''
        self.last_missing = ''

    def refuse(self, fault: str, reason: str) -> None:
        """Count a refused message: ``fault`` ``missing_joints`` or ``malformed``."""
        if fault == 'missing_joints':
            self.missing_joints += 1
            self.last_missing = reason
        else:
            self.malformed += 1
            self.last_malformed = reason

    def counters(self, joints: bool) -> dict[str, int]:
        """Return ``samples_in`` and ``malformed`` and, with ``joints``, ``missing_joints``."""
        counters = {'samples_in': self.samples, 'malformed': self.malformed}
        if joints:
            counters['missing_joints'] = self.missing_joints
        return counters


def reported_counters(compensator: MultiAxisCompensator | None) -> dict[str, int]:
    """
    Return the core's counters a multi-axis node reports (:data:`REPORTED_COUNTERS`).

    Parameters
    ----------
    compensator : MultiAxisCompensator or None
        The core; None before every axis has a model (every counter 0).

    Returns
    -------
    dict of str to int
        The counters, summed over the axes.

    """
    counters = dict.fromkeys(REPORTED_COUNTERS, 0)
    if compensator is not None:
        summed = compensator.counters
        counters.update((key, summed[key]) for key in REPORTED_COUNTERS)
    return counters
