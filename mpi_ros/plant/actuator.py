# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Simulated magnetostrictive actuator: the "truth" plant for tests, demos and the simulator node.

This is deliberately *not* a modified Prandtl-Ishlinskii model, so that identifying an MPI
model on its data is a fair test.  The coil current ``i`` [A] drives

1. the input-side steps of the registered effects (an eddy-current lag,
   ``tau_e di_e/dt = i - i_e``; off: ``i_e = i``);
2. a Preisach operator ``P[i_e]`` in [0, 1]: a superposition of relay hysterons with
   switching thresholds ``alpha >= beta`` (up at ``alpha``, down at ``beta``), weighted by a
   smooth density that is Gaussian in the coercive coordinate ``u = (alpha - beta) / 2`` and
   the interaction coordinate ``v = (alpha + beta) / 2``;
3. a magnetization-like state ``y = (1 - r) P + r i_e / i_r`` (``r`` reversible fraction);
4. a strictly increasing, non-convex, asymmetric static map (magnetostriction with
   saturation) ``s_h = s_max g(y)``;
5. the output-side steps of the registered effects (creep, thermal drift, a dead time);
6. a sensor zero: the reading is ``s - s_0 + sensor_offset_m``, where ``s_0`` is the
   displacement where the sensor was zeroed (0 at rest by default, see below), and
   sensor noise.

Steps 2-4 are the compiled hysteresis core.  The effects are plug-ins: each registered
:class:`~mpi_ros.extensions.effect.Effect` with a ``plant`` step
(:class:`~mpi_ros.extensions.effect.PlantEffect`) adds its parameters to
:class:`ActuatorConfig` and, when switched on, its vectorised pass at its stage of the chain
(steps 1 and 5, in the order of registration within a stage); see the effect modules for
their equations and :mod:`mpi_ros.extensions.plant_steps` for the exact lags and the delay.

At 0 A the actuator is at rest with displacement 0: every relay is 'down' and the
current history starts at 0 A.  The paper's operating range is 1 A +- 0.8 A (section 5).
A rig's sensor is zeroed in operation instead: with ``sensor_zero_peak_current_a=1.8`` and
``sensor_zero_current_a=0.2`` the sensor was zeroed after the current went from rest up to
1.8 A and back down to 0.2 A, so the actuator reads 0 m at the lowest current of that range
on its major loop (by the wiping-out property, every later return from a 1.8 A peak to
0.2 A reads 0 again); ``sensor_offset_m`` shifts the zero further.

Notes
-----
The Preisach plane is discretised into a grid of ``relay_grid_size`` points per axis on
``[threshold_min_a, threshold_max_a]``; each grid cell holds a uniform density of relays.
The output is evaluated exactly, through the Everett function ``F(a, b)`` (mass of the
relays with ``alpha <= a`` and ``beta < b``, tabulated on the grid and bilinearly
interpolated) and the memory of alternating dominant extrema ``(M_k, m_k)``, ``M_1 > M_2 >
...``, ``m_1 < m_2 < ...``:

``P = sum_k F(M_k, m_k) - sum_k F(M_{k+1}, m_k)``.

The wiping-out property removes the extrema a larger excursion erases, so the cost per
sample is a handful of table look-ups and the output has no staircase.

Sampling may be non-uniform.  Before the first sample the actuator was at rest at 0 A; the
first sample is applied at ``time[0]`` with no elapsed time, so the effects' lags start from
rest.

"""

import math
from typing import Any, Mapping

import numba
import numpy as np
import numpy.typing as npt

from ..errors import DataError, ModelError
from ..extensions.effect import plant_effects, PlantChunk, PlantEffect, PlantParameter

__all__ = ['ActuatorConfig', 'MagnetostrictiveActuator']

FloatArray = npt.NDArray[np.float64]

_STACK_CAPACITY = 128
# Indices into the scalar state vector: has a previous sample, its time, memory length.
_HAS_PREV, _T_PREV, _COUNT = range(3)
_N_SCALARS = 3

#: The hysteresis core's parameters (before the effects' in a config's order).
_MATERIAL = (
    PlantParameter('displacement_scale_m', 4.0e-5, 'displacement at magnetization 1', 'm',
                   low=0.0, low_open=True),
    PlantParameter('coercive_current_a', 0.3, 'Preisach density centre in (alpha-beta)/2',
                   'A', low=0.0),
    PlantParameter('coercive_spread_a', 0.1, 'Preisach density spread in (alpha-beta)/2',
                   'A', low=0.0, low_open=True),
    PlantParameter('interaction_center_a', 0.95, 'Preisach density centre in (alpha+beta)/2',
                   'A'),
    PlantParameter('interaction_spread_a', 0.45,
                   'Preisach density spread in (alpha+beta)/2', 'A', low=0.0, low_open=True),
    PlantParameter('reversible_fraction', 0.1, 'reversible share of the magnetization', '1',
                   low=0.0, high=1.0, high_open=True),
    PlantParameter('reversible_current_scale_a', 2.0,
                   'current where the reversible part is full', 'A', low=0.0, low_open=True),
    PlantParameter('map_linear_fraction', 0.15, 'linear share of the static map', '1',
                   low=0.0, high=1.0, low_open=True,
                   note='so that the static map is strictly increasing'),
    PlantParameter('map_knee', 0.55, 'knee of the static magnetostriction map', '1',
                   low=0.0, low_open=True),
    PlantParameter('threshold_min_a', -1.0, 'lowest relay threshold', 'A'),
    PlantParameter('threshold_max_a', 3.0, 'highest relay threshold', 'A', low=0.0,
                   low_open=True),
    PlantParameter('relay_grid_size', 161, 'grid points per axis of the Preisach plane',
                   low=3, high=2001),
)
#: The sensor's parameters (after the effects' in a config's order).
_SENSOR = (
    PlantParameter('noise_std_m', 0.0, 'sensor noise standard deviation, 0 = off', 'm',
                   low=0.0, note='(0 switches it off)'),
    PlantParameter('sensor_zero_current_a', 0.0, 'current where the sensor was zeroed', 'A'),
    PlantParameter('sensor_zero_peak_current_a', 0.0,
                   'peak current visited from rest before zeroing, 0 = none', 'A'),
    PlantParameter('sensor_offset_m', 0.0, 'constant added to every reading', 'm'),
)


class ActuatorConfig:
    """
    Parameters of :class:`MagnetostrictiveActuator` (SI units, named in each field).

    The fields are the hysteresis core's and the sensor's (below) and those of every
    registered effect with a plant step (:class:`~mpi_ros.extensions.effect.PlantEffect`,
    read from :data:`~mpi_ros.extensions.EFFECTS` when the config is built).  The built-in
    effects add ``creep_gain``, ``creep_time_constant_min_s``, ``creep_time_constant_max_s``
    and ``creep_lag_count`` (:mod:`~mpi_ros.extensions.creep`), ``eddy_time_constant_s``
    (:mod:`~mpi_ros.extensions.rate_dependence`), ``thermal_gain_m_per_a2`` and
    ``thermal_time_constant_s`` (:mod:`~mpi_ros.extensions.thermal_drift`) and
    ``dead_time_s`` (:mod:`~mpi_ros.extensions.dead_time`).  Every effect is off when its
    switch is 0 (the default).  The ROS parameter names are the field names, optionally
    prefixed with ``actuator.`` (see :meth:`from_mapping`).  The config is immutable; its
    fields are read as attributes (``config.creep_gain``).

    Parameters
    ----------
    **values : float or int
        Field values by name; missing fields keep their defaults.  Integers are accepted
        for float fields, integral floats for integer fields.

    Attributes
    ----------
    displacement_scale_m : float
        ``s_max``: displacement [m] at the magnetization-like state ``y = 1``.
    coercive_current_a : float
        Centre ``u_0`` of the Preisach density in ``u = (alpha - beta) / 2`` [A]; sets the
        loop width.
    coercive_spread_a : float
        Standard deviation ``sigma_u`` of the density in ``u`` [A].
    interaction_center_a : float
        Centre ``v_0`` of the density in ``v = (alpha + beta) / 2`` [A].
    interaction_spread_a : float
        Standard deviation ``sigma_v`` of the density in ``v`` [A].
    reversible_fraction : float
        ``r`` in [0, 1): share of the reversible (anhysteretic, linear) magnetization.
    reversible_current_scale_a : float
        ``i_r`` [A]: current at which the reversible part reaches ``r``.
    map_linear_fraction : float
        ``c`` in (0, 1]: linear share of the static map ``g``.
    map_knee : float
        ``y_0 > 0``: knee of the magnetostriction curve (inflection at ``y_0 / sqrt(2)``).
    threshold_min_a, threshold_max_a : float
        Extent of the Preisach plane [A]; relays outside do not exist.  Only relays with
        ``alpha > 0`` carry weight, so all are 'down' at rest.
    relay_grid_size : int
        Grid points per axis of the Preisach plane (Everett table size).
    noise_std_m : float
        Standard deviation [m] of additive Gaussian sensor noise.  0 switches it off.
    sensor_zero_current_a : float
        Current [A] at which the sensor was zeroed: the reading is shifted by minus the
        rate-independent displacement after the current went from rest (0 A) to
        ``sensor_zero_peak_current_a`` and then to this current.  With both 0 (the
        default) the sensor reads 0 m at rest.
    sensor_zero_peak_current_a : float
        Peak current [A] visited before zeroing (a conditioning half cycle); 0 for none.
    sensor_offset_m : float
        Further constant added to every reading [m] (a shifted sensor zero).

    Raises
    ------
    ModelError
        An unknown field, or a value of the wrong type or range (the first one found).

    Notes
    -----
    Static map (magnetostriction ``lambda ~ M^2`` at low magnetization, saturating at high):

    ``g(y) = c y + (1 - c) h(y) / h(1)``, ``h(y) = 1 - exp(-(y / y_0)^2)`` for ``y > 0``,
    ``h(y) = 0`` otherwise.  ``g`` is convex then concave (non-convex), not odd-symmetric
    about its midpoint, and ``g' >= c > 0``: strictly increasing, hence invertible.

    The effects' equations are in their modules (``PLANT``).  Noise: ``s_meas +=
    noise_std_m * N(0, 1)`` from a seeded :class:`numpy.random.Generator`.

    Examples
    --------
    >>> ActuatorConfig(creep_gain=0.05).creep_gain
    0.05

    """

    __slots__ = ('_values', '_effects')

    # The hysteresis core's and the sensor's fields, typed (the effects' are read through
    # __getattr__ as well).
    displacement_scale_m: float
    coercive_current_a: float
    coercive_spread_a: float
    interaction_center_a: float
    interaction_spread_a: float
    reversible_fraction: float
    reversible_current_scale_a: float
    map_linear_fraction: float
    map_knee: float
    threshold_min_a: float
    threshold_max_a: float
    relay_grid_size: int
    noise_std_m: float
    sensor_zero_current_a: float
    sensor_zero_peak_current_a: float
    sensor_offset_m: float

    def __init__(self, **values: Any) -> None:
        effects = plant_effects()
        parameters = _parameters(effects)
        unknown = [name for name in values if name not in parameters]
        if unknown:
            msg = (f'unknown actuator parameter {unknown[0]!r}; valid names are'
                   f' {", ".join(sorted(parameters))}')
            raise ModelError(msg)
        checked: dict[str, float | int] = {}
        for name, spec in parameters.items():
            checked[name] = _checked_type(spec, values.get(name, spec.default))
        object.__setattr__(self, '_values', checked)
        object.__setattr__(self, '_effects', tuple(effects))
        for name, spec in parameters.items():
            if not spec.accepts(checked[name]):
                self._reject(name, spec.expected, spec.default)
        if not checked['threshold_min_a'] < checked['threshold_max_a']:
            self._reject('threshold_min_a', f'< threshold_max_a = {checked["threshold_max_a"]}',
                         parameters['threshold_min_a'].default)
        for _, plant in effects:
            wrong = plant.check(checked) if plant.check is not None else None
            if wrong is not None:
                self._reject(wrong[0], wrong[1], parameters[wrong[0]].default)

    def _reject(self, name: str, expected: str, default: float | int) -> None:
        msg = (f'actuator.{name} must be {expected}; found {self._values[name]!r};'
               f' fix the parameter (default {default!r})')
        raise ModelError(msg)

    def __getattr__(self, name: str) -> Any:
        """Return a field's value (the effects' fields included)."""
        try:
            return object.__getattribute__(self, '_values')[name]
        except KeyError:
            msg = f'ActuatorConfig has no field {name!r}'
            raise AttributeError(msg) from None

    def __setattr__(self, name: str, value: Any) -> None:
        """Refuse: the config is immutable."""
        msg = f'ActuatorConfig is immutable; build a new one instead of setting {name!r}'
        raise AttributeError(msg)

    def __eq__(self, other: object) -> bool:
        """Tell whether two configs have the same fields and values."""
        if not isinstance(other, ActuatorConfig):
            return NotImplemented
        same: bool = self._values == other._values
        return same

    def __hash__(self) -> int:
        """Hash the fields and values."""
        return hash(tuple(self._values.items()))

    def __repr__(self) -> str:
        """Return ``ActuatorConfig(name=value, ...)``."""
        return f'ActuatorConfig({", ".join(f"{k}={v!r}" for k, v in self._values.items())})'

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle by value (a config built again from its fields)."""
        return (_restore, (dict(self._values),))

    @property
    def effects(self) -> tuple[tuple[str, PlantEffect], ...]:
        """Return the plant steps of the effects registered when the config was built."""
        effects: tuple[tuple[str, PlantEffect], ...] = self._effects
        return effects

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any], *,
                     prefix: str = 'actuator.') -> 'ActuatorConfig':
        """
        Build a config from a flat mapping such as ROS parameters.

        Parameters
        ----------
        mapping : mapping of str to number
            Keys are field names (e.g. ``'creep_gain'``), with or without ``prefix``
            (``'actuator.creep_gain'``).  Missing keys keep their defaults.  Integers are
            accepted for float fields, integral floats for integer fields.
        prefix : str, optional
            Prefix stripped from the keys; default ``'actuator.'``.

        Returns
        -------
        ActuatorConfig
            The validated config.

        Raises
        ------
        ModelError
            Unknown key, a key given twice, or a value of the wrong type or range.

        Examples
        --------
        >>> ActuatorConfig.from_mapping({'actuator.creep_gain': 0.05}).creep_gain
        0.05

        """
        names = set(_parameters(plant_effects()))
        values: dict[str, Any] = {}
        for key, value in mapping.items():
            name = key[len(prefix):] if prefix and key.startswith(prefix) else key
            if name not in names:
                msg = (f'unknown actuator parameter {key!r}; valid names are'
                       f' {", ".join(sorted(names))} (optionally prefixed {prefix!r})')
                raise ModelError(msg)
            if name in values:
                msg = f'actuator parameter {name!r} is given twice; keep one of the keys'
                raise ModelError(msg)
            values[name] = value
        return cls(**values)

    def to_mapping(self, *, prefix: str = '') -> dict[str, float | int]:
        """
        Return the fields as a flat dict, keys optionally prefixed (``'actuator.'``).

        Parameters
        ----------
        prefix : str, optional
            Prepended to every key; default none.

        Returns
        -------
        dict of str to float or int
            Round-trips through :meth:`from_mapping`.

        """
        return {prefix + key: value for key, value in self._values.items()}

    @classmethod
    def parameters(cls) -> tuple[PlantParameter, ...]:
        """
        Return every field's description, read from the effect registry now.

        Returns
        -------
        tuple of PlantParameter
            The hysteresis core's, the registered effects' (in signal-chain order) and
            the sensor's fields: name, default, description, unit and range.

        """
        return tuple(_parameters(plant_effects()).values())

    @classmethod
    def descriptions(cls) -> dict[str, str]:
        """
        Return a one-line description with unit for every field (for parameter descriptors).

        Returns
        -------
        dict of str to str
            Field name to description.

        """
        return {p.name: p.text for p in cls.parameters()}


def _parameters(effects: list[tuple[str, PlantEffect]]) -> dict[str, PlantParameter]:
    """Return every field by name: the core's, the effects' (in chain order), the sensor's."""
    parameters = {p.name: p for p in _MATERIAL}
    for name, plant in effects:
        for p in plant.parameters:
            if p.name in parameters or any(p.name == q.name for q in _SENSOR):
                msg = (f'effect {name!r}: plant parameter {p.name!r} is a field of the actuator'
                       ' already; give it another name')
                raise ModelError(msg)
            parameters[p.name] = p
    parameters.update((p.name, p) for p in _SENSOR)
    return parameters


def _checked_type(spec: PlantParameter, value: Any) -> float | int:
    """Return a value as the field's plain Python type; raise ModelError when it is not."""
    number = (isinstance(value, (int, float, np.integer, np.floating))
              and not isinstance(value, bool))
    if isinstance(spec.default, int):
        # Integral floats are accepted: YAML and ROS tools may write 81.0 for 81.
        if number and math.isfinite(value) and float(value).is_integer():
            return int(value)
        expected = 'an integer'
    else:
        if number and math.isfinite(value):
            return float(value)
        expected = 'a finite number'
    msg = f'actuator.{spec.name} must be {expected}; found {value!r}'
    raise ModelError(msg)


def _restore(values: dict[str, Any]) -> ActuatorConfig:
    return ActuatorConfig(**values)


class MagnetostrictiveActuator:
    """
    Simulated magnetostrictive actuator, batch and streaming (see the module notes).

    Parameters
    ----------
    config : ActuatorConfig, optional
        Parameters; the default config when omitted.
    seed : int or None, optional
        Seed of the sensor-noise generator (:func:`numpy.random.default_rng`).  ``None``
        draws fresh entropy, as numpy does.  Only used when ``noise_std_m > 0``.
    core : object, optional
        Another hysteresis core in place of the built-in Preisach kernel (steps 2-4), e.g. a
        :class:`mpi_ros.plant.preisach.DiscretePreisachCore`: ``core.start()`` gives its
        state at rest, ``core.run(state, current)`` advances it in place over the current
        the material sees and returns the displacement [m].  The effects' steps and the
        sensor wrap it as they wrap the built-in core; the config's core parameters are
        then unused.

    Examples
    --------
    >>> act = MagnetostrictiveActuator()
    >>> s = act.simulate([0.0, 0.1, 0.2], [0.0, 1.0, 1.8])
    >>> bool(s[0] == 0.0 and 0 < s[1] < s[2] < 1e-4)
    True

    """

    def __init__(self, config: ActuatorConfig | None = None, *,
                 seed: int | None = None, core: Any = None) -> None:
        self._other_core = core
        self._config = ActuatorConfig() if config is None else config
        if not isinstance(self._config, ActuatorConfig):
            msg = f'config must be an ActuatorConfig; found {type(config).__name__}'
            raise ModelError(msg)
        self._seed = seed
        cfg = self._config
        self._table = _everett_table(cfg)
        self._grid_lo = float(cfg.threshold_min_a)
        self._grid_step = (cfg.threshold_max_a - cfg.threshold_min_a) / (cfg.relay_grid_size - 1)
        self._map_norm = 1.0 - math.exp(-1.0 / cfg.map_knee ** 2)
        # The effects' plant steps that are switched on, in signal-chain order.
        values = cfg.to_mapping()
        self._values = values
        steps = [plant for _, plant in cfg.effects if plant.is_on(values)]
        self._input_steps = tuple(p for p in steps if p.stage == 'input')
        self._output_steps = tuple(p for p in steps if p.stage == 'output')
        # The compiled core's constant arguments (read once: the config's fields are looked
        # up through __getattr__).
        self._core = (self._table, self._grid_lo, self._grid_step, cfg.reversible_fraction,
                      cfg.reversible_current_scale_a, cfg.map_linear_fraction, cfg.map_knee,
                      self._map_norm, cfg.displacement_scale_m)
        self._noise_std = cfg.noise_std_m
        self._sensor_shift = cfg.sensor_offset_m - self._zeroed_displacement()
        self._state = self._initial_state()

    @property
    def config(self) -> ActuatorConfig:
        """Return the actuator parameters (immutable)."""
        return self._config

    def reset(self) -> None:
        """Return to rest at 0 A (all relays down, lags at 0) and re-seed the noise."""
        self._state = self._initial_state()

    def simulate(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """
        Simulate a whole experiment from rest; the streaming state is left untouched.

        Parameters
        ----------
        time : array_like of float, shape (N,)
            Sample times [s], strictly increasing (uniform or not).
        current : array_like of float, shape (N,)
            Coil current [A].

        Returns
        -------
        ndarray of float, shape (N,)
            Measured displacement [m].  Identical to ``reset()`` followed by :meth:`step`
            (or :meth:`advance`) over the same samples, with the same seed.

        Raises
        ------
        DataError
            Shapes differ, values are not finite or ``time`` is not strictly increasing.

        """
        t, x = _check_series(time, current)
        return self._run(self._initial_state(), t, x)

    def advance(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """
        Continue the streaming state over a chunk of samples.

        Parameters
        ----------
        time : array_like of float, shape (N,)
            Sample times [s], strictly increasing and after the last sample seen.
        current : array_like of float, shape (N,)
            Coil current [A].

        Returns
        -------
        ndarray of float, shape (N,)
            Measured displacement [m]; chunked calls equal one :meth:`simulate`.

        Raises
        ------
        DataError
            As :meth:`simulate`, or the chunk starts at or before the last sample time.

        """
        t, x = _check_series(time, current)
        last = self._state['scalars'][_T_PREV]
        if self._state['scalars'][_HAS_PREV] and t[0] <= last:
            msg = (f'time must be after the last sample ({float(last)!r} s); found'
                   f' {float(t[0])!r} s; call reset() to start a new experiment')
            raise DataError(msg)
        return self._run(self._state, t, x)

    def step(self, t: float, current: float) -> float:
        """
        Advance by one sample.

        Parameters
        ----------
        t : float
            Sample time [s], after the previous one.
        current : float
            Coil current [A].

        Returns
        -------
        float
            Measured displacement [m].

        Raises
        ------
        DataError
            Non-finite values or a time not after the previous sample.

        """
        scalars = self._state['scalars']
        if (type(t) is float and type(current) is float and math.isfinite(t)
                and math.isfinite(current) and not (scalars[_HAS_PREV] and t <= scalars[_T_PREV])):
            # The common case (the plant simulator node, once per command) without the
            # array checks of the boundary; anything else goes through advance().
            return float(self._run(self._state, np.array([t]), np.array([current]))[0])
        return float(self.advance([t], [current])[0])

    def static_map(self, magnetization: npt.ArrayLike) -> FloatArray:
        """
        Evaluate the static magnetostriction map ``s_max g(y)``.

        Parameters
        ----------
        magnetization : array_like of float
            Magnetization-like state ``y`` [1] (0 at rest, about 1 near saturation).

        Returns
        -------
        ndarray of float
            Displacement [m] without creep, drift, delay or noise.

        """
        y = np.asarray(magnetization, dtype=np.float64)
        cfg = self._config
        h = np.where(y > 0, -np.expm1(-(np.maximum(y, 0.0) / cfg.map_knee) ** 2), 0.0)
        g = cfg.map_linear_fraction * y + (1 - cfg.map_linear_fraction) * h / self._map_norm
        return cfg.displacement_scale_m * g

    def _zeroed_displacement(self) -> float:
        # Rate-independent displacement where the sensor was zeroed: from rest (0 A) to the
        # peak current, then to the zero current.
        cfg = self._config
        if cfg.sensor_zero_current_a == 0.0 and cfg.sensor_zero_peak_current_a == 0.0:
            return 0.0
        state = self._initial_state()
        path = np.array([0.0, cfg.sensor_zero_peak_current_a, cfg.sensor_zero_current_a])
        return float(self._material(state, path)[-1])

    def _initial_state(self) -> dict[str, Any]:
        scalars = np.zeros(_N_SCALARS)
        scalars[_COUNT] = 1.0  # one rising extremum pair (0 A, 0 A): all relays down
        return {
            'scalars': scalars,
            'maxima': np.zeros(_STACK_CAPACITY),
            'minima': np.zeros(_STACK_CAPACITY),
            'input': [plant.start(self._values) for plant in self._input_steps],
            'output': [plant.start(self._values) for plant in self._output_steps],
            'rng': np.random.default_rng(self._seed),
            'core': None if self._other_core is None else self._other_core.start(),
        }

    def _material(self, state: dict[str, Any], current: FloatArray) -> FloatArray:
        """Return the hysteresis core's displacement for the current the material sees."""
        if self._other_core is not None:
            other: FloatArray = self._other_core.run(state['core'], current)
            return other
        out: FloatArray = _kernel(current, *self._core, state['scalars'], state['maxima'],
                                  state['minima'])
        return out

    def _run(self, state: dict[str, Any], t: FloatArray, x: FloatArray) -> FloatArray:
        # The signal chain: input-side steps, the hysteresis core, output-side steps,
        # then the sensor (zero and noise).
        seen = x
        if self._input_steps:
            chunk = PlantChunk(t, x)
            for plant, plant_state in zip(self._input_steps, state['input']):
                seen = plant.run(plant_state, chunk, seen)
        out = self._material(state, seen)
        if self._output_steps:
            chunk = PlantChunk(t, x, out)
            for plant, plant_state in zip(self._output_steps, state['output']):
                out = plant.run(plant_state, chunk, out)
        scalars = state['scalars']
        scalars[_HAS_PREV] = 1.0
        scalars[_T_PREV] = t[-1]
        if self._sensor_shift != 0.0:
            out = out + self._sensor_shift
        if self._noise_std > 0:
            out = out + self._noise_std * state['rng'].standard_normal(out.shape[0])
        return out


def _check_series(time: npt.ArrayLike, current: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Validate a (time, current) pair at the boundary; raise DataError."""
    arrays = []
    for name, values, unit in (('time', time, 's'), ('current', current, 'A')):
        try:
            arr = np.ascontiguousarray(values, dtype=np.float64)
        except (TypeError, ValueError) as err:
            msg = f'{name} must be numbers [{unit}]; found {type(values).__name__}'
            raise DataError(msg) from err
        if arr.ndim != 1 or arr.size == 0:
            msg = (f'{name} must be a non-empty 1-D sequence [{unit}]; found shape'
                   f' {arr.shape}; pass one value per sample')
            raise DataError(msg)
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            msg = (f'{name} must be finite; found {arr[bad[0]]} at index {bad[0]}'
                   f' ({bad.size} non-finite value(s)); drop or repair those samples')
            raise DataError(msg)
        arrays.append(arr)
    t, x = arrays
    if t.shape != x.shape:
        msg = (f'time and current must have the same length; found {t.size} and {x.size};'
               ' pass one time stamp per current sample')
        raise DataError(msg)
    steps = np.diff(t)
    if steps.size and not np.all(steps > 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        msg = (f'time must be strictly increasing; found {float(t[k + 1])!r} s after'
               f' {float(t[k])!r} s at index {k + 1}; sort the samples and drop duplicates')
        raise DataError(msg)
    return t, x


def _everett_table(cfg: ActuatorConfig) -> FloatArray:
    """
    Tabulate the Everett function ``F[i, j]`` = mass of relays with alpha <= g_i, beta < g_j.

    The density is Gaussian in ``u = (alpha - beta) / 2`` and ``v = (alpha + beta) / 2``,
    restricted to ``beta <= alpha`` and ``alpha > 0``, normalised to total mass 1.
    """
    n = cfg.relay_grid_size
    grid = np.linspace(cfg.threshold_min_a, cfg.threshold_max_a, n)
    centres = 0.5 * (grid[:-1] + grid[1:])
    alpha = centres[:, None]
    beta = centres[None, :]
    u = 0.5 * (alpha - beta)
    v = 0.5 * (alpha + beta)
    density = (np.exp(-0.5 * ((u - cfg.coercive_current_a) / cfg.coercive_spread_a) ** 2)
               * np.exp(-0.5 * ((v - cfg.interaction_center_a) / cfg.interaction_spread_a) ** 2))
    mass = np.where(beta < alpha, density, 0.0)
    diag = np.arange(n - 1)
    mass[diag, diag] = 0.5 * density[diag, diag]  # cells cut by the diagonal alpha = beta
    mass[grid[1:] <= 0.0, :] = 0.0  # no relay with alpha <= 0: all are down at rest
    total = mass.sum()
    if not total > 0:
        msg = ('actuator Preisach density has no mass on the grid; move interaction_center_a'
               ' or widen threshold_min_a .. threshold_max_a')
        raise ModelError(msg)
    table = np.zeros((n, n))
    table[1:, 1:] = np.cumsum(np.cumsum(mass, axis=0), axis=1) / total
    return table


@numba.njit(cache=True, nogil=True)
def _everett(table: FloatArray, lo: float, step: float, a: float,
             b: float) -> float:  # pragma: no cover - compiled
    """Bilinear interpolation of the Everett table, clamped to the grid."""
    n = table.shape[0]
    fa = (a - lo) / step
    fb = (b - lo) / step
    fa = min(max(fa, 0.0), n - 1.0)
    fb = min(max(fb, 0.0), n - 1.0)
    ia = min(int(fa), n - 2)
    ib = min(int(fb), n - 2)
    ta = fa - ia
    tb = fb - ib
    value: float = ((1.0 - ta) * ((1.0 - tb) * table[ia, ib] + tb * table[ia, ib + 1])
                    + ta * ((1.0 - tb) * table[ia + 1, ib] + tb * table[ia + 1, ib + 1]))
    return value


@numba.njit(cache=True, nogil=True)
def _kernel(current: FloatArray, table: FloatArray, grid_lo: float, grid_step: float,
            rev_frac: float, rev_scale: float, lin: float, knee: float, map_norm: float,
            scale: float, scalars: FloatArray, maxima: FloatArray,
            minima: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """Advance the Preisach memory over the samples; return the material's displacement."""
    n_samples = current.shape[0]
    capacity = maxima.shape[0]
    out = np.empty(n_samples)
    count = int(scalars[2])
    for k in range(n_samples):
        x = current[k]
        # Preisach memory: alternating dominant extrema with wiping out.
        last = minima[count - 1]
        if x > last:
            if maxima[count - 1] == minima[count - 1]:
                maxima[count - 1] = x
                minima[count - 1] = x
            elif count < capacity:
                maxima[count] = x
                minima[count] = x
                count += 1
            else:  # memory full: forget the innermost loop
                maxima[count - 1] = x
                minima[count - 1] = x
            while count >= 2 and maxima[count - 2] <= x:
                maxima[count - 2] = x
                minima[count - 2] = x
                count -= 1
        elif x < last:
            minima[count - 1] = x
            while count >= 2 and minima[count - 2] >= x:
                count -= 1
                minima[count - 1] = x
        preisach = 0.0
        for j in range(count):
            preisach += _everett(table, grid_lo, grid_step, maxima[j], minima[j])
            if j + 1 < count:
                preisach -= _everett(table, grid_lo, grid_step, maxima[j + 1], minima[j])
        # Magnetization-like state and static magnetostriction map.
        y = (1.0 - rev_frac) * preisach + rev_frac * x / rev_scale
        hy = -math.expm1(-(y / knee) ** 2) if y > 0.0 else 0.0
        out[k] = scale * (lin * y + (1.0 - lin) * hy / map_norm)
    scalars[2] = count
    return out
