# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Physical signatures of the extensions in the baseline residual, and a diagnostic excitation.

The MPI model Gamma is rate independent: while the input holds, its output is constant, and
its response to a sinusoidal burst has a phase that does not depend on the frequency.  So
two parts of a record show the dynamic effects directly, without any fitted extension:

**Holds** (input constant for at least ``minimum_hold`` seconds).  After the first
``settle`` seconds (lags and delays of a few milliseconds have settled) the residual
``r = y - Gamma[x]`` of each hold is regressed on ``[1, u, u^2, log u]`` with
``u = (t - t_0) / T_hold``.  Creep is a *spread* of time constants around the hold's own
time scale (Kuhnen's creep operators, the ``log t`` law), so it leaves a ``log u``
component that no smooth drift explains.  Thermal drift has one time constant much longer
than a hold: a smooth (linear, slightly curved) drift and no ``log u`` component.  Tests:

- ``log_chi2 = sum_k (a_k / se_k)^2`` of the ``log u`` coefficients ``a_k`` (``se_k`` from
  the residual scatter of that hold's regression), chi-square with one degree of freedom
  per hold;
- ``drift_chi2 = sum_k (b_k / se_k)^2`` of the slopes ``b_k`` of ``[1, u]`` fits, chi-square
  likewise.

Noise alone gives both near their degrees of freedom; a lag or a dead time settles before
``settle`` and gives neither.

**Bursts** (runs of at least three input cycles of equal period and amplitude, found from
the input alone).  Per burst frequency ``f`` the measured output and the baseline
simulation are fitted by ``c cos + s sin + offset + slope`` at ``f`` (first cycle dropped:
minor-loop transient) and ``g(f) = log(Y / S)`` (log-amplitude ratio + i phase difference)
is formed.  Gamma contributes a frequency-independent ``g``; an input lag gives
``g = c - log(1 + i w tau)`` (phase ``-atan(w tau)``, amplitude falling), a dead time
``g = c - i w L`` (phase linear in ``w``, amplitude flat).  Both laws are fitted (one
parameter plus a complex constant each); an F test of the better law against the
constant says whether a fast effect is present, the smaller residual says which.
"""

from dataclasses import dataclass
import math
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy import stats

from .invertibility import monotone_branches
from ..extensions.fitting import hold_segments

__all__ = ['HoldSignature', 'BurstSignature', 'hold_signature', 'burst_signature',
           'burst_segments']

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class HoldSignature:
    """
    Creep and drift tests on the residual during input holds (see the module notes).

    Attributes
    ----------
    holds : int
        Holds used.
    log_chi2, log_p : float
        Chi-square of the ``log u`` (creep) coefficients and its p-value.
    drift_chi2, drift_p : float
        Chi-square of the smooth-drift slopes and its p-value.
    log_amplitude, drift_amplitude : float
        RMS over holds of the ``log u`` coefficient and of the drift over a hold [m].

    """

    holds: int
    log_chi2: float
    log_p: float
    drift_chi2: float
    drift_p: float
    log_amplitude: float
    drift_amplitude: float


@dataclass(frozen=True)
class BurstSignature:
    """
    Frequency-response test on the burst responses (see the module notes).

    Attributes
    ----------
    frequencies : list of float
        Burst frequencies [Hz], ascending.
    log_ratio : list of complex
        ``log(Y / S)`` per frequency (real: log-amplitude ratio, imaginary: phase [rad]).
    lag_time_constant, lag_sse : float
        Best input-lag ``tau`` [s] and the residual sum of squares of its law.
    delay, delay_sse : float
        Best dead time ``L`` [s] and the residual of its law.
    constant_sse : float
        Residual of a frequency-independent ``g`` (no fast effect).
    f_statistic, p : float
        F test of the better law against the constant, and its p-value.

    """

    frequencies: list[float]
    log_ratio: list[complex]
    lag_time_constant: float
    lag_sse: float
    delay: float
    delay_sse: float
    constant_sse: float
    f_statistic: float
    p: float

    @property
    def law(self) -> str:
        """Return ``'lag'`` or ``'delay'``: the law with the smaller residual."""
        return 'lag' if self.lag_sse < self.delay_sse else 'delay'


def hold_signature(time: FloatArray, current: FloatArray, residual: FloatArray, *,
                   minimum_hold: float = 1.0, settle: float = 0.05) -> HoldSignature | None:
    """
    Test the residual during input holds for a ``log t`` component and a smooth drift.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s].
    current : ndarray of float, shape (N,)
        Input [A].
    residual : ndarray of float, shape (N,)
        Measured minus baseline-simulated output [m].
    minimum_hold : float
        Shortest hold used [s].
    settle : float
        Time after the start of a hold that is skipped [s].

    Returns
    -------
    HoldSignature or None
        None when the record has no hold of ``minimum_hold`` with 20 samples.

    """
    logs, drifts = [], []
    for a, b in hold_segments(time, current, minimum_hold):
        w = slice(a, b + 1)
        u = (time[w] - time[a] - settle) / (time[b] - time[a] - settle)
        keep = u > 0.0
        if keep.sum() < 20:
            continue
        u, r = u[keep], residual[w][keep]
        full = np.column_stack([np.ones(u.size), u, u * u, np.log(u)])
        logs.append(_coefficient(full, r, 3))
        drifts.append(_coefficient(full[:, :2], r, 1))
    if not logs:
        return None
    la, ls = np.array(logs).T
    da, ds = np.array(drifts).T
    log_chi2 = float(np.sum((la / ls) ** 2))
    drift_chi2 = float(np.sum((da / ds) ** 2))
    k = la.size
    return HoldSignature(k, log_chi2, float(stats.chi2.sf(log_chi2, k)), drift_chi2,
                         float(stats.chi2.sf(drift_chi2, k)),
                         float(np.sqrt(np.mean(la ** 2))), float(np.sqrt(np.mean(da ** 2))))


def burst_segments(time: FloatArray, current: FloatArray, *, minimum_cycles: int = 3,
                   tolerance: float = 0.2) -> list[tuple[int, int, float]]:
    """
    Find bursts: runs of input half-cycles of equal duration and amplitude.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s].
    current : ndarray of float, shape (N,)
        Input [A].
    minimum_cycles : int
        Fewest full cycles of a burst.
    tolerance : float
        Largest relative change of half-cycle duration and amplitude within a burst.

    Returns
    -------
    list of (int, int, float)
        ``(start, end, frequency [Hz])`` per burst, without its first cycle.

    """
    branches = monotone_branches(current, 0.02 * float(np.ptp(current)))
    found = []
    i = 0
    while i < len(branches):
        j = i
        while j + 1 < len(branches):
            (a0, b0), (a1, b1) = branches[j], branches[j + 1]
            h0, h1 = time[b0] - time[a0], time[b1] - time[a1]
            d0, d1 = abs(current[b0] - current[a0]), abs(current[b1] - current[a1])
            if h0 <= 0 or d0 <= 0 or abs(h1 / h0 - 1) > tolerance or \
                    abs(d1 / d0 - 1) > tolerance:
                break
            j += 1
        if j - i + 1 >= 2 * minimum_cycles:
            start, end = branches[i + 2][0], branches[j][1]
            found.append((start, end, (j - i - 1) / 2.0 / float(time[end] - time[start])))
            i = j + 1
        else:
            i += 1
    return found


def burst_signature(time: FloatArray, current: FloatArray, measured: FloatArray,
                    simulated: FloatArray) -> BurstSignature | None:
    """
    Fit the lag and the delay law to the measured/simulated burst responses.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s].
    current : ndarray of float, shape (N,)
        Input [A].
    measured, simulated : ndarray of float, shape (N,)
        Measured output and the baseline simulation [m].

    Returns
    -------
    BurstSignature or None
        None when fewer than three distinct burst frequencies are present.

    """
    rows: dict[float, complex] = {}
    for a, b, f in burst_segments(time, current):
        tt = time[a:b + 1] - time[a]
        w = 2.0 * math.pi * f
        design = np.column_stack([np.cos(w * tt), np.sin(w * tt), np.ones_like(tt), tt])
        cy = np.linalg.lstsq(design, measured[a:b + 1], rcond=None)[0]
        cs = np.linalg.lstsq(design, simulated[a:b + 1], rcond=None)[0]
        ratio = complex(cy[0], -cy[1]) / complex(cs[0], -cs[1])
        if ratio != 0 and all(abs(f / g - 1) > 0.05 for g in rows):
            rows[round(f, 6)] = ratio
    if len(rows) < 3:
        return None
    freqs = np.array(sorted(rows))
    g = np.log(np.array([rows[k] for k in freqs]))
    g = g.real + 1j * np.unwrap(g.imag)
    omega = 2.0 * math.pi * freqs
    constant = float(np.sum(np.abs(g - g.mean()) ** 2))
    grid = np.concatenate([[0.0], np.geomspace(1e-2 / omega[-1], 10.0 / omega[0], 600)])
    lag, lag_sse = _fit_law(g, [-np.log(1.0 + 1j * omega * p) for p in grid], grid)
    delay, delay_sse = _fit_law(g, [-1j * omega * p for p in grid], grid)
    dof = 2 * freqs.size - 3
    best = min(lag_sse, delay_sse)
    stat = (constant - best) / max(best / dof, 1e-300)
    return BurstSignature([float(v) for v in freqs], [complex(v) for v in g], lag, lag_sse,
                          delay, delay_sse, constant, float(stat),
                          float(stats.f.sf(stat, 1, dof)))


def _coefficient(design: FloatArray, r: FloatArray, index: int) -> tuple[float, float]:
    coef, *_ = np.linalg.lstsq(design, r, rcond=None)
    dof = max(r.size - design.shape[1], 1)
    s2 = float(np.sum((r - design @ coef) ** 2)) / dof
    cov = s2 * np.linalg.pinv(design.T @ design)
    return float(coef[index]), math.sqrt(max(float(cov[index, index]), 1e-300))


def _fit_law(g: Any, shapes: list[Any], grid: FloatArray) -> tuple[float, float]:
    best, best_sse = 0.0, math.inf
    for p, m in zip(grid, shapes):
        c = np.mean(g - m)
        sse = float(np.sum(np.abs(g - m - c) ** 2))
        if sse < best_sse:
            best, best_sse = float(p), sse
    return best, best_sse
