# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The time base of the desired displacement: when each sample is, for an effect's lags.

An extended model's lags (the eddy-current lag's lead filter, creep, thermal drift) are
inverted on the desired signal's own time base, never on the jittered times at which DDS
happens to deliver its messages: a lead filter differentiates whatever time base it is
given, and one bunched message (two arrivals 0.1 ms apart in a 1 kHz stream) made the old
arrival-timed lead swing the command across the range.

``message_time`` of the compensator nodes chooses the time base:

- ``nominal`` (the default): every sample ``sample_period`` after the one before, across
  messages too; no clock is read.  Identical commands whatever the arrival times.
- ``arrival``: the nominal spacing as well, but a *pause* of the stream is counted.  When a
  message arrives more than the pause threshold (:func:`pause_threshold`: 100 sample periods,
  at least 0.1 s) after the previous one, the gap is added in whole sample periods, so the
  slow lags (creep, thermal drift) see the time the actuator held its last command.  Shorter
  gaps, late and bunched messages (DDS jitter, a busy executor) are timed as the nominal
  stream: the arrival clock never makes an interval shorter than ``sample_period``, nor one
  longer unless the stream stopped.  :class:`MessageClock` holds this rule.

Where a message carries its own stamp the core takes it as given
(:meth:`~mpi_ros.compensation.Compensator.command` ``time=``); stamps that do not increase are
counted (``bad_time``) and timed ``sample_period`` apart.
"""

import math

import numpy as np
import numpy.typing as npt

__all__ = ['MessageClock', 'MESSAGE_TIMES', 'pause_threshold', 'PAUSE_PERIODS', 'PAUSE_MIN']

FloatArray = npt.NDArray[np.float64]

#: The values of the nodes' ``message_time`` parameter.
MESSAGE_TIMES = ('nominal', 'arrival')

#: A gap between two messages of more than this many sample periods is a pause ...
PAUSE_PERIODS = 100
#: ... and of at least this many seconds [s].
PAUSE_MIN = 0.1


def pause_threshold(sample_period: float) -> float:
    """
    Return the gap [s] between two messages above which the stream paused (``arrival``).

    Parameters
    ----------
    sample_period : float
        Nominal interval between two samples [s], > 0.

    Returns
    -------
    float
        ``max(PAUSE_PERIODS * sample_period, PAUSE_MIN)`` [s].

    Examples
    --------
    >>> pause_threshold(1e-3), pause_threshold(0.01)
    (0.1, 1.0)

    """
    return max(PAUSE_PERIODS * sample_period, PAUSE_MIN)


class MessageClock:
    """
    The stream times of messages that arrive one after the other (``message_time: arrival``).

    A message of K samples gets K times ``sample_period`` apart, the first one
    ``sample_period`` after the previous message's last sample; after a pause (the message
    came more than :func:`pause_threshold` after the previous one) the whole sample periods
    of the gap are added first.  The first message's last sample is at its arrival.  The
    times always increase by at least ``sample_period``, and arrivals that jitter, bunch or
    run back (below the threshold) give exactly the nominal times.  The sample period is
    given per message (a node's ``sample_period`` may change while it runs).

    Attributes
    ----------
    pauses : int
        Pauses counted so far.

    Examples
    --------
    >>> clock = MessageClock()                            # period 0.25 s: pauses over 25 s
    >>> clock.times(100.0, 2, 0.25).tolist(), clock.times(100.01, 1, 0.25).tolist()
    ([99.75, 100.0], [100.25])
    >>> clock.time(160.0, 0.25)                          # a 59.99 s pause: 240 periods
    160.25

    """

    def __init__(self) -> None:
        self._arrival: float | None = None     # arrival of the previous message [s]
        self._last: float | None = None        # stream time of its last sample [s]
        self.pauses = 0

    def times(self, arrival: float, samples: int, sample_period: float) -> FloatArray:
        """
        Return the stream times [s] of a message of ``samples`` samples that arrived now.

        Parameters
        ----------
        arrival : float
            When the message arrived [s] (steady clock).
        samples : int
            Samples in the message, K >= 1.
        sample_period : float
            Nominal interval between two samples [s], > 0.

        Returns
        -------
        ndarray of float, shape (K,)
            Increasing stream times [s], ``sample_period`` apart.

        """
        period = float(sample_period)
        previous, self._arrival = self._arrival, float(arrival)
        if self._last is None:
            last = float(arrival) if math.isfinite(arrival) else 0.0
        elif previous is None:            # after reset: at the arrival, never back
            last = max(float(arrival) if math.isfinite(arrival) else -math.inf,
                       self._last + samples * period)
        else:
            steps = float(samples)
            ratio = (float(arrival) - previous) / period
            if math.isfinite(ratio) and ratio * period > pause_threshold(period):
                steps = max(steps, float(np.rint(ratio)))
                self.pauses += 1
            last = self._last + steps * period
        self._last = last
        return last - period * np.arange(samples - 1, -1, -1, dtype=np.float64)

    def time(self, arrival: float, sample_period: float) -> float:
        """Return the stream time [s] of a one-sample message (see :meth:`times`)."""
        return float(self.times(arrival, 1, sample_period)[0])

    def reset(self) -> None:
        """Forget the previous message: the next one is at its arrival (never earlier)."""
        self._arrival = None
