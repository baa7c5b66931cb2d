# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The simulated plant as plain data: what the plant simulator node is given and builds.

The plant the node's parameters (:mod:`mpi_ros.node_parameters.plant_simulator`) describe
(:func:`build_truth`: the built-in magnetostrictive actuator or an MPI model), its
description in words (:func:`describe_truth`) and the schedule of the excitation mode
(:func:`excitation_schedule`); what the node runs: :class:`SimulatedPlants` (one truth per
axis, the sensor noise, the sample times and the counters) and :class:`ExcitationRun` (the
schedule played in real time).  The ROS side is :mod:`mpi_ros.nodes.plant_simulator`.
"""

import math
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

from .actuator import ActuatorConfig, MagnetostrictiveActuator
from .excitation import diagnostic_excitation, identification_excitation
from ..errors import ParameterRejected
from ..extensions.effect import plant_effects
from ..operators.model import HYSTERESIS_INITIAL_STATES, MODEL_KEYS, MPIModel, \
    OPERATING_POINT_KEYS, RECORD_START_STATES

__all__ = ['ExcitationRun', 'NODE_OWNED_FIELDS', 'SimulatedPlants', 'build_truth',
           'describe_truth', 'excitation_schedule']


#: ActuatorConfig fields that the node sets itself instead of an ``actuator.*`` parameter.
NODE_OWNED_FIELDS = {'noise_std_m': 'noise_std'}


def build_truth(values: Dict[str, Any], seed: Optional[int] = None) -> Any:
    """
    Build the simulated plant the node's parameters describe.

    Parameters
    ----------
    values : dict
        The node's parameter values (``truth``, ``model.*``, ``actuator.*``, ``seed``).
    seed : int, optional
        Seed of the actuator's noise; None: ``values['seed']``.

    Returns
    -------
    object
        The streaming MPI model (``truth:=mpi``) or the built-in actuator.

    Raises
    ------
    ParameterRejected
        For ``truth:=mpi`` without the model's parameters, naming the missing keys.

    """
    if values['truth'] == 'mpi':
        missing = [key for key in MODEL_KEYS if values[key] is None]
        if missing:
            msg = f'truth:=mpi needs the model parameters; missing: {", ".join(missing)}'
            raise ParameterRejected(msg)
        # The plant starts where its states say (the record start of a model file).
        return MPIModel.from_params(
            {key: values.get(key) for key in MODEL_KEYS + OPERATING_POINT_KEYS + (
                RECORD_START_STATES, HYSTERESIS_INITIAL_STATES)}).stream()
    mapping = {name: value for name, value in values.items()
               if name.startswith('actuator.')}
    for field_name in NODE_OWNED_FIELDS:
        mapping[f'actuator.{field_name}'] = 0.0
    return MagnetostrictiveActuator(ActuatorConfig.from_mapping(mapping),
                                    seed=values['seed'] if seed is None else seed)


def describe_truth(values: Dict[str, Any]) -> str:
    """
    Say in words what the plant simulator simulates (for its start-up log line).

    Parameters
    ----------
    values : dict
        The node's parameter values.

    Returns
    -------
    str
        E.g. ``'an MPI model (n=3, l=2) with 1e-08 m sensor noise'``.

    """
    if values['truth'] == 'mpi':
        n = len(values['model.hysteresis.thresholds']) - 1
        l_s = len(values['model.superposition.thresholds']) - 1
        text = f'an MPI model (n={n}, l={l_s})'
    else:
        actuator = {name[len('actuator.'):]: value for name, value in values.items()
                    if name.startswith('actuator.')}
        effects = [plant.label for _, plant in plant_effects() if plant.is_on(actuator)]
        text = ('the built-in magnetostrictive actuator (Preisach type'
                + (f'; {", ".join(effects)}' if effects else '') + ')')
    if values['noise_std'] > 0.0:
        text += f' with {values["noise_std"]:g} m sensor noise'
    return text


def excitation_schedule(values: Dict[str, Any]) -> Tuple[Any, Any]:
    """
    Return the schedule of the plant simulator's excitation mode.

    Parameters
    ----------
    values : dict
        The node's parameter values (``excitation.*``, ``seed``).

    Returns
    -------
    time, current : ndarray of float
        Sample times [s] and currents [A].

    """
    common = {'sample_rate': values['excitation.sample_rate'],
              'bias': values['excitation.bias'], 'amplitude': values['excitation.amplitude'],
              'seed': values['seed'], 'hold_duration': values['excitation.hold_duration']}
    if values['excitation.signal'] == 'diagnostic':
        return diagnostic_excitation(repeats=values['excitation.repeats'], **common)
    return identification_excitation(values['excitation.duration'],
                                     holds=values['excitation.holds'],
                                     bursts=values['excitation.bursts'], **common)


class SimulatedPlants:
    """
    What the plant simulator runs: one truth per axis with its sensor, on plain numbers.

    Parameters
    ----------
    values : dict
        The node's parameter values (``truth``, ``model.*``, ``actuator.*``, ``seed``,
        ``noise_std``, ``axes``, ``sample_period``, ``excitation.enabled``,
        ``record.path``).

    Attributes
    ----------
    axes : int
        Number of plants: axis k is the truth of :func:`build_truth` with seed
        ``seed + k``.
    last_t : float
        Time of the last sample [s] (-inf before the first one).
    counters : dict of str to int
        ``commands``, ``nonfinite_commands``, ``published`` and, once a message was
        refused, ``malformed`` (the node counts messages; :meth:`measure_block` counts
        the non-finite currents of a block).

    Raises
    ------
    ParameterRejected
        For several axes with the excitation mode or a recording (single-axis only), and
        when the truth cannot be built (:func:`build_truth`).

    """

    def __init__(self, values: Dict[str, Any]) -> None:
        self.axes = int(values['axes'])
        if self.axes > 1 and (values['excitation.enabled'] or values['record.path']):
            msg = (f'axes={self.axes}: excitation.enabled and record.path are single-axis '
                   'only; set axes:=1, or leave excitation and recording off')
            raise ParameterRejected(msg)
        self._rng = np.random.default_rng(values['seed'])
        self._noise_std = values['noise_std']
        self._sample_period = values['sample_period']
        self.plants = [build_truth(values)] + [build_truth(values, seed=values['seed'] + k)
                                               for k in range(1, self.axes)]
        self._held = np.zeros(self.axes)
        self.last_t = -math.inf
        self.counters: Dict[str, int] = {'commands': 0, 'nonfinite_commands': 0, 'published': 0}

    def sample_time(self, t: float) -> float:
        """Return the time of a new sample at ``t`` [s]: 1 ns after the last one at least."""
        self.last_t = max(t, self.last_t + 1e-9)
        return self.last_t

    def measure(self, t: float, current: float) -> float:
        """
        Advance the first plant by one sample and return the measured displacement.

        Parameters
        ----------
        t : float
            Sample time [s], after the previous one (used by the built-in actuator).
        current : float
            Coil current [A], finite.

        Returns
        -------
        float
            Displacement [m] with sensor noise.

        """
        return self._measure(self.plants[0], t, current)

    def measure_block(self, t: float, currents: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """
        Advance every axis by the samples of a block; return the displacements.

        Parameters
        ----------
        t : float
            Time of the block's last sample [s]; the others ``sample_period`` apart (and
            each 1 ns after the previous one at least).
        currents : array_like of float, shape (K, axes)
            Coil currents [A]; a non-finite one is not applied (the axis's last current
            is held) and counted (``nonfinite_commands``).

        Returns
        -------
        ndarray of float, shape (K, axes)
            Displacements [m] with sensor noise.

        """
        block = np.asarray(currents, dtype=np.float64)
        out = np.empty_like(block)
        samples = block.shape[0]
        for row in range(samples):
            ts = self.sample_time(t - (samples - 1 - row) * self._sample_period)
            for axis, plant in enumerate(self.plants):
                current = float(block[row, axis])
                if math.isfinite(current):
                    self._held[axis] = current
                else:
                    self.counters['nonfinite_commands'] += 1
                out[row, axis] = self._measure(plant, ts, float(self._held[axis]))
        return out

    def _measure(self, plant: Any, t: float, current: float) -> float:
        if isinstance(plant, MagnetostrictiveActuator):
            displacement = plant.step(t, current)
        else:
            displacement = plant.step(current)
        if self._noise_std > 0.0:
            displacement += self._noise_std * float(self._rng.standard_normal())
        return float(displacement)


class ExcitationRun:
    """
    The excitation mode's schedule played in real time: which samples are due when.

    Parameters
    ----------
    times, currents : array_like of float, shape (N,)
        The schedule (:func:`excitation_schedule`): sample times [s], non-decreasing, and
        currents [A].

    Examples
    --------
    >>> run = ExcitationRun([0.0, 0.1, 0.2], [1.0, 1.5, 2.0])
    >>> run.due(50.0), run.due(50.15), run.done
    ([(0.0, 1.0)], [(0.1, 1.5)], False)
    >>> run.due(51.0), run.done
    ([(0.2, 2.0)], True)

    """

    def __init__(self, times: npt.ArrayLike, currents: npt.ArrayLike) -> None:
        self.times = np.asarray(times, dtype=float)
        self.currents = np.asarray(currents, dtype=float)
        self.index = 0
        self._start: Optional[float] = None

    @property
    def done(self) -> bool:
        """Tell whether every sample was handed out."""
        return self.index >= len(self.times)

    def due(self, now: float) -> List[Tuple[float, float]]:
        """
        Return the samples due at ``now`` that were not handed out yet.

        Parameters
        ----------
        now : float
            Steady time [s]; the first call starts the schedule (its first sample is due
            at once).

        Returns
        -------
        list of (float, float)
            Each sample's time on the schedule [s] and current [A], in order.

        """
        if self._start is None:
            self._start = now - float(self.times[0])
        stop = int(np.searchsorted(self.times, now - self._start, side='right'))
        samples = [(float(self.times[k]), float(self.currents[k]))
                   for k in range(self.index, stop)]
        self.index = stop
        return samples
