# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Random, extreme and wrong-typed values for every model key (hypothesis strategies)."""

import math

from hypothesis import strategies as st
from mpi_ros.compensation.updates import model_keys

#: Subnormals, the largest doubles, signed zeros, infinities, NaN, and ordinary values.
EXTREME = [0.0, -0.0, 5e-324, -5e-324, 1e-310, 2.2250738585072014e-308, 1e-200, 1e308,
           -1e308, 1.7976931348623157e308, math.inf, -math.inf, math.nan, 1e-9, 1.0, -1.0]
NUMBERS = st.one_of(st.sampled_from(EXTREME), st.floats(allow_nan=True, allow_infinity=True),
                    st.floats(-10.0, 10.0))
ARRAYS = st.one_of(
    st.lists(NUMBERS, max_size=20),
    st.builds(lambda v, k: [v] * k, st.sampled_from(EXTREME), st.integers(0, 40)),
    st.builds(lambda k: [0.01 * i for i in range(k)], st.integers(0, 5000)),
)
WRONG = st.one_of(st.text(max_size=5), st.booleans(), st.integers(-3, 3), st.none(),
                  st.lists(st.text(max_size=3), max_size=3),
                  st.lists(st.integers(-3, 3), max_size=4), st.lists(st.booleans(), max_size=3))


def type_name(value):
    """Return the rclpy type name a Python value arrives as (an empty list: double array)."""
    if value is None:
        return 'not_set'
    if isinstance(value, bool):
        return 'bool'
    if isinstance(value, int):
        return 'integer'
    if isinstance(value, float):
        return 'double'
    if isinstance(value, str):
        return 'string'
    if not value or isinstance(value[0], float):
        return 'double_array'
    return {bool: 'bool_array', int: 'integer_array', str: 'string_array'}[type(value[0])]


FACTORS = st.sampled_from([5e-324, 1e-310, 1e-200, 1e-20, -1.0, 1e20, 1e200, 1e308])


def _near(base):
    """Draw arrays close to a valid one: scaled, one item replaced, all replaced."""
    size = len(base)
    return st.one_of(
        FACTORS.map(lambda f: [v * f for v in base]),
        st.tuples(st.integers(0, size - 1), st.sampled_from(EXTREME)).map(
            lambda c: [c[1] if i == c[0] else v for i, v in enumerate(base)]),
        st.sampled_from(EXTREME).map(lambda v: [v] * size),
    )


@st.composite
def pushes(draw, specs, base=None):
    """
    Draw a request of 1 to 6 model keys, each a random, extreme or wrong-typed value.

    With ``base`` (a valid model's keys) half the requests change 1 to 3 of its keys by a
    little: arrays scaled by a subnormal or huge factor or with one item extreme, scalars
    extreme; these pass the form checks more often than random values do.
    """
    if base is not None and draw(st.booleans()):
        keys = draw(st.lists(st.sampled_from(sorted(base)), min_size=1, max_size=3,
                             unique=True))
        return {key: draw(_near(base[key]) if isinstance(base[key], list)
                          else st.sampled_from(EXTREME)) for key in keys}
    keys = draw(st.lists(st.sampled_from(model_keys()), min_size=1, max_size=6, unique=True))
    request = {}
    for key in keys:
        array = specs[key].type_.endswith('array')
        request[key] = draw(st.one_of(ARRAYS if array else NUMBERS, WRONG,
                                      NUMBERS if array else ARRAYS))
    return request
