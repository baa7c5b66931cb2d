# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Report for people: a markdown summary and PNG plots of a :class:`DiagnosisReport`.

Plots (matplotlib, Agg backend): measured vs simulated loops (``loops.png``), the
residuals over time (``residual.png``) and one signature plot per candidate
(``signature_<cause>.png``): creep - residual during input holds; rate dependence -
residual against the input rate; thermal drift - residual against the lagged input power;
dead time - cross-correlation of measured and simulated output rate against lag.
"""

import json
import os
from pathlib import Path
from typing import Any


from .diagnose import DiagnosisReport
from ..extensions import EFFECTS
from ..params import write_params_yaml

__all__ = ['write_report', 'write_json', 'write_extended_params']


def write_json(report: DiagnosisReport, path: str | os.PathLike[str]) -> None:
    """Write ``report.to_json()`` to ``path`` (UTF-8, indented)."""
    Path(path).write_text(json.dumps(report.to_json(), indent=2) + '\n', encoding='utf-8')


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


def write_report(report: DiagnosisReport, directory: str | os.PathLike[str]) -> list[Path]:
    """
    Write ``summary.md`` and the PNG plots into ``directory`` (created if missing).

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
    t, x, y, k0 = s['time'], s['current'], s['displacement'], s['start']
    val = slice(k0, None)
    sims = {'baseline MPI': s.get('baseline')}
    if report.cause in s.get('candidates', {}):
        sims[f'extended ({report.cause})'] = s['candidates'][report.cause]

    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(x[val], y[val], lw=0.8, color='k', label='measured')
    for (name, sim), color in zip(sims.items(), ('tab:blue', 'tab:red')):
        if sim is not None:
            ax.plot(x[val], sim[val], lw=0.8, color=color, label=name)
    ax.set_xlabel('input (current) [A]')
    ax.set_ylabel('output (displacement) [m]')
    ax.set_title('validation data: measured vs simulated')
    ax.legend(fontsize=8)
    written.append(_save(fig, out / 'loops.png', plt))

    if sims['baseline MPI'] is not None:
        fig, ax = plt.subplots(figsize=(8, 3.5))
        for (name, sim), color in zip(sims.items(), ('tab:blue', 'tab:red')):
            ax.plot(t[val], (y - sim)[val], lw=0.6, color=color, label=name)
        ax.set_xlabel('time [s]')
        ax.set_ylabel('measured - simulated [m]')
        ax.set_title('validation residual over time')
        ax.legend(fontsize=8)
        written.append(_save(fig, out / 'residual.png', plt))
        for cause, sim in s.get('candidates', {}).items():
            plot = _signature(cause, t, x, y, sims['baseline MPI'], sim, k0,
                              out / f'signature_{cause}.png', plt)
            if plot is not None:
                written.append(plot)
    summary = out / 'summary.md'
    summary.write_text(_markdown(report, [p.name for p in written]), encoding='utf-8')
    written.append(summary)
    return written


def _save(fig: Any, path: Path, plt: Any) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _signature(cause: str, t: Any, x: Any, y: Any, base: Any, sim: Any, k0: int,
               path: Path, plt: Any) -> Path | None:
    # Each effect draws its own signature plot (mpi_ros.extensions.effect.Effect.plot).
    effect = EFFECTS.get(cause)
    if effect is None or effect.plot is None:
        return None
    fig, ax = plt.subplots(figsize=(6, 4))
    effect.plot(ax, t, x, y, base, sim, k0)
    ax.legend(fontsize=8, markerscale=6)
    return _save(fig, path, plt)


def _markdown(report: DiagnosisReport, images: list[str]) -> str:
    j = report.to_json()
    lines = ['# mpi_ros diagnosis', '', f'**Verdict: `{report.cause}`**', '',
             report.evidence, '']
    lines += [f'**Warning:** {warning}\n' for warning in report.warnings]
    if report.baseline:
        b, e = report.baseline, report.extended
        lines += ['| model | validation RMS error | (37) nonlinearity error | gain |',
                  '|---|---|---|---|',
                  f'| baseline MPI, order {tuple(b["order"])} | {100 * b["rms_error"]:.3f} % |'
                  f' {100 * b["nonlinearity_error"]:.3f} % | - |']
        for c in report.candidates:
            mark = ' **(chosen)**' if c['cause'] == report.cause else ''
            lines.append(f'| {c["cause"]}{mark} | {100 * c["rms_error"]:.3f} % |'
                         f' {100 * c["nonlinearity_error"]:.3f} % | {100 * c["gain"]:+.1f} %'
                         f' (z {c["z"]:.1f}) |')
        lines += ['', f'Extended model validation RMS error: {100 * e["rms_error"]:.3f} %.', '',
                  '## Decision', '']
        lines += [f'- {step}' for step in report.decision.get('steps', [])]
        lines += ['', '## Residual structure (baseline, validation data)', '', '```',
                  json.dumps(j['residual'], indent=1), '```', '']
    lines += ['## Data', '', '```', json.dumps(j['data'], indent=1), '```', '',
              '## Plots', '']
    lines += [f'![{name}]({name})' for name in images]
    return '\n'.join(lines) + '\n'
