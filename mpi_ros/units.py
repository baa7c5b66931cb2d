# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Units of recorded signals: one rule for every command and the identifier.

Everything the package stores and computes is in SI units (REP 103): time in s, the output
(displacement) in m, the input in A for a current-driven actuator (a coil) or in V for a
voltage-driven one (a piezo stack).  A recording says its units in one of two ways:

- **A unit suffix in the signal's name** (a CSV column, a bag topic or joint): a token such as
  ``_V``, ``_mV``, ``_A``, ``_mA``, ``_m``, ``_mm``, ``_um``, ``_nm``, ``_s``, ``_ms``,
  ``_us`` (``Vplus_V``, ``D1_nm``, ``time_ms``), or a word (``voltage``, ``volts``,
  ``current``, ``microns``, ...).  The last unit token of the name counts.
- **An option** (``--input-unit`` / ``--output-unit`` / ``--time-unit``, the identifier's
  ``input_unit`` / ``output_unit`` / ``time_unit``): the unit of the values as recorded (after
  ``--input-scale`` etc.); it overrides the name.

The values are converted to SI as they are read (:func:`resolve_units` gives the factors).
A name's unit and a scale: with scale 1 the values are in the named unit; a scale equal to the
unit's factor to SI (``D1_nm`` with ``--output-scale 1e-9``) already converted them; any other
scale is the user's own conversion to SI (``--input-scale``: "multiply the input by this to
get A"), and the name is not applied.  Nothing named or stated: A, m and s.

The input's SI unit tells the *input quantity* (``current`` or ``voltage``), which a model
records as ``model.input_quantity`` (:data:`INPUT_QUANTITY_KEY`) so that messages, YAML
headers and plots name the actuator's real unit.

Scales that look wrong (:func:`scale_warnings`): a displacement range above 1 mm (a
smart-material actuator moves micrometres: nm or um read as m), and samples 0.1 s apart or
more (ms read as s) get a warning that names the option to pass.
"""

from dataclasses import dataclass
import math
import re
from typing import Any, Mapping

import numpy as np
import numpy.typing as npt

__all__ = ['INPUT_QUANTITIES', 'INPUT_QUANTITY_KEY', 'INPUT_UNITS', 'OUTPUT_UNITS',
           'SignalUnits', 'TIME_UNITS', 'input_unit_of', 'named_unit', 'resolve_units',
           'scale_warnings']

#: Input units with their SI unit and factor to it.
INPUT_UNITS = {'A': ('A', 1.0), 'mA': ('A', 1e-3), 'uA': ('A', 1e-6), 'µA': ('A', 1e-6),
               'V': ('V', 1.0), 'mV': ('V', 1e-3), 'kV': ('V', 1e3), 'uV': ('V', 1e-6),
               'µV': ('V', 1e-6)}
#: Output (length) units with their factor to m.
OUTPUT_UNITS = {'m': 1.0, 'mm': 1e-3, 'um': 1e-6, 'µm': 1e-6, 'nm': 1e-9, 'pm': 1e-12}
#: Time units with their factor to s.
TIME_UNITS = {'s': 1.0, 'ms': 1e-3, 'us': 1e-6, 'µs': 1e-6, 'ns': 1e-9}
#: The input quantities and their SI units.
INPUT_QUANTITIES = {'current': 'A', 'voltage': 'V'}
#: The parameter key that records a model's input quantity.
INPUT_QUANTITY_KEY = 'model.input_quantity'

#: Largest displacement range [m] that is plausible for a smart-material actuator.
DISPLACEMENT_LIMIT = 1e-3
#: Smallest sample interval [s] that suggests a time column in ms read as s.
INTERVAL_LIMIT = 0.1
#: Largest input [A] plausible for a coil current when the name says no unit (a piezo's
#: voltage read as a current reaches tens to hundreds).
CURRENT_LIMIT = 20.0

# Words in a name that name a unit (case-insensitive), and the unit.
_WORDS = {'volt': 'V', 'volts': 'V', 'voltage': 'V', 'millivolt': 'mV', 'millivolts': 'mV',
          'amp': 'A', 'amps': 'A', 'ampere': 'A', 'amperes': 'A', 'current': 'A',
          'milliamp': 'mA', 'milliamps': 'mA',
          'meter': 'm', 'meters': 'm', 'metre': 'm', 'metres': 'm',
          'micron': 'µm', 'microns': 'µm', 'micrometer': 'µm', 'micrometers': 'µm',
          'nanometer': 'nm', 'nanometers': 'nm', 'millimeter': 'mm', 'millimeters': 'mm',
          'seconds': 's', 'second': 's', 'milliseconds': 'ms', 'millisecond': 'ms',
          'microseconds': 'us', 'microsecond': 'us'}
# Unit tokens matched with their case (``V``, ``mV``, ``nm``; ``u``/``µ``/``μ`` for micro).
_TOKENS = {'V': 'V', 'mV': 'mV', 'kV': 'kV', 'uV': 'uV', 'µV': 'µV', 'μV': 'µV',
           'A': 'A', 'mA': 'mA', 'uA': 'uA', 'µA': 'µA', 'μA': 'µA',
           'm': 'm', 'mm': 'mm', 'um': 'µm', 'µm': 'µm', 'μm': 'µm', 'nm': 'nm', 'pm': 'pm',
           's': 's', 'ms': 'ms', 'us': 'us', 'µs': 'us', 'μs': 'us', 'ns': 'ns'}
_KNOWN: dict[str, Mapping[str, Any]] = {'input': INPUT_UNITS, 'output': OUTPUT_UNITS,
                                        'time': TIME_UNITS}
_BASE = {'input': 'A', 'output': 'm', 'time': 's'}


@dataclass(frozen=True)
class SignalUnits:
    """
    The units of a recording as read, and the factors that bring it to SI.

    Attributes
    ----------
    time, input, output : str
        The unit of each signal as recorded (after the scales), e.g. ``'ms'``, ``'V'``,
        ``'nm'``.
    time_factor, input_factor, output_factor : float
        Factors to s, to A or V, and to m.
    found : str
        How they were found (one phrase per signal).
    input_known : bool
        Whether the input's unit was named or stated (False: A by default).

    Examples
    --------
    >>> units = resolve_units('time_ms', 'Vplus_V', 'D1_nm')
    >>> units.input_quantity, units.si_input, units.output_factor, units.time_factor
    ('voltage', 'V', 1e-09, 0.001)

    """

    time: str = 's'
    input: str = 'A'  # noqa: A003 - the signal's name
    output: str = 'm'
    time_factor: float = 1.0
    input_factor: float = 1.0
    output_factor: float = 1.0
    found: str = ''
    input_known: bool = False

    @property
    def si_input(self) -> str:
        """Return the SI unit of the input: ``'A'`` or ``'V'``."""
        return INPUT_UNITS[self.input][0] if self.input in INPUT_UNITS else 'A'

    @property
    def input_quantity(self) -> str:
        """Return ``'current'`` or ``'voltage'``."""
        return 'voltage' if self.si_input == 'V' else 'current'


def named_unit(name: str, role: str) -> str | None:
    """
    Return the unit a signal's name names for a role, or None.

    Parameters
    ----------
    name : str
        A CSV column, a topic or a joint name.
    role : {'input', 'output', 'time'}
        Which signal it is (only that role's units count).

    Returns
    -------
    str or None
        A key of :data:`INPUT_UNITS`, :data:`OUTPUT_UNITS` or :data:`TIME_UNITS`.

    Examples
    --------
    >>> named_unit('D1_nm', 'output'), named_unit('Vplus_V', 'input'), named_unit('t', 'time')
    ('nm', 'V', None)

    """
    known = _KNOWN[role]
    for token in reversed([w for w in re.split(r'[^0-9A-Za-zµμ]+', name) if w]):
        unit = _TOKENS.get(token) or _WORDS.get(token.lower())
        if unit is not None and unit in known:
            return unit
    return None


def resolve_units(time_name: str = '', input_name: str = '', output_name: str = '', *,
                  time_scale: float = 1.0, input_scale: float = 1.0,
                  output_scale: float = 1.0, time_unit: str | None = None,
                  input_unit: str | None = None,
                  output_unit: str | None = None) -> SignalUnits:
    """
    Find the units of a recording's signals and their factors to SI (the module's rule).

    Parameters
    ----------
    time_name, input_name, output_name : str
        The signals' names ('' when unknown or none).
    time_scale, input_scale, output_scale : float
        The reader's factors (``--time-scale`` etc.).
    time_unit, input_unit, output_unit : str, optional
        The units stated by the user (a key of :data:`TIME_UNITS`, :data:`INPUT_UNITS`,
        :data:`OUTPUT_UNITS`); they override the names.

    Returns
    -------
    SignalUnits
        The units after the scales and the factors to SI.

    Raises
    ------
    ValueError
        For a stated unit that is not known (the options check them first).

    Examples
    --------
    >>> resolve_units(output_name='D1_nm', output_scale=1e-9).output_factor
    1.0
    >>> resolve_units(input_name='volts', input_scale=0.1).input   # the scale converts to A
    'A'

    """
    found = []
    units: dict[str, tuple[str, float]] = {}
    for role, name, scale, stated in (('time', time_name, time_scale, time_unit),
                                      ('input', input_name, input_scale, input_unit),
                                      ('output', output_name, output_scale, output_unit)):
        if stated is not None:
            if stated not in _KNOWN[role]:
                msg = (f'unknown {role} unit {stated!r}; known: '
                       f'{", ".join(_KNOWN[role])}')
                raise ValueError(msg)
            units[role] = (stated, _factor(role, stated))
            found.append(f'{role} in {stated} (stated)')
            continue
        named = named_unit(name, role)
        if named is None:
            units[role] = (_BASE[role], 1.0)
            if name:
                found.append(f'{role} {name!r} names no unit: {_BASE[role]}')
            continue
        factor = _factor(role, named)
        si = INPUT_UNITS[named][0] if role == 'input' else _BASE[role]
        if scale == 1.0:
            units[role] = (named, factor)
            found.append(f'{role} {name!r}: {named}')
        elif math.isclose(scale, factor, rel_tol=1e-9):
            units[role] = (si, 1.0)
            found.append(f'{role} {name!r} times {scale:g}: {si}')
        else:
            base = _BASE[role]
            units[role] = (base, 1.0)
            found.append(f'{role} {name!r} times {scale:g}: {base} (the scale converts it)')
    known = input_unit is not None or named_unit(input_name, 'input') is not None
    return SignalUnits(time=units['time'][0], input=units['input'][0],
                       output=units['output'][0], time_factor=units['time'][1],
                       input_factor=units['input'][1], output_factor=units['output'][1],
                       found='; '.join(found), input_known=known)


def input_unit_of(quantity: str | None) -> str:
    """
    Return the SI unit of an input quantity (``model.input_quantity``).

    Parameters
    ----------
    quantity : str or None
        ``'current'``, ``'voltage'``, or None (unset: current).

    Returns
    -------
    str
        ``'A'`` or ``'V'``.

    Examples
    --------
    >>> input_unit_of('voltage'), input_unit_of(None)
    ('V', 'A')

    """
    return INPUT_QUANTITIES.get(quantity or 'current', 'A')


def scale_warnings(time: npt.ArrayLike, displacement: npt.ArrayLike, *, timed: bool,
                   units: SignalUnits, option: dict[str, str],
                   current: npt.ArrayLike | None = None) -> list[str]:
    """
    Return warnings about scales that look wrong, each naming the option to pass.

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s], after the conversion.
    displacement : array_like of float, shape (N,)
        Output [m], after the conversion.
    timed : bool
        Whether the time is a time base (not the sample index).
    units : SignalUnits
        The units the values were read in.
    option : dict
        How the user writes ``output_unit``, ``time_unit`` and ``input_unit``
        (``--output-unit``).
    current : array_like of float, shape (N,), optional
        The input, after the conversion: a current of more than 20 A whose unit nothing
        names is warned about (a voltage read as a current).

    Returns
    -------
    list of str
        One sentence per suspicious signal (none when the scales look right).

    Examples
    --------
    >>> scale_warnings([0.0, 1.0], [0.0, 520.4], timed=True, units=SignalUnits(),
    ...                option={'output_unit': '--output-unit', 'time_unit': '--time-unit'})[0][:46]
    'the displacement spans 520 m, more than 0.001 '

    """
    warnings = []
    y = np.asarray(displacement, dtype=np.float64)
    finite = y[np.isfinite(y)]
    span = float(np.ptp(finite)) if finite.size else 0.0
    if span > DISPLACEMENT_LIMIT:
        warnings.append(
            f'the displacement spans {span:.3g} m, more than {DISPLACEMENT_LIMIT:g} m: large '
            f'for a smart-material actuator (read in {units.output}); if the output is in '
            f'nm or um, pass {option["output_unit"]} nm (or um), or end the column name '
            'with _nm / _um')
    if current is not None and not units.input_known:
        x = np.asarray(current, dtype=np.float64)
        x = x[np.isfinite(x)]
        largest = float(np.max(np.abs(x))) if x.size else 0.0
        if largest > CURRENT_LIMIT:
            flag = option.get('input_unit', '--input-unit')
            warnings.append(
                f'the input reaches {largest:.3g} A, large for a coil current, and its name '
                f'says no unit; if it is a voltage, pass {flag} V (or end the column name '
                'with _V): the model then records a voltage input')
    t = np.asarray(time, dtype=np.float64)
    if timed and t.size > 1:
        steps = np.diff(t)
        steps = steps[np.isfinite(steps) & (steps > 0)]
        interval = float(np.median(steps)) if steps.size else 0.0
        if interval >= INTERVAL_LIMIT:
            warnings.append(
                f'the samples are {interval:.3g} s apart (read in {units.time}): slow for an '
                f'actuator record; if the time is in ms, pass {option["time_unit"]} ms (or '
                'end the time column name with _ms)')
    return warnings


def _factor(role: str, unit: str) -> float:
    if role == 'input':
        return INPUT_UNITS[unit][1]
    return float(_KNOWN[role][unit])
