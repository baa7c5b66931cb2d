# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Report for people: a markdown summary and PNG plots of a :class:`DiagnosisReport`.

**One set of facts feeds everything.**  The JSON (``report.to_json()``), the summary lines
the command line prints, ``summary.md``, the plot titles and the captions are all written
from the report's typed fields (:mod:`mpi_ros.diagnosis.facts`: the JSON is their form, a
field's name its key); the prose only rounds their numbers (3 significant digits) and
never computes a number of its own.  Errors are
percentages of the output's range, gains percentages of the baseline's error, lengths and
times carry their units.  The units are the data's (``data['units']``: input ``A`` or
``V``, output ``m``, ``µm``, ``nm``, ...; see :func:`data_units`), A and m (SI, REP 103)
when nothing says otherwise.

Plots (matplotlib, Agg backend), each titled with what to look at: measured vs simulated
loops (``loops.png``), the residuals over time (``residual.png``) and one signature plot
per candidate (``signature_<cause>.png``, drawn by the effect's ``plot``, captioned by its
``caption``: :class:`mpi_ros.extensions.Effect`).  Each PNG carries its title, axis labels
and legend as its ``Title`` and ``Description`` text, so a check reads them back.
"""

import inspect
import json
import math
import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from scipy.stats import norm

from .diagnose import DiagnosisReport, z_wording
from .facts import Baseline, Decision, Residual, Reversals, ScoredCandidate
from .notation import length, LENGTH_PREFIXES, percent, signed_percent, significant
from ..extensions import EFFECTS
from ..extensions.effect import effect_caption, separating_measurement
from ..extensions.fitting import AxisUnits
from ..params import write_params_yaml
from ..recordings.files import atomic_write
from ..units import INPUT_UNITS, OUTPUT_UNITS, resolve_units

__all__ = ['report_facts', 'write_report', 'write_json', 'write_extended_params', 'summary_lines',
           'markdown', 'data_units', 'significant', 'z_wording', 'INPUT_UNITS',
           'OUTPUT_UNITS']


def write_json(report: DiagnosisReport | Mapping[str, Any],
               path: str | os.PathLike[str]) -> None:
    """
    Write the report's dictionary (``report.to_json()``) to ``path`` (UTF-8, indented).

    Written atomically (:func:`mpi_ros.recordings.atomic_write`): ``path`` holds the old
    file or the new one, never a part.

    """
    facts = report_facts(report) if isinstance(report, DiagnosisReport) else report
    text = json.dumps(facts, indent=2) + '\n'
    with atomic_write(path) as handle:
        handle.write(text)


def report_facts(report: DiagnosisReport) -> dict[str, Any]:
    """
    Return the one dictionary the JSON, the summary lines and ``summary.md`` are written from.

    ``report.to_json()`` with the data's units (``data['units']``, see :func:`data_units`;
    A and m when the report does not name them).

    """
    facts = report.to_json()
    facts['data'].setdefault('units', data_units())
    return facts


def write_extended_params(report: DiagnosisReport, path: str | os.PathLike[str], *,
                          node_name: str = 'compensator') -> None:
    """
    Write the extended model as a ROS 2 parameter file the compensator accepts.

    Parameters
    ----------
    report : DiagnosisReport
        A report with a fitted model (not ``outside_invertible_class``).
    path : str or PathLike
        Target YAML file.
    node_name : str
        Node the parameters are keyed by.

    """
    header = (f'mpi_ros diagnose: cause {report.cause}, validation gain {report.gain:.3f}\n'
              f'{report.evidence}')
    write_params_yaml(path, report.parameters(), node_name=node_name, header=header)


def data_units(input_name: str = '', output_name: str = '', *, input_scale: float = 1.0,
               output_scale: float = 1.0, input_unit: str | None = None,
               output_unit: str | None = None) -> dict[str, str]:
    """
    Name the units of the data as read: SI, the input in A or V (:mod:`mpi_ros.units`).

    The readers convert every recording to SI by the one rule of :mod:`mpi_ros.units` (unit
    suffixes of the names, the scales, ``--input-unit`` / ``--output-unit``), so the data
    the report describes are in s, A or V, and m; the input's name or stated unit tells
    whether it is a current or a voltage.

    Parameters
    ----------
    input_name, output_name : str
        Names of the input and output signals ('' when unknown).
    input_scale, output_scale : float
        The reader's factors (``--input-scale``, ``--output-scale``).
    input_unit, output_unit : str, optional
        The units stated by the user (keys of :data:`INPUT_UNITS`, :data:`OUTPUT_UNITS`).

    Returns
    -------
    dict
        ``time`` (``'s'``), ``input`` (``'A'`` or ``'V'``), ``output`` (``'m'``) and
        ``from`` (how they were found, one phrase).

    Examples
    --------
    >>> u = data_units('volts', 'nm', output_scale=1e-9)
    >>> u['input'], u['output']
    ('V', 'm')
    >>> data_units('current', 'displacement_um')['output']
    'm'

    """
    units = resolve_units('', input_name, output_name, input_scale=input_scale,
                          output_scale=output_scale, input_unit=input_unit,
                          output_unit=output_unit)
    found = units.found or 'input: A, output: m (SI)'
    return {'time': 's', 'input': units.si_input, 'output': 'm',
            'from': f'{found}; read as s, {units.si_input}, m'}


def summary_lines(report: DiagnosisReport) -> list[str]:
    """
    Return the short summary (printed on stderr, and the head of ``summary.md``).

    Parameters
    ----------
    report : DiagnosisReport
        The diagnosis; every statement is written from its typed fields (the JSON holds
        the same fields).

    Returns
    -------
    list of str
        One statement per line: verdict, gains, ties, scored part, holds, units.

    """
    units = _units(report)
    decision = _decision(report)
    label = _verdict_label(report)
    lines = [f'verdict: {report.cause} ({label})'
             + (f', validation gain {percent(report.gain)}' if report.gain else '')]
    reason = decision.weak_reason if decision is not None else None
    if reason and 'weak' in label:
        lines.append(f'weak: {reason}')
    zc = decision.z_critical if decision is not None else 1.645
    if report.baseline is not None:
        lines.append('gains on the validation data (Diebold-Mariano z against the baseline): '
                     + ', '.join(f'{c.cause} {signed_percent(c.gain)} (z'
                                 f' {significant(c.z)}, {z_wording(c.z, zc)})'
                                 for c in _ranked(report)))
    chosen = _chosen(report)
    if chosen is not None and chosen.parts and chosen.part_gains and chosen.part_z:
        gains, z = chosen.part_gains, chosen.part_z
        lines.append('each effect beyond the other alone (the pair against the other effect'
                     ' alone): ' + ', '.join(
                         f'{name} {signed_percent(gains[name])} (z {significant(z[name])},'
                         f' {z_wording(z[name], zc)})' for name in chosen.parts))
    if decision is not None and decision.ambiguous:
        lines.append(f'ambiguous: {_tie_reasons(report)}; separate them with'
                     ' mpi-ros diagnose --excitation (see summary.md)')
    finding = report.data.dynamics_finding
    text = finding.describe() if finding is not None else ''
    if text:
        lines.append(text)
    lines.append(f'scored part: {_scored(report)}')
    lines.append(f'holds: {_holds(report)}')
    lines.append(f'units: input {units["input"]}, output {units["output"]},'
                 f' time s ({units["from"]})')
    return lines


def markdown(report: DiagnosisReport, images: Sequence[str] = ()) -> str:
    """
    Return ``summary.md`` for the report.

    Parameters
    ----------
    report : DiagnosisReport
        The diagnosis; the prose is written from its typed fields.
    images : sequence of str
        File names of the plots, in the report folder.

    Returns
    -------
    str
        Markdown; every number rounded to 3 significant digits (counts exactly).

    """
    units = _units(report)
    decision = _decision(report)
    lines = ['# mpi_ros diagnosis', '',
             f'**Verdict: {report.cause}** ({_verdict_label(report)})', '']
    lines += [f'- {line[0].upper()}{line[1:]}' for line in summary_lines(report)]
    lines.append('')
    lines += [f'**Warning:** {warning}\n' for warning in report.warnings]
    residual = report.residual
    if report.baseline is None or decision is None or not isinstance(residual, Residual):
        lines += ['## Why no model was fitted', '', report.evidence, '']
    else:
        lines += _candidate_section(report, report.baseline, decision, units)
        if decision.ambiguous:
            lines += _tie_section(report, decision)
        lines += _evidence_section(residual, decision, units)
    lines += _data_section(report, units)
    if images:
        fitted = report.baseline is not None
        lines += ['## Plots', '']
        for name in images:
            lines += [f'![{name}]({name})', '', f'*{_caption(name, fitted)}*', '']
    return '\n'.join(lines).rstrip('\n') + '\n'


def write_report(report: DiagnosisReport, directory: str | os.PathLike[str]) -> list[Path]:
    """
    Write ``summary.md`` and the PNG plots into ``directory`` (created if missing).

    Each file is written atomically (:func:`mpi_ros.recordings.atomic_write`), the plots
    first and ``summary.md``, which lists them, last. A crash leaves every file old or
    new; ``mpi-ros diagnose`` writes its ``--json`` after this folder.

    Parameters
    ----------
    report : DiagnosisReport
        The diagnosis.
    directory : str or PathLike
        Output directory.

    Returns
    -------
    list of Path
        The files written.

    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    s = report.series
    written = []
    t, x, y, k0 = s.time, s.current, s.displacement, s.start
    axes = _axis_units(_units(report), y[k0:])
    val = slice(k0, None)
    sims = {} if s.baseline is None else {'baseline MPI': s.baseline}
    if report.cause in s.candidates:
        sims[f'extended ({report.cause})'] = s.candidates[report.cause]
    out_label = f'output [{axes.displacement}]'

    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    ax.plot(x[val], axes.scale * y[val], lw=0.8, color='k', label='measured')
    for (name, sim), color in zip(sims.items(), ('tab:blue', 'tab:red')):
        ax.plot(x[val], axes.scale * sim[val], lw=0.8, color=color, label=name)
    ax.set_xlabel(f'input [{axes.current}]')
    ax.set_ylabel(out_label)
    ax.set_title('validation loops: where the baseline (blue) leaves the measured loop\n'
                 '(black), the extended model (red) should follow it' if len(sims) > 1 else
                 'validation loops: the baseline MPI (blue) should lie on the measured\n'
                 'loop (black); no extension was chosen' if sims else
                 'the measured loops (black): outside the invertible class,\nno model was'
                 ' fitted', fontsize=10)
    ax.legend(fontsize=8)
    written.append(_save(fig, out / 'loops.png', plt))

    if s.baseline is not None:
        fig, ax = plt.subplots(figsize=(8, 3.8))
        for (name, sim), color in zip(sims.items(), ('tab:blue', 'tab:red')):
            ax.plot(t[val], axes.scale * (y - sim)[val], lw=0.6, color=color, label=name)
        ax.set_xlabel('time [s]')
        ax.set_ylabel(f'measured - simulated [{axes.displacement}]')
        ax.set_title('validation residual: the extended model (red) should be smaller than the'
                     ' baseline (blue)\nand lose its structure (drift in holds, spikes at fast'
                     ' moves)' if len(sims) > 1 else 'validation residual of the baseline MPI:'
                     ' no extension was chosen;\nwhat is left should look like noise, without'
                     ' drift in holds or spikes at fast moves', fontsize=10)
        ax.legend(fontsize=8)
        written.append(_save(fig, out / 'residual.png', plt))
        parameters = {c.cause: c.parameters for c in report.candidates}
        for cause, sim in s.candidates.items():
            plot = _signature(cause, t, x, y, s.baseline, sim, k0,
                              out / f'signature_{cause}.png', plt, axes,
                              parameters.get(cause, {}))
            if plot is not None:
                written.append(plot)
    summary = out / 'summary.md'
    with atomic_write(summary) as handle:
        handle.write(markdown(report, [p.name for p in written]))
    written.append(summary)
    return written


def _save(fig: Any, path: Path, plt: Any) -> Path:
    # The PNG carries what its text says (title, axis labels, legend) as its Title and
    # Description, so the report's check can read a plot's words back beside the JSON.
    ax = fig.axes[0]
    legend = ax.get_legend()
    labels = [t.get_text() for t in legend.get_texts()] if legend is not None else []
    metadata = {'Title': ax.get_title(),
                'Description': '\n'.join([f'x: {ax.get_xlabel()}', f'y: {ax.get_ylabel()}',
                                          *(f'legend: {label}' for label in labels)])}
    fig.tight_layout()
    try:
        with atomic_write(path, binary=True) as handle:
            fig.savefig(handle, format='png', dpi=110, metadata=metadata)
    finally:
        plt.close(fig)
    return path


def _signature(cause: str, t: Any, x: Any, y: Any, base: Any, sim: Any, k0: int,
               path: Path, plt: Any, axes: AxisUnits,
               parameters: Mapping[str, Any]) -> Path | None:
    # Each effect draws its own signature plot (mpi_ros.extensions.effect.Effect.plot);
    # the built-in ones take the units and the fitted parameters as keywords.
    effect = EFFECTS.get(cause)
    if effect is None or effect.plot is None:
        return None
    accepted = inspect.signature(effect.plot).parameters
    extra = {k: v for k, v in (('units', axes), ('parameters', parameters))
             if k in accepted}
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    effect.plot(ax, t, x, y, base, sim, k0, **extra)
    ax.legend(fontsize=8, markerscale=3)
    return _save(fig, path, plt)


def _caption(name: str, fitted: bool = True) -> str:
    # The two plots of every report, and each effect's signature plot as its module says.
    captions = {
        'loops.png': ('Measured and simulated output against the input, validation data.'
                      if fitted else 'Measured output against the input; no model fitted.'),
        'residual.png': 'Measured minus simulated output over time, validation data.'}
    if name in captions:
        return captions[name]
    return effect_caption(name.removeprefix('signature_').removesuffix('.png'))


def _units(report: DiagnosisReport) -> dict[str, str]:
    units = report.data.units
    return dict(units) if units else data_units()


def _decision(report: DiagnosisReport) -> Decision | None:
    # The decision of a fitted record (None: outside the invertible class, a refusal).
    return report.decision if isinstance(report.decision, Decision) else None


def _chosen(report: DiagnosisReport) -> ScoredCandidate | None:
    return next((c for c in report.candidates if c.cause == report.cause), None)


def _axis_units(units: Mapping[str, str], y: Any) -> AxisUnits:
    # Metres are drawn with the prefix that suits the output's range; a named unit as it is.
    if units['output'] != 'm':
        return AxisUnits(current=units['input'], displacement=units['output'])
    span = float(np.ptp(y)) if len(y) else 0.0
    factor, prefix = next(((f, p) for f, p in LENGTH_PREFIXES if span >= f), LENGTH_PREFIXES[-1])
    return AxisUnits(current=units['input'], displacement=prefix, scale=1.0 / factor)


def _seconds(value: Any) -> str:
    v = float(value)
    return f'{significant(1e3 * v)} ms' if abs(v) < 1.0 else f'{significant(v)} s'


def _verdict_label(report: DiagnosisReport) -> str:
    # The strength the diagnosis states (e.g. 'present, weak'), else by the cause.
    decision = _decision(report)
    if decision is not None and decision.strength == 'present, weak':
        return 'present, weak'
    if report.cause == 'none':
        return 'no effect found'
    if report.cause == 'outside_invertible_class':
        return 'outside the invertible class: no model fitted'
    if decision is not None and decision.ambiguous:
        return f'present, ambiguous: tied with {" and ".join(decision.tied_with)}'
    return 'present'


def _ranked(report: DiagnosisReport) -> list[ScoredCandidate]:
    return sorted(report.candidates, key=lambda c: -c.gain)


def _tie_reasons(report: DiagnosisReport) -> str:
    # Each tied cause with the reason the diagnosis gave (the validation data's z, or the
    # analysis of the record that identify states), in one sentence.
    decision = _decision(report)
    if decision is None:
        return ''
    reasons = decision.tie_reasons
    return '; '.join(f'{cause} is tied with {report.cause}'
                     + (f': {reasons[cause]}' if reasons.get(cause) else '')
                     for cause in decision.tied_with)


def _scored(report: DiagnosisReport) -> str:
    data = report.data
    scored = data.validation_scored
    if scored is not None:
        first, samples, left = scored.from_sample, scored.samples, scored.left_out
    elif data.training_samples is not None:                   # a split record
        first, samples = data.training_samples, data.samples - data.training_samples
        left = 'the training part'
    else:
        return 'the whole validation record'
    where = ('validation record' if data.validation_samples is not None
             else 'record (after the training part)')
    return (f'{where} from sample {first}, {samples} samples'
            + (f' (left out before it: {left})' if left and left != 'nothing' else ''))


def _holds(report: DiagnosisReport) -> str:
    return _holds_of(report.residual)


def _holds_of(residual: Residual | Reversals) -> str:
    if not isinstance(residual, Residual):
        return 'not counted (no model fitted)'
    holds = residual.holds
    shortest = holds.minimum_duration
    text = (f'{holds.count} input hold(s)'
            + (f' of {significant(shortest)} s or more' if shortest else '')
            + ' in the scored part')
    used = residual.hold_signature
    need = holds.signature_minimum_duration
    longer = f' ({significant(need)} s or more)' if need else ''
    if used is None:
        return (f'{text}; none long enough{longer} for the hold signature test (creep,'
                ' thermal drift): that signature is unavailable')
    return f'{text}; {used.holds} used by the hold signature test{longer}'


def _parameters(candidate: ScoredCandidate) -> str:
    # The fitted values with their units (a non-finite value, null in the JSON, is left out).
    parts = []
    for p in candidate.fitted():
        if isinstance(p.value, tuple):
            if not p.value:
                continue
            parts.append(f'{p.name} {_with_unit(min(p.value), p.unit)} to'
                         f' {_with_unit(max(p.value), p.unit)} ({len(p.value)} values)')
        elif math.isfinite(p.value):
            parts.append(f'{p.name} {_with_unit(p.value, p.unit)}')
    return '; '.join(parts) or '-'


def _with_unit(value: float, unit: str) -> str:
    # A time in ms or s, any other unit after the number, none for a dimensionless value.
    if unit == 's':
        return _seconds(value)
    return f'{significant(value)} {unit}' if unit else significant(value)


def _candidate_section(report: DiagnosisReport, b: Baseline, decision: Decision,
                       units: Mapping[str, str]) -> list[str]:
    zc = decision.z_critical
    level = float(norm.sf(zc))
    lines = ['## Models on the validation data', '',
             'Errors are RMS over the validation output range; the gain is the relative cut'
             ' of the baseline RMS error; z is the Diebold-Mariano statistic of the squared'
             f' errors against the baseline, tested one-sided at {percent(level)}: z >='
             f' {significant(zc, 4)} is significantly better, z <= -{significant(zc, 4)}'
             ' significantly worse.', '',
             '| rank | model | RMS error | (37) nonlinearity error | gain | z | test |'
             ' signature | fitted parameters |',
             '|---|---|---|---|---|---|---|---|---|',
             f'| - | baseline MPI, order {b.order[0]}, {b.order[1]} |'
             f' {percent(b.rms_error)} | {percent(b.nonlinearity_error)} | - | - | - |'
             ' - | - |']
    for rank, c in enumerate(_ranked(report), 1):
        mark = ' (chosen)' if c.cause == report.cause else ''
        lines.append(f'| {rank} | {c.cause}{mark} | {percent(c.rms_error)} |'
                     f' {percent(c.nonlinearity_error)} | {signed_percent(c.gain)} |'
                     f' {significant(c.z)} | {z_wording(c.z, zc)} |'
                     f' {c.signature} | {_parameters(c)}'
                     + ''.join(f'; {k} not identified (at a search bound)'
                               for k in c.not_identified) + ' |')
    lines += ['', f'Straight line fitted on the training data: {percent(b.linear_rms_error)}'
              f' RMS error on the validation data.']
    above = 'exceeds' if decision.baseline_above_noise else 'does not exceed'
    lines += ['', f'Rule: a candidate counts when its gain is at least'
              f' {percent(decision.min_gain)}, its z test says significantly better and its'
              ' physical signature is present (or unavailable in this record); the'
              ' largest gain among those wins.  The baseline residual'
              f' {above} {significant(decision.noise_factor)} times the noise'
              f' floor ({length(decision.noise_floor, units["output"])}).']
    return lines + ['']


def _tie_section(report: DiagnosisReport, decision: Decision) -> list[str]:
    tied = [report.cause, *decision.tied_with]
    lines = ['## Ambiguous: the record cannot tell these causes apart', '',
             f'{_tie_reasons(report)}. Ranked by gain:', '']
    rank = 0
    for row in decision.ranking:
        if row.cause not in tied:
            continue
        rank += 1
        against = ('chosen' if row.cause == report.cause else
                   f'z {significant(row.z_against_chosen)} against {report.cause}')
        lines.append(f'{rank}. {row.cause}: gain {signed_percent(row.gain)}'
                     f' ({against}; signature {row.signature})')
    lines += ['', 'To separate them, run `mpi-ros diagnose --excitation validation_input.csv`,'
              ' play that input on the rig, record the answer and diagnose again with'
              ' `--validate` the new record.  The excitation holds the input after steps up'
              f' and down and drives bursts at 5-40 Hz: {separating_measurement(tied)}.', '']
    return lines


def _evidence_section(residual: Residual, decision: Decision,
                      units: Mapping[str, str]) -> list[str]:
    out = units['output']
    lines = ['## Physical evidence (baseline residual, validation data)', '',
             f'- Baseline residual RMS {length(residual.rms, out)}; noise floor'
             f' {length(residual.noise_floor, out)}'
             f' ({percent(residual.noise_floor_relative)} of the output range).',
             f'- Holds: {_holds_of(residual)}.']
    holds = residual.hold_signature
    if holds is not None:
        lines.append(f'- During {holds.holds} hold(s) the residual has a log(t) component'
                     f' of {length(holds.log_amplitude, out)} RMS'
                     f' (p = {significant(holds.log_p)}) and a smooth drift of'
                     f' {length(holds.drift_amplitude, out)} RMS'
                     f' (p = {significant(holds.drift_p)}).')
    bursts = residual.burst_signature
    if bursts is None:
        lines.append('- Bursts: none the burst signature test can use (no burst signature'
                     ' for rate dependence and dead time).')
    else:
        f = bursts.frequencies
        lines.append(f'- Bursts at {len(f)} frequencies, {significant(f[0])} to'
                     f' {significant(f[-1])} Hz: the phase of measured/simulated follows the'
                     f' {bursts.law} law (delay L = {_seconds(bursts.delay)}, residual'
                     f' {significant(bursts.delay_sse)}; lag tau ='
                     f' {_seconds(bursts.lag_time_constant)}, residual'
                     f' {significant(bursts.lag_sse)}; p = {significant(bursts.p)}).')
    onset = residual.step_onset
    if onset is not None:
        check = onset.dead_time_check or 'a dead time up to it is physical'
        lines.append(f'- Step response: the output moves within {_seconds(onset.bound)}'
                     f' of a step ({onset.steps} step(s) measured); {check}.')
    lines.append(f'- Each signature test runs at p < {significant(decision.signature_level)}.')
    return lines + ['']


def _data_section(report: DiagnosisReport, units: Mapping[str, str]) -> list[str]:
    data = report.data
    lines = ['## Data', '',
             f'- Training: `{data.source}`, {data.samples} samples'
             + (f', the first {percent(data.split)} of the record' if data.split is not None
                else '')
             + (f' after its leading hold of {data.leading_hold} samples'
                if data.leading_hold else '') + '.']
    if data.validation_samples is not None:
        lines.append(f'- Validation: `{data.validation}`,'
                     f' {data.validation_samples} samples (a separate record).')
    lines.append(f'- Scored: {_scored(report)}.')
    scored = data.validation_scored
    if scored is not None and scored.start_state:
        lines.append(f'- Start state of the scored part: {scored.start_state}.')
    if data.output_offset_reestimated:
        shift = (report.baseline.validation_output_offset if report.baseline is not None
                 else None)
        lines.append('- The validation record has its own sensor zero: only its output offset'
                     ' is re-estimated, for every model alike (baseline:'
                     f' {length(shift, units["output"])}).')
    if data.output_sign is not None:
        lines.append(f'- Output sign: {data.output_sign:+d}'
                     + (' (a falling sensor)' if data.output_sign < 0 else '') + '.')
    lines.append(f'- Units: input {units["input"]}, output {units["output"]}, time s'
                 f' ({units["from"]}).')
    return lines + ['']
