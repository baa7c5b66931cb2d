# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The diagnosis' one way of writing a number: 3 significant digits, lengths with a prefix.

The summary lines, ``summary.md`` (:mod:`mpi_ros.diagnosis.report`) and the progress lines
of :func:`~mpi_ros.diagnosis.diagnose` write their numbers with these functions: errors
and gains as percentages, times in ms or s, lengths in metres with the prefix that suits
the value.
"""

import math
from typing import Any

__all__ = ['LENGTH_PREFIXES', 'length', 'percent', 'signed_percent', 'significant']

#: Factors and names of the prefixes a length in metres is written with, largest first.
LENGTH_PREFIXES = ((1.0, 'm'), (1e-3, 'mm'), (1e-6, 'µm'), (1e-9, 'nm'), (1e-12, 'pm'))


def significant(value: Any, digits: int = 3) -> str:
    """
    Format a number with ``digits`` significant digits (plain, or exponent when tiny/huge).

    Examples
    --------
    >>> significant(0.0065317), significant(66.93), significant(48351.0), significant(5e-23)
    ('0.00653', '66.9', '4.84e+04', '5.00e-23')

    """
    if value is None or isinstance(value, bool):
        return 'n/a'
    v = float(value)
    if not math.isfinite(v):
        return 'n/a'
    if v == 0.0:
        return '0'
    rounded = float(f'{v:.{digits - 1}e}')
    exponent = math.floor(math.log10(abs(rounded)))
    if -3 <= exponent < digits:
        return f'{rounded:.{max(digits - 1 - exponent, 0)}f}'
    return f'{rounded:.{digits - 1}e}'


def percent(fraction: Any) -> str:
    """
    Write a fraction as a percentage with :func:`significant` digits.

    Examples
    --------
    >>> percent(0.012), percent(-0.5328)
    ('1.20 %', '-53.3 %')

    """
    return f'{significant(100.0 * float(fraction))} %'


def signed_percent(fraction: Any) -> str:
    """
    Write a fraction as a percentage with its sign, ``+`` included (a gain).

    Examples
    --------
    >>> signed_percent(0.532), signed_percent(-0.0173), signed_percent(0.0)
    ('+53.2 %', '-1.73 %', '+0 %')

    """
    text = percent(fraction)
    return text if text.startswith('-') else '+' + text


def length(value: Any, unit: str = 'm') -> str:
    """
    Write a length in the data's output unit; metres get the prefix that suits the value.

    Examples
    --------
    >>> length(7.151e-06), length(-2.5e-8), length(0.0), length(3.0, 'V'), length(None)
    ('7.15 µm', '-25.0 nm', '0 m', '3.00 V', 'n/a')

    """
    if value is None:
        return 'n/a'
    v = float(value)
    if unit != 'm' or v == 0.0:
        return f'{significant(v)} {unit}'
    factor, prefix = next(((f, p) for f, p in LENGTH_PREFIXES if abs(v) >= f),
                          LENGTH_PREFIXES[-1])
    return f'{significant(v / factor)} {prefix}'
