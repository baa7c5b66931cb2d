# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The report of ``mpi-ros demo``: ``report.md``, ``results.json`` and the PNG plots.

Written for a person who has not read the paper: the report names it, says in words what
the nonlinearity error (37) and the control error (38) measure, and what to look at in each
plot.  The plots show the displacement in µm and the current in A; the measured trace stays
visible (drawn on top of the model), every model is simulated from the record's first sample
from the start state the identification estimated (so model and data start together), and
the best straight line is drawn only over the displacement range of the data.
"""

import json
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ['PAPER', 'PAPER_ERRORS', 'write_report', 'write_effect_report']

#: The paper the model, the identification and the two error measures come from.
PAPER = ('K. Kuhnen, "Modeling, Identification and Compensation of Complex Hysteretic '
         'Nonlinearities: A Modified Prandtl-Ishlinskii Approach", European Journal of '
         'Control 9 (2003) 407-418')

#: The paper's nonlinearity errors (37) on its magnetostrictive actuator (section 5).
PAPER_ERRORS = {(0, 0): 0.4872, (4, 2): 0.0633, (8, 4): 0.0338, (14, 7): 0.0261}

#: Over which samples the demos measure (37).
_FITTED = ('the samples the fit used (all of them, unless the identification left out a start '
           'no state explains or ringing after steps)')
_WHOLE = 'the whole record'


def _measures(scope: str) -> list[str]:
    return [
        '**What the two numbers measure** (both are percentages; smaller is better):',
        '',
        '- **Nonlinearity error (37)**: how closely the identified model reproduces the '
        'recorded displacement. The model is driven with the recorded current from the first '
        'sample on, from the state it estimates the actuator was in; (37) is the largest '
        f'distance between its output and the measured displacement over {scope}, as a '
        'percentage of the displacement range of the record (the paper divides by the largest '
        'model output; the two agree when the displacement starts at 0, as in the paper).',
        '- **Control error (38)**: how closely the compensated actuator follows a desired '
        'displacement. The compensator turns each desired displacement into a current; (38) is '
        'the largest distance between the desired and the measured displacement while tracking, '
        'as a percentage of the largest desired displacement.',
        '',
        'Both are worst cases (a maximum over the run), not averages: a single spike counts.',
    ]


def _pyplot() -> Any:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    return plt


def _um(values: npt.ArrayLike) -> npt.NDArray[np.float64]:
    return np.asarray(values, dtype=np.float64) * 1e6


def _within(line: npt.NDArray[np.float64], low: float,
            high: float) -> npt.NDArray[np.float64]:
    # The line only where it lies inside the data's range (NaN breaks it elsewhere).
    return np.where((line >= low) & (line <= high), line, np.nan)


def write_report(out: Path, data: Any, models: dict[tuple[int, int], Any], t: np.ndarray,
                 desired: np.ndarray, traces: dict[str, np.ndarray],
                 results: dict[str, Any]) -> list[Path]:
    """
    Write the plain demo's report: ``report.md``, ``results.json``, two PNGs, the traces.

    Parameters
    ----------
    out : Path
        The output folder.
    data : Recording
        The identification record (time [s], current [A], displacement [m]).
    models : dict
        The identified models by order ``(n, l)``; ``(0, 0)`` and ``(14, 7)`` are drawn.
    t : ndarray of float, shape (K,)
        Tracking time [s].
    desired : ndarray of float, shape (K,)
        Desired displacement [m].
    traces : dict of str to ndarray
        Measured displacement [m] per controller, in the order of ``results['tracking']``.
    results : dict
        The demo's results (``identification``, ``tracking``, ``samples``, ...).

    Returns
    -------
    list of Path
        The files written.

    """
    plt = _pyplot()
    errors = {(r['n'], r['l']): r['nonlinearity_error'] for r in results['identification']}
    control = {r['controller']: r['control_error'] for r in results['tracking']}
    final = max(models, key=lambda order: order[0])
    x, y = data.current, _um(data.displacement)
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 5.0))
    ax = axes[0]
    model_y = _um(models[final].simulate(x))
    ax.plot(x, model_y, color='C1', lw=2.6, alpha=0.6,
            label=f'MPI model n={final[0]}, l={final[1]}: (37) {100 * errors[final]:.2f} %')
    if (0, 0) in models:
        # A straight line in the current (n = 0: no loops): drawn along a grid of the
        # record's currents, only where it stays within the measured displacements.
        grid = np.linspace(float(np.min(x)), float(np.max(x)), 400)
        line = _within(_um(models[(0, 0)].simulate(grid)), float(y.min()), float(y.max()))
        ax.plot(grid, line, color='C3', ls='--', lw=1.3,
                label=f'best straight line (n=0, l=0): (37) {100 * errors[(0, 0)]:.1f} %')
    ax.plot(x, y, color='k', lw=0.45, label='measured (plant simulator)')
    ax.plot(x[0], y[0], 'o', mfc='none', mec='k', ms=8, label='first sample (data)')
    ax.plot(x[0], model_y[0], 'x', color='C1', ms=8, mew=2, label='first sample (model)')
    ax.set(xlabel='current [A]', ylabel='displacement [µm]')
    ax.set_title('Identification record: does the model (orange) follow\nthe measured loops '
                 '(black) everywhere?', fontsize=10.5)
    ax.legend(fontsize=8, loc='upper left')
    ax = axes[1]
    lo, hi = float(np.min(desired)), float(np.max(desired))
    ax.plot(_um([lo, hi]), _um([lo, hi]), color='0.75', lw=4.0, label='ideal: measured = desired')
    for label, measured in traces.items():
        if label.startswith('linear') or label.endswith(f'l={final[1]}'):
            ax.plot(_um(desired), _um(measured), lw=0.8,
                    color='C0' if label.startswith('linear') else 'C1',
                    label=f'{label}: (38) {100 * control[label]:.2f} %')
    ax.set(xlabel='desired displacement [µm]', ylabel='measured displacement [µm]')
    ax.set_title('Compensated actuator: the closer to the grey diagonal, the better\n'
                 "(compare the paper's Fig. 12)", fontsize=10.5)
    ax.legend(fontsize=8, loc='upper left')
    fig.tight_layout()
    files = [out / 'loops.png', out / 'tracking_error.png', out / 'report.md',
             out / 'results.json', out / 'tracking.npz']
    _save_figure(fig, files[0])
    plt.close(fig)
    _tracking_figure(files[1], t, desired, traces, control,
                     'Tracking error while following the same desired trajectory: the closer '
                     'to 0, the better')
    lines = ['# mpi_ros demo: hysteresis compensation over DDS', '',
             'The modified Prandtl-Ishlinskii (MPI) model, its identification and the two '
             f'error measures below are those of {PAPER}; the numbers in brackets refer to its '
             'equations and figures.', '',
             f'**What ran.** The plant simulator (a magnetostrictive-like actuator: a Preisach '
             f'model and a static map with sensor noise, *not* an MPI model) was driven with '
             f'an excitation current and recorded into a bag ({results["samples"]} samples). '
             "MPI models of the paper's four orders were identified from the bag. Each was "
             'pushed into a fresh compensator process, which then drove a fresh plant along '
             'the same desired trajectory with minor loops; the uncompensated baseline is the '
             'best straight line of the model (`enabled:=false`). '
             f'ROS_DOMAIN_ID {results["domain_id"]}; {results["elapsed_s"]:.0f} s in all.', '',
             *_measures(_FITTED), '',
             '| model order n, l | nonlinearity error (37) | paper, its actuator |',
             '|---|---|---|']
    for r in results['identification']:
        paper = PAPER_ERRORS.get((r['n'], r['l']))
        name = 'best straight line' if (r['n'], r['l']) == (0, 0) else 'MPI'
        lines.append(f"| {r['n']}, {r['l']} ({name}) | {100 * r['nonlinearity_error']:.2f} % "
                     f"| {'' if paper is None else f'{100 * paper:.2f} %'} |")
    lines += ['', '| controller | control error (38) |', '|---|---|']
    lines += [f"| {r['controller']} | {100 * r['control_error']:.2f} % |"
              for r in results['tracking']]
    lines += ['', "The paper's compensated magnetostrictive actuator reaches a control error of "
              'about 3 %; uncompensated, its error is about 50 %.', '',
              '## Plots', '',
              '![loops](loops.png)', '',
              '*Left*: the identification record (black) with the model of the highest order '
              '(orange, drawn underneath so that the data stay visible) and the best straight '
              'line (red dashes, drawn only over the displacement range of the data). Each '
              'model is driven with the recorded current from the first sample, starting in '
              "the state the identification estimated for the record's start (circle and "
              'cross: data and model start together). Look for black loops the orange band '
              'does not cover. *Right*: the compensated actuator, measured against desired '
              'displacement, with the compensator and with the straight-line baseline; a '
              'perfect compensator lies on the grey diagonal.', '',
              '![tracking error](tracking_error.png)', '',
              '*Top*: measured minus desired displacement over time for every controller. '
              '*Bottom*: the MPI compensators only, enlarged. The largest excursion of each '
              'trace, over the largest desired displacement, is its control error (38).', '']
    _write_text(files[2], '\n'.join(lines))
    _write_text(files[3], json.dumps(results, indent=2))
    _save_traces(files[4], t, desired, traces)
    return files


def write_effect_report(out: Path, t: np.ndarray, desired: np.ndarray,
                        traces: dict[str, np.ndarray], results: dict[str, Any]) -> list[Path]:
    """
    Write the ``--effect`` demo's report: ``report.md``, ``results.json``, a PNG, arrays.

    Parameters
    ----------
    out : Path
        The output folder.
    t : ndarray of float, shape (K,)
        Tracking time [s].
    desired : ndarray of float, shape (K,)
        Desired displacement [m].
    traces : dict of str to ndarray
        Measured displacement [m] per controller (plain, then extended).
    results : dict
        The demo's results (``effect``, ``plant``, ``identification``, ``tracking``, ...).

    Returns
    -------
    list of Path
        The files written.

    """
    effect = results['effect']
    control = {r['controller']: r['control_error'] for r in results['tracking']}
    files = [out / 'tracking_error.png', out / 'report.md', out / 'results.json',
             out / 'tracking.npz']
    _tracking_figure(files[0], t, desired, traces, control,
                     f'Tracking error on the plant with {effect.replace("_", " ")}: plain '
                     'against extended compensator (the closer to 0, the better)',
                     zoom=False)
    strength = ', '.join(f'`{k}:={v:g}`' for k, v in results['plant'].items())
    late = max(v['max'] for v in results['lateness_s'].values())
    what = {'creep': 'creep (the displacement keeps drifting slowly after the current '
                     'stops changing)',
            'rate_dependence': 'rate dependence (an eddy-current lag: the displacement lags '
                               'the current, more at higher rates)'}.get(effect, effect)
    lines = ['# mpi_ros demo: extended compensator', '',
             f'The MPI model, its identification and the error measures are those of {PAPER}; '
             "the extension (creep or rate dependence) is this package's "
             '(`mpi_ros.extensions`).', '',
             f'**What ran.** The plant simulator with {what} ({strength}) and sensor noise was '
             f'driven in real time at {results["sample_rate"]:g} Hz and recorded '
             f'({results["samples"]} samples; the latest sample went out '
             f'{1e3 * late:.1f} ms behind schedule). Two models of order (14, 7) were fitted: '
             'the plain MPI model and the MPI model extended by the effect. Each was pushed '
             'into a fresh compensator in front of a fresh plant, tracking the same desired '
             f'trajectory. ROS_DOMAIN_ID {results["domain_id"]}; '
             f'{results["elapsed_s"]:.0f} s in all.', '',
             *_measures(_WHOLE), '',
             '| model | nonlinearity error (37), identification record | its largest error at |',
             '|---|---|---|']
    lines += [f"| {r['model']} | {100 * r['nonlinearity_error']:.2f} % "
              f"| {r['largest_error_at_s']:.2f} s |" for r in results['identification']]
    lines += ['', 'A largest error in the first second of the record means that the model '
              'starts in another state than the actuator did.']
    lines += ['', 'Fitted extension: ' + ', '.join(
        f'`{k}` = {np.round(np.asarray(v, dtype=float), 6).tolist()}'
        for k, v in results['extension'].items()), '',
        '| controller | control error (38) | RMS |', '|---|---|---|']
    lines += [f"| {r['controller']} | {100 * r['control_error']:.2f} % "
              f"| {100 * r['rms_error']:.2f} % |" for r in results['tracking']]
    lines += ['', '(RMS: the root-mean-square tracking error over the largest desired '
              'displacement, the divisor of (38); it counts the whole run, where (38) counts '
              'the worst sample.)', '',
              '![tracking error](tracking_error.png)', '',
              'Measured minus desired displacement over time for both compensators; the '
              'extended one should stay closer to 0.', '']
    _, report, summary, arrays_file = files
    _write_text(report, '\n'.join(lines))
    _write_text(summary, json.dumps(results, indent=2))
    _save_traces(arrays_file, t, desired, traces)
    return files


def _save_traces(path: Path, t: np.ndarray, desired: np.ndarray,
                 traces: dict[str, np.ndarray]) -> None:
    # time [s], desired [m] and measured_<k> [m] per controller, k in the report's order.
    arrays: dict[str, Any] = {'time': t, 'desired': desired,
                              **{f'measured_{k}': v for k, v in enumerate(traces.values())}}
    from ..recordings import atomic_write
    with atomic_write(path, binary=True) as handle:
        np.savez(handle, **arrays)


def _tracking_figure(path: Path, t: np.ndarray, desired: np.ndarray,
                     traces: dict[str, np.ndarray], control: dict[str, float], title: str, *,
                     zoom: bool = True) -> None:
    plt = _pyplot()
    compensated = [label for label in traces if not label.startswith('linear')]
    rows = 2 if zoom and len(compensated) < len(traces) else 1
    fig, axes = plt.subplots(rows, 1, figsize=(12.5, 3.4 * rows + 0.4), sharex=True,
                             squeeze=False)
    for row, labels in enumerate([list(traces), compensated][:rows]):
        ax = axes[row, 0]
        for i, label in enumerate(traces):
            if label in labels:
                ax.plot(t, _um(traces[label] - desired), lw=0.7, color=f'C{i}',
                        label=f'{label}: (38) {100 * control[label]:.2f} %')
        ax.axhline(0.0, color='k', lw=0.6)
        ax.set_ylabel('measured − desired [µm]')
        ax.legend(fontsize=8, loc='upper left', bbox_to_anchor=(1.01, 1.0))
        if row == 0:
            ax.set_title(title, fontsize=10.5)
        else:
            ax.set_title('The MPI compensators only (enlarged)', fontsize=10.5)
    axes[-1, 0].set_xlabel('time [s]')
    fig.tight_layout()
    _save_figure(fig, path)
    plt.close(fig)


def _write_text(path: Path, text: str) -> None:
    # Every output file atomically: the old file or the new one after a crash.
    from ..recordings import atomic_write
    with atomic_write(path) as handle:
        handle.write(text)


def _save_figure(fig: Any, path: Path) -> None:
    from ..recordings import atomic_write
    with atomic_write(path, binary=True) as handle:
        fig.savefig(handle, format='png', dpi=110)
