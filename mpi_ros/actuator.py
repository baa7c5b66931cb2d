# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Simulated magnetostrictive actuator: the "truth" plant for tests, demos and the simulator node.

(Over 500 lines on purpose: one simulator - its configuration, its compiled Preisach kernel
with the effects' states, and the sensor model - that only makes sense read together.)

This is deliberately *not* a modified Prandtl-Ishlinskii model, so that identifying an MPI
model on its data is a fair test.  The coil current ``i`` [A] drives

1. an optional eddy-current lag, ``tau_e di_e/dt = i - i_e`` (off: ``i_e = i``);
2. a Preisach operator ``P[i_e]`` in [0, 1]: a superposition of relay hysterons with
   switching thresholds ``alpha >= beta`` (up at ``alpha``, down at ``beta``), weighted by a
   smooth density that is Gaussian in the coercive coordinate ``u = (alpha - beta) / 2`` and
   the interaction coordinate ``v = (alpha + beta) / 2``;
3. a magnetization-like state ``y = (1 - r) P + r i_e / i_r`` (``r`` reversible fraction);
4. a strictly increasing, non-convex, asymmetric static map (magnetostriction with
   saturation) ``s_h = s_max g(y)``;
5. optional slow effects (creep, thermal drift), a dead time and sensor noise;
6. a sensor zero: the reading is ``s - s_0 + sensor_offset_m``, where ``s_0`` is the
   displacement where the sensor was zeroed (0 at rest by default, see below).

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

Sampling may be non-uniform.  Each first-order lag is advanced exactly for an input that
is linear between samples (first-order hold): with ``h = t_k - t_{k-1}``,
``a = exp(-h / tau)`` and slope ``q = (u_k - u_{k-1}) / h``,

``x_k = a x_{k-1} + (1 - a) u_k + q (a h - tau (1 - a))``.

Before the first sample the actuator was at rest at 0 A; the first sample is applied at
``time[0]`` with no elapsed time, so the lags start from rest.

"""

from collections import deque
from dataclasses import asdict, dataclass, field, fields
import math
from typing import Any, Mapping

import numba
import numpy as np
import numpy.typing as npt

from .errors import DataError, ModelError

__all__ = ['ActuatorConfig', 'MagnetostrictiveActuator']

FloatArray = npt.NDArray[np.float64]

_STACK_CAPACITY = 128
# Indices into the scalar state vector of the compiled kernel.
_HAS_PREV, _T_PREV, _I_PREV, _I_EFF, _SH_PREV, _THERMAL, _ISQ_PREV, _COUNT = range(8)
_N_SCALARS = 8


def _describe(text: str) -> dict[str, str]:
    return {'description': text}


@dataclass(frozen=True)
class ActuatorConfig:
    """
    Parameters of :class:`MagnetostrictiveActuator` (SI units, named in each field).

    Every optional effect is off when its strength is 0 (the default).  The ROS parameter
    names are the field names, optionally prefixed with ``actuator.`` (see
    :meth:`from_mapping`).

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
    creep_gain : float
        ``gamma >= 0``: fraction of a change of the hysteretic displacement that creeps in
        afterwards.  0 switches creep off.
    creep_time_constant_min_s, creep_time_constant_max_s : float
        Range [s] of the logarithmically spaced creep time constants.
    creep_lag_count : int
        Number of first-order lags in the creep bank.
    eddy_time_constant_s : float
        ``tau_e >= 0`` [s] of the eddy-current lag.  0 switches rate dependence off.
    thermal_gain_m_per_a2 : float
        ``k_T`` [m/A^2]: displacement per unit thermal state.  0 switches drift off.
    thermal_time_constant_s : float
        ``tau_T > 0`` [s] of the thermal state.
    dead_time_s : float
        ``L >= 0`` [s]: pure delay between current and measured displacement.
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

    Notes
    -----
    Static map (magnetostriction ``lambda ~ M^2`` at low magnetization, saturating at high):

    ``g(y) = c y + (1 - c) h(y) / h(1)``, ``h(y) = 1 - exp(-(y / y_0)^2)`` for ``y > 0``,
    ``h(y) = 0`` otherwise.  ``g`` is convex then concave (non-convex), not odd-symmetric
    about its midpoint, and ``g' >= c > 0``: strictly increasing, hence invertible.

    Creep (thermally activated domain-wall relaxation with a spread of time constants,
    which gives the ``log t`` law over ``[tau_min, tau_max]``): lags ``q_j`` with
    ``tau_j dq_j/dt = s_h - q_j``, ``tau_j`` log-spaced, add ``gamma mean_j(q_j)``.  After a
    step of ``s_h`` by ``D`` the output creeps by about ``gamma D`` over those decades.

    Rate dependence (eddy currents delay the field in the core): the material sees
    ``i_e`` with ``tau_e di_e/dt = i - i_e``; loops widen as ``omega tau_e`` grows.

    Thermal drift (Joule heating of the coil, thermal expansion of the rod):
    ``tau_T dT/dt = i^2 - T`` (``T`` in A^2, steady state the mean of ``i^2``), adding
    ``k_T T``.

    Dead time: ``s_meas(t) = s(t - L)``, linearly interpolated on the sampled stream, 0
    before the first sample.  Noise: ``s_meas += noise_std_m * N(0, 1)`` from a seeded
    :class:`numpy.random.Generator`.

    """

    displacement_scale_m: float = field(
        default=4.0e-5, metadata=_describe('displacement at magnetization 1 [m]'))
    coercive_current_a: float = field(
        default=0.3, metadata=_describe('Preisach density centre in (alpha-beta)/2 [A]'))
    coercive_spread_a: float = field(
        default=0.1, metadata=_describe('Preisach density spread in (alpha-beta)/2 [A]'))
    interaction_center_a: float = field(
        default=0.95, metadata=_describe('Preisach density centre in (alpha+beta)/2 [A]'))
    interaction_spread_a: float = field(
        default=0.45, metadata=_describe('Preisach density spread in (alpha+beta)/2 [A]'))
    reversible_fraction: float = field(
        default=0.1, metadata=_describe('reversible share of the magnetization [1]'))
    reversible_current_scale_a: float = field(
        default=2.0, metadata=_describe('current where the reversible part is full [A]'))
    map_linear_fraction: float = field(
        default=0.15, metadata=_describe('linear share of the static map [1]'))
    map_knee: float = field(
        default=0.55, metadata=_describe('knee of the static magnetostriction map [1]'))
    threshold_min_a: float = field(
        default=-1.0, metadata=_describe('lowest relay threshold [A]'))
    threshold_max_a: float = field(
        default=3.0, metadata=_describe('highest relay threshold [A]'))
    relay_grid_size: int = field(
        default=161, metadata=_describe('grid points per axis of the Preisach plane'))
    creep_gain: float = field(
        default=0.0, metadata=_describe('creep fraction of a change, 0 = off [1]'))
    creep_time_constant_min_s: float = field(
        default=0.1, metadata=_describe('shortest creep time constant [s]'))
    creep_time_constant_max_s: float = field(
        default=100.0, metadata=_describe('longest creep time constant [s]'))
    creep_lag_count: int = field(
        default=7, metadata=_describe('number of creep lags'))
    eddy_time_constant_s: float = field(
        default=0.0, metadata=_describe('eddy-current lag time constant, 0 = off [s]'))
    thermal_gain_m_per_a2: float = field(
        default=0.0, metadata=_describe('thermal drift per unit state, 0 = off [m/A^2]'))
    thermal_time_constant_s: float = field(
        default=30.0, metadata=_describe('thermal time constant [s]'))
    dead_time_s: float = field(
        default=0.0, metadata=_describe('dead time of the measurement, 0 = off [s]'))
    noise_std_m: float = field(
        default=0.0, metadata=_describe('sensor noise standard deviation, 0 = off [m]'))
    sensor_zero_current_a: float = field(
        default=0.0, metadata=_describe('current where the sensor was zeroed [A]'))
    sensor_zero_peak_current_a: float = field(
        default=0.0, metadata=_describe('peak current visited from rest before zeroing,'
                                        ' 0 = none [A]'))
    sensor_offset_m: float = field(
        default=0.0, metadata=_describe('constant added to every reading [m]'))

    def __post_init__(self) -> None:
        """Check every field; raise ModelError naming the first bad one."""
        for f in fields(self):
            value = getattr(self, f.name)
            number = (isinstance(value, (int, float, np.integer, np.floating))
                      and not isinstance(value, bool))
            convert: type[int] | type[float]
            if f.type in (int, 'int'):
                # Integral floats are accepted: YAML and ROS tools may write 81.0 for 81.
                ok = number and math.isfinite(value) and float(value).is_integer()
                expected, convert = 'an integer', int
            else:
                ok = number and math.isfinite(value)
                expected, convert = 'a finite number', float
            if not ok:
                msg = f'actuator.{f.name} must be {expected}; found {value!r}'
                raise ModelError(msg)
            # Plain Python types, so that to_mapping() declares ROS parameters of the right type.
            object.__setattr__(self, f.name, convert(value))
        positive = ('displacement_scale_m', 'coercive_spread_a', 'interaction_spread_a',
                    'reversible_current_scale_a', 'map_knee', 'creep_time_constant_min_s',
                    'thermal_time_constant_s', 'threshold_max_a')
        for name in positive:
            self._require(name, getattr(self, name) > 0, '> 0')
        for name in ('coercive_current_a', 'creep_gain', 'eddy_time_constant_s',
                     'dead_time_s', 'noise_std_m'):
            self._require(name, getattr(self, name) >= 0, '>= 0 (0 switches it off)')
        self._require('reversible_fraction', 0 <= self.reversible_fraction < 1, 'in [0, 1)')
        self._require('map_linear_fraction', 0 < self.map_linear_fraction <= 1,
                      'in (0, 1] so that the static map is strictly increasing')
        self._require('threshold_min_a', self.threshold_min_a < self.threshold_max_a,
                      f'< threshold_max_a = {self.threshold_max_a}')
        self._require('relay_grid_size', 3 <= self.relay_grid_size <= 2001, 'in [3, 2001]')
        self._require('creep_time_constant_max_s',
                      self.creep_time_constant_max_s >= self.creep_time_constant_min_s,
                      f'>= creep_time_constant_min_s = {self.creep_time_constant_min_s}')
        self._require('creep_lag_count', 1 <= self.creep_lag_count <= 100, 'in [1, 100]')

    def _require(self, name: str, condition: bool, expected: str) -> None:
        if not condition:
            msg = (f'actuator.{name} must be {expected}; found {getattr(self, name)!r};'
                   f' fix the parameter (default {_DEFAULTS[name]!r})')
            raise ModelError(msg)

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
        names = {f.name for f in fields(cls)}
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
        return {prefix + key: value for key, value in asdict(self).items()}

    @classmethod
    def descriptions(cls) -> dict[str, str]:
        """
        Return a one-line description with unit for every field (for parameter descriptors).

        Returns
        -------
        dict of str to str
            Field name to description.

        """
        return {f.name: f.metadata['description'] for f in fields(cls)}


_DEFAULTS = {f.name: f.default for f in fields(ActuatorConfig)}


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

    Examples
    --------
    >>> act = MagnetostrictiveActuator()
    >>> s = act.simulate([0.0, 0.1, 0.2], [0.0, 1.0, 1.8])
    >>> bool(s[0] == 0.0 and 0 < s[1] < s[2] < 1e-4)
    True

    """

    def __init__(self, config: ActuatorConfig | None = None, *,
                 seed: int | None = None) -> None:
        self._config = ActuatorConfig() if config is None else config
        if not isinstance(self._config, ActuatorConfig):
            msg = f'config must be an ActuatorConfig; found {type(config).__name__}'
            raise ModelError(msg)
        self._seed = seed
        cfg = self._config
        self._table = _everett_table(cfg)
        self._grid_lo = float(cfg.threshold_min_a)
        self._grid_step = (cfg.threshold_max_a - cfg.threshold_min_a) / (cfg.relay_grid_size - 1)
        self._creep_taus = np.geomspace(cfg.creep_time_constant_min_s,
                                        cfg.creep_time_constant_max_s, cfg.creep_lag_count)
        self._map_norm = 1.0 - math.exp(-1.0 / cfg.map_knee ** 2)
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
        return float(_kernel(np.arange(3.0), path, self._table,
                             self._grid_lo, self._grid_step, cfg.reversible_fraction,
                             cfg.reversible_current_scale_a, cfg.map_linear_fraction,
                             cfg.map_knee, self._map_norm, cfg.displacement_scale_m, 0.0, 0.0,
                             self._creep_taus, 0.0, cfg.thermal_time_constant_s,
                             state['scalars'], state['maxima'], state['minima'],
                             state['creep'])[-1])

    def _initial_state(self) -> dict[str, Any]:
        scalars = np.zeros(_N_SCALARS)
        scalars[_COUNT] = 1.0  # one rising extremum pair (0 A, 0 A): all relays down
        return {
            'scalars': scalars,
            'maxima': np.zeros(_STACK_CAPACITY),
            'minima': np.zeros(_STACK_CAPACITY),
            'creep': np.zeros(self._config.creep_lag_count),
            'delay_time': deque(),
            'delay_value': deque(),
            'rng': np.random.default_rng(self._seed),
        }

    def _run(self, state: dict[str, Any], t: FloatArray, x: FloatArray) -> FloatArray:
        cfg = self._config
        out = _kernel(t, x, self._table, self._grid_lo, self._grid_step,
                      cfg.reversible_fraction, cfg.reversible_current_scale_a,
                      cfg.map_linear_fraction, cfg.map_knee, self._map_norm,
                      cfg.displacement_scale_m, cfg.eddy_time_constant_s, cfg.creep_gain,
                      self._creep_taus, cfg.thermal_gain_m_per_a2, cfg.thermal_time_constant_s,
                      state['scalars'], state['maxima'], state['minima'], state['creep'])
        if cfg.dead_time_s > 0:
            out = _delay(state, t, out, cfg.dead_time_s)
        if self._sensor_shift != 0.0:
            out = out + self._sensor_shift
        if cfg.noise_std_m > 0:
            out = out + cfg.noise_std_m * state['rng'].standard_normal(out.shape[0])
        return out


def _delay(state: dict[str, Any], t: FloatArray, out: FloatArray, dead_time: float) -> FloatArray:
    """Return ``out`` delayed by ``dead_time`` using (and updating) the history buffer."""
    times: deque[float] = state['delay_time']
    values: deque[float] = state['delay_value']
    hist_t = np.concatenate([np.fromiter(times, float, len(times)), t])
    hist_v = np.concatenate([np.fromiter(values, float, len(values)), out])
    delayed: FloatArray = np.interp(t - dead_time, hist_t, hist_v, left=0.0)
    # Keep only what later samples can still need: the last point at or before t[-1] - L.
    keep_from = max(int(np.searchsorted(hist_t, t[-1] - dead_time, side='right')) - 1, 0)
    times.clear()
    values.clear()
    times.extend(hist_t[keep_from:].tolist())
    values.extend(hist_v[keep_from:].tolist())
    return delayed


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
def _lag(y0: float, u0: float, u1: float, h: float,
         tau: float) -> float:  # pragma: no cover - compiled
    """Exact first-order-lag update for an input linear between samples (first-order hold)."""
    a = math.exp(-h / tau)
    one_minus_a = -math.expm1(-h / tau)
    slope = (u1 - u0) / h
    return a * y0 + one_minus_a * u1 + slope * (a * h - tau * one_minus_a)


@numba.njit(cache=True, nogil=True)
def _kernel(time: FloatArray, current: FloatArray, table: FloatArray, grid_lo: float,
            grid_step: float, rev_frac: float, rev_scale: float, lin: float, knee: float,
            map_norm: float, scale: float, eddy_tau: float, creep_gain: float,
            creep_taus: FloatArray, thermal_gain: float, thermal_tau: float,
            scalars: FloatArray, maxima: FloatArray, minima: FloatArray,
            creep: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """Advance the actuator state over the samples; return the undelayed, noiseless output."""
    n_samples = time.shape[0]
    n_creep = creep_taus.shape[0]
    capacity = maxima.shape[0]
    out = np.empty(n_samples)
    count = int(scalars[7])
    for k in range(n_samples):
        t = time[k]
        i = current[k]
        has_prev = scalars[0] > 0.0
        h = t - scalars[1] if has_prev else 0.0
        # Eddy-current lag of the current seen by the material.
        if eddy_tau > 0.0:
            if has_prev:
                scalars[3] = _lag(scalars[3], scalars[2], i, h, eddy_tau)
            x = scalars[3]
        else:
            x = i
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
        s_h = scale * (lin * y + (1.0 - lin) * hy / map_norm)
        s = s_h
        if creep_gain > 0.0:
            acc = 0.0
            for j in range(n_creep):
                if has_prev:
                    creep[j] = _lag(creep[j], scalars[4], s_h, h, creep_taus[j])
                acc += creep[j]
            s += creep_gain * acc / n_creep
        if thermal_gain != 0.0:
            if has_prev:
                scalars[5] = _lag(scalars[5], scalars[6], i * i, h, thermal_tau)
            s += thermal_gain * scalars[5]
        scalars[0] = 1.0
        scalars[1] = t
        scalars[2] = i
        scalars[4] = s_h
        scalars[6] = i * i
        out[k] = s
    scalars[7] = count
    return out
