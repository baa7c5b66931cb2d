# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mpi-ros diagnose``: summary.md, the stderr summary and the plots say what the JSON says.

Each record goes through the command line as a user runs it; summary.md is parsed back and
every sentence that states a fact is checked against report.json: the verdict and its
label (clear, weak, ambiguous), the holds count and the holds the signature test used, the
bursts, the scored part, every model's errors, gain, z and the z test's wording (table,
summary line, decision steps, evidence), who decided (the signature or the gain alone), the
fitted parameters (table, evidence, plot titles and legends, read back from each PNG's
text), the captions (each effect's own, from the registry) and the units.  No line of
summary.md may look like JSON or carry more than 4 significant digits, and every error or
gain printed on stderr is a percentage.  The records: synthetic plants of every effect
(mpi_ros.plant) and the measured records of ``../shared/data/measured`` when present.
"""

import json
import math
from pathlib import Path
import re

from mpi_ros.app.cli import main
from mpi_ros.diagnosis.report import data_units, markdown, summary_lines, z_wording
from mpi_ros.extensions import EFFECTS
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import diagnostic_excitation, identification_excitation
from mpi_ros.recordings import write_csv_columns
import numpy as np
from PIL import Image
import pytest

NOISE = 2e-8                       # [m] sensor noise, 0.05 % of the stroke
MEASURED = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'measured'
# Rounding to 3 significant digits moves a number by at most half a unit of the third digit.
ROUNDING = 5e-3


def _record(path, config, *, seconds=20.0, seed=1, **excitation):
    t, x = identification_excitation(seconds, sample_rate=1000.0, seed=seed, **excitation)
    y = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=NOISE, **config),
                                 seed=seed).simulate(t, x)
    write_csv_columns(path, {'time': t, 'current': x, 'displacement': y})


def _diagnose(tmp_path, capsys, data, *extra, order=('8', '4')):
    argv = ['diagnose', str(data), '--order', *order, '--json', str(tmp_path / 'r.json'),
            '--report', str(tmp_path / 'report'), *extra]
    assert main(argv) == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    facts = json.loads((tmp_path / 'r.json').read_text(encoding='utf-8'))
    summary = (tmp_path / 'report' / 'summary.md').read_text(encoding='utf-8')
    _check_plots(facts, summary, tmp_path / 'report')
    return facts, summary, err


def _close(text, value):
    """Whether a number printed with 3 significant digits is ``value`` rounded."""
    return math.isclose(float(text), value, rel_tol=ROUNDING, abs_tol=1e-12)


def _check_agreement(facts, summary, err):
    lines = summary.splitlines()
    # Verdict.
    verdict = re.fullmatch(r'\*\*Verdict: (.+?)\*\* \((.+)\)', lines[2])
    assert verdict is not None, lines[:4]
    assert verdict.group(1) == facts['cause']
    assert verdict.group(2).startswith('no effect found' if facts['cause'] == 'none'
                                       else 'present')
    # Holds: the count of the JSON, and the holds the signature test used.
    residual = facts['residual']
    holds = re.search(r'Holds: (\d+) input hold\(s\)', summary)
    assert holds is not None and int(holds.group(1)) == residual['holds']['count']
    if residual['hold_signature'] is None:
        assert 'none long enough' in summary
    else:
        used = re.search(r'; (\d+) used by the hold signature test', summary)
        assert int(used.group(1)) == residual['hold_signature']['holds']
        assert 'none long enough' not in summary
    assert 'no holds' not in summary and 'no holds' not in facts['evidence']
    # Scored part.
    scored = re.search(r'from sample (\d+), (\d+) samples', summary)
    assert scored is not None
    assert int(scored.group(1)) == facts['data']['validation_scored']['from_sample']
    assert int(scored.group(2)) == facts['data']['validation_scored']['samples']
    # Every candidate's gain, errors and z, and the z test's wording.
    zc = facts['decision']['z_critical']
    rows = {}
    for line in lines:
        row = re.fullmatch(r'\| (\d+) \| (\S+)( \(chosen\))? \| (\S+) % \| (\S+) % \|'
                           r' (\S+) % \| (\S+) \| ([a-z ]+) \| .*', line)
        if row:
            rows[row.group(2)] = row
    assert sorted(rows) == sorted(c['cause'] for c in facts['candidates'])
    for c in facts['candidates']:
        row = rows[c['cause']]
        assert _close(row.group(4), 100 * c['rms_error'])
        assert _close(row.group(5), 100 * c['nonlinearity_error'])
        assert _close(row.group(6), 100 * c['gain'])
        assert _close(row.group(7), c['z'])
        wording = ('significantly better' if c['z'] >= zc else
                   'significantly worse' if c['z'] <= -zc else 'not significant')
        assert row.group(8) == wording
        assert bool(row.group(3)) == (c['cause'] == facts['cause'])
    ranks = [int(rows[c['cause']].group(1)) for c in
             sorted(facts['candidates'], key=lambda c: -c['gain'])]
    assert ranks == list(range(1, len(ranks) + 1))
    # Units.
    units = re.search(r'Units: input (\S+), output (\S+), time s', summary)
    assert (units.group(1), units.group(2)) == (facts['data']['units']['input'],
                                                facts['data']['units']['output'])
    # Ties.
    if facts['decision']['ambiguous']:
        tied = [facts['cause'], *facts['decision']['tied_with']]
        section = summary.split('## Ambiguous', 1)[1].split('\n## ', 1)[0]
        for row in facts['decision']['ranking']:
            if row['cause'] in tied:
                gain = re.search(rf'\d+\. {row["cause"]}: gain (\S+) %', section)
                assert gain is not None and _close(gain.group(1), 100 * row['gain'])
        assert '`mpi-ros diagnose --excitation' in section
    else:
        assert '## Ambiguous' not in summary
    # The decision steps word each z as the table does and say whether it counts (never
    # "not significant" beside a table's "significantly better").
    steps = facts['decision'].get('steps', [])
    for c in facts['candidates']:
        for step in (s for s in steps if s.startswith(f'{c["cause"]}: gain ')):
            assert f'({z_wording(c["z"], zc)})' in step, (step, c['z'])
            assert (', counts;' in step) == c['significant'], step
    # What decided, worded from the chosen candidate's signature, everywhere.
    chosen = next((c for c in facts['candidates'] if c['cause'] == facts['cause']), None)
    said = ' '.join([facts['evidence'], *steps])
    if chosen is not None and chosen['signature'] == 'unavailable':
        assert 'the signature decided' not in said
    elif chosen is not None:
        assert 'decided on the gain alone' not in said
    # The holds the evidence speaks of are the holds the signature test used.
    if residual['hold_signature'] is not None:
        assert 'no hold of' not in facts['evidence']
    # stdout/stderr state errors and gains in percent of the range, never as fractions.
    for line in err.splitlines():
        for number in re.finditer(r'(?:RMS error|gain) ([-+]?\d[\d.]*(?:e[-+]?\d+)?)( %)?',
                                  line):
            assert number.group(2), line
    # The stderr summary is the summary's head, line by line.
    for line in summary_lines(facts):
        assert line in err.splitlines()
        assert f'- {line[0].upper()}{line[1:]}' in lines
    _check_prose(summary)
    _check_sentences(facts, summary, err)


#: Sentences checked against the JSON, by kind (counted over the whole module's records).
CHECKED = {}


def _count(kind, n=1):
    CHECKED[kind] = CHECKED.get(kind, 0) + n


def _check_sentences(facts, summary, err):
    """Check the sentences beyond the table: label, summary gains, evidence, baseline."""
    decision, residual = facts['decision'], facts['residual']
    zc = decision['z_critical']
    chosen = next((c for c in facts['candidates'] if c['cause'] == facts['cause']), None)
    by_cause = {c['cause']: c for c in facts['candidates']}
    # The label: ambiguous, weak or clear as the decision says.
    label = re.search(r'\*\*Verdict: .+?\*\* \((.+)\)', summary).group(1)
    assert label.startswith('present, ambiguous') == (
        decision['ambiguous'] and decision.get('strength') != 'present, weak'), label
    assert (label == 'present, weak') == (decision.get('strength') == 'present, weak'), label
    _count('verdict label')
    # The summary line of gains: every candidate's gain, z and wording.
    line = next(x for x in summary.splitlines() if x.startswith('- Gains on the validation'))
    said = re.findall(r'(\S+) ([-+]\S+) % \(z (\S+), ([a-z ]+)\)', line.split(': ', 1)[1])
    assert sorted(c for c, *_ in said) == sorted(by_cause)
    for cause, gain, z, wording in said:
        c = by_cause[cause]
        assert _close(gain, 100 * c['gain']) and _close(z, c['z'])
        assert wording == z_wording(c['z'], zc)
        _count('gain and significance (summary line)')
    # The baseline's row and the straight line.
    base = facts['baseline']
    row = re.search(r'\| - \| baseline MPI, order (\d+), (\d+) \| (\S+) % \| (\S+) % \|', summary)
    assert [int(row.group(1)), int(row.group(2))] == base['order']
    assert _close(row.group(3), 100 * base['rms_error'])
    assert _close(row.group(4), 100 * base['nonlinearity_error'])
    line = re.search(r'Straight line fitted on the training data: (\S+) % RMS', summary)
    assert _close(line.group(1), 100 * base['linear_rms_error'])
    _count('baseline errors', 2)
    # Each candidate's fitted scalar parameters, as the table states them.
    units = {p.key: p.unit for e in EFFECTS.values() for p in e.parameters}
    for c in facts['candidates']:
        row = next(x for x in summary.splitlines()
                   if re.match(rf'\| \d+ \| {re.escape(c["cause"])}( \(chosen\))? \|', x))
        for key, value in c['parameters'].items():
            if isinstance(value, list):
                continue
            name = key.rsplit('.', 1)[-1].replace('_', ' ')
            said = re.search(rf'(?:\| |; ){re.escape(name)} (\S+)( ms| s| [^;| ]+)?(?:;| \|)',
                             row)
            assert said is not None, (key, row)
            scale = 1e3 if said.group(2) == ' ms' else 1.0
            assert units.get(key) != 's' or said.group(2) in (' ms', ' s'), (key, row)
            # Every other unit is stated with its number (Hz, m, 1/A).
            assert units.get(key) in ('', 's') or said.group(2) == f' {units[key]}', (key, row)
            assert _close(said.group(1), scale * value), (key, value, row)
            _count('fitted parameter (table)')
        for key in c.get('not_identified', {}):
            assert f'{key} not identified' in row
            _count('not identified (table)')
    # The evidence sentence (JSON) and the evidence section (summary.md).
    evidence = facts['evidence']
    miss = re.search(r'misses (\S+) % of the output range', evidence)
    assert _close(miss.group(1), 100 * base['rms_error'])
    _count('evidence: baseline error')
    cut = re.search(r'extension cuts it by (-?\d+) % \(z = (\S+);', evidence)
    if chosen is None:
        assert cut is None and 'no extension reduces it significantly' in evidence
    else:
        assert cut is not None, evidence
        assert int(cut.group(1)) == round(100 * chosen['gain'])
        assert math.isclose(float(cut.group(2)), chosen['z'], abs_tol=0.051)
    _count('evidence: chosen gain and z')
    holds = residual['hold_signature']
    used = re.search(r'the hold signature test used (\d+) hold', evidence)
    assert used is None or (holds is not None and int(used.group(1)) == holds['holds'])
    assert ('no hold of' in evidence) <= (holds is None)
    during = re.search(r'- During (\d+) hold\(s\) the residual', summary)
    assert (during is None) == (holds is None)
    if holds is not None:
        assert int(during.group(1)) == holds['holds']
    _count('holds (evidence)', 2)
    bursts = residual['burst_signature']
    shown = re.search(r'- Bursts at (\d+) frequencies, .* follows the (\w+) law \(delay L ='
                      r' (\S+) ms', summary)
    assert (shown is None) == (bursts is None)
    if bursts is not None:
        assert int(shown.group(1)) == len(bursts['frequencies'])
        assert shown.group(2) == bursts['law']
        assert _close(shown.group(3), 1e3 * bursts['delay'])
    tested = re.search(r'the burst signature test used bursts at (\d+) frequencies', evidence)
    assert tested is None or int(tested.group(1)) == len(bursts['frequencies'])
    _count('bursts (evidence)', 2)
    # Who decided: the chosen candidate's signature, worded the same everywhere.
    if chosen is not None:
        for says in re.findall(r'its physical signature is (\w+)', evidence):
            assert says == chosen['signature'], evidence
        gain_alone = 'decided on the gain alone' in evidence
        assert gain_alone <= (chosen['signature'] == 'unavailable')
        _count('who decided')
    # The noise floor of the evidence section.
    floor = re.search(r'noise floor \S+ \S+ \((\S+) % of the output range\)', summary)
    assert _close(floor.group(1), 100 * residual['noise_floor_relative'])
    _count('noise floor')
    # stderr: every error, gain and noise floor a percentage; the offset a length with its unit.
    for line in err.splitlines():
        for number in re.finditer(r'(?:error|gain|noise floor|line) ([-+]?\d[\d.]*(?:e[-+]?\d+)?)'
                                  r'(?=[ ,;)])( %)?', line):
            assert number.group(2), line
        for number in re.finditer(r'offset re-estimated: (\S+)( m)?', line):
            assert number.group(2), line
    _count('stderr units')


def _png_text(path):
    with Image.open(path) as image:
        return dict(image.text)


def _check_plots(facts, summary, folder):
    """Check each plot's words (title, labels, legend) and its caption against the JSON."""
    images = re.findall(r'^!\[(\S+)\]\(\S+\)\n\n\*(.+)\*$', summary, flags=re.MULTILINE)
    assert images, summary[-500:]
    parameters = {c['cause']: c['parameters'] for c in facts['candidates']}
    for name, caption in images:
        text = _png_text(folder / name)
        title, words = text['Title'], text['Description']
        if name in ('loops.png', 'residual.png'):
            assert ('no extension was chosen' in title) == (facts['cause'] == 'none'), title
            assert ('no model was fitted' in title) == (not facts['baseline']), title
            assert ('simulated' in caption) == bool(facts['baseline']), caption
            _count('plot title: chosen or not')
            continue
        cause = name.removeprefix('signature_').removesuffix('.png')
        assert caption == EFFECTS[cause].caption
        _count('caption')
        fitted = parameters[cause]
        if cause == 'dead_time':
            said = re.search(r'fitted L = (\S+) ms; the residual is smallest at\sd = (\S+) ms'
                             r' \((.+)\)', title)
            assert _close(said.group(1), 1e3 * fitted['model.dead_time']), title
            assert f'legend: minimum at d = {said.group(2)} ms' in words
            assert f'legend: fitted dead time L = {said.group(1)} ms' in words
            _count('plot title: fitted value', 2)
        elif cause == 'resonance':
            said = re.search(r'f = (\S+) Hz, decay (\S+) ms', title)
            if 'model.resonance.frequency' in fitted and fitted['model.resonance.frequency'] > 0:
                assert said is not None, title
                assert math.isclose(float(said.group(1)), fitted['model.resonance.frequency'],
                                    rel_tol=5e-4)
                assert _close(said.group(2), 1e3 * fitted['model.resonance.decay'])
            else:
                assert said is None and 'no mode fitted' in title, title
            _count('plot title: fitted value')
        elif cause == 'thermal_drift':
            said = re.search(r'tau_T = (\S+) s, fitted', words)
            tau = fitted.get('model.thermal_drift.time_constant')
            assert (said is None) == (not tau), words
            if said is not None:
                assert _close(said.group(1), tau)
            _count('plot label: fitted value')
        elif cause == 'rate_dependence':
            said = re.search(r'lag tau = (\S+) ms', title)
            tau = fitted.get('model.rate_dependence.time_constant')
            assert (said is None) == (tau is None), title
            if said is not None:
                assert _close(said.group(1), 1e3 * tau)
            _count('plot title: fitted value')


def _check_prose(summary):
    for line in summary.splitlines():
        assert not re.match(r'\s*[{\[]', line), line
        assert not re.search(r'"\w+":', line), line
        for number in re.findall(r'\d*\.\d+(?:e[-+]?\d+)?|\d+e[-+]?\d+', line):
            mantissa = number.split('e')[0].replace('.', '').lstrip('0')
            assert len(mantissa) <= 4, (number, line)


def test_no_effect_record(tmp_path, capsys):
    _record(tmp_path / 'data.csv', {})
    facts, summary, err = _diagnose(tmp_path, capsys, tmp_path / 'data.csv')
    _check_agreement(facts, summary, err)
    assert facts['data']['units'] == data_units('current', 'displacement')
    assert (facts['data']['units']['input'], facts['data']['units']['output']) == ('A', 'm')


def test_creep_record_with_holds(tmp_path, capsys):
    _record(tmp_path / 'data.csv', {'creep_gain': 0.06}, seconds=30.0, hold_duration=2.0)
    facts, summary, err = _diagnose(tmp_path, capsys, tmp_path / 'data.csv')
    assert facts['residual']['holds']['count'] > 0          # the record holds the input
    _check_agreement(facts, summary, err)


def test_tie_is_ranked_with_how_to_separate(tmp_path, capsys):
    """A 10 ms dead time without holds or bursts: the record cannot separate the causes."""
    _record(tmp_path / 'data.csv', {'dead_time_s': 0.01}, holds=False, bursts=False)
    facts, summary, err = _diagnose(tmp_path, capsys, tmp_path / 'data.csv')
    assert facts['decision']['ambiguous'], facts['decision']['steps']
    _check_agreement(facts, summary, err)
    assert 'ambiguous' in err


def test_dead_time_validation_scored_from_a_later_sample_in_volts_and_nm(tmp_path, capsys):
    """A separate validation record in V and nm, with its own zero, scored after its burn-in."""
    cfg = ActuatorConfig(noise_std_m=NOISE, dead_time_s=0.0099)
    t, x = identification_excitation(20.0, sample_rate=1000.0, seed=1)
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=2, repeats=1, hold_duration=1.5)
    for name, (tk, xk), zero, seed in (('data', (t, x), -123e-6, 1),
                                       ('val', (tv, xv), -116e-6, 2)):
        y = MagnetostrictiveActuator(cfg, seed=seed).simulate(tk, xk)
        columns = {'time': tk, 'u_V': 10.0 * xk, 'D1_nm': (zero - y) * 1e9}
        write_csv_columns(tmp_path / f'{name}.csv', columns)
    facts, summary, err = _diagnose(tmp_path, capsys, tmp_path / 'data.csv', '--validate',
                                    str(tmp_path / 'val.csv'), '--output-scale', '1e-9')
    assert facts['data']['validation_scored']['from_sample'] > 0
    assert (facts['data']['units']['input'], facts['data']['units']['output']) == ('V', 'm')
    _check_agreement(facts, summary, err)
    assert 'current [A]' not in summary and 'input V' in summary
    # The fitted dead time, 3 significant digits, in the table; the sensor zero in nm or um.
    chosen = next(c for c in facts['candidates'] if c['cause'] == 'dead_time')
    fitted = re.search(r'\| dead time (\S+) ms \|', summary)
    assert _close(fitted.group(1), 1e3 * chosen['parameters']['model.dead_time'])
    shift = re.search(r'\(baseline: (\S+) (µm|nm)\)', summary)
    factor = 1e6 if shift.group(2) == 'µm' else 1e9
    assert _close(shift.group(1), factor * facts['baseline']['validation_output_offset'])


@pytest.mark.parametrize('names, scales, expected', [
    (('Vplus_V', 'D1_nm'), (1.0, 1e-9), ('V', 'm')),
    # Issue 27: the readers convert a named um column to m, so the data are in m.
    (('voltage', 'displacement_um'), (1.0, 1.0), ('V', 'm')),
    (('volts', 'nm'), (0.1, 1e-9), ('A', 'm')),         # the scale converts volts to A
    (('input_mV', 'pos'), (1e-3, 1.0), ('V', 'm')),
    (('/current_command', '/displacement'), (1.0, 1.0), ('A', 'm')),
    (('ch1', 'ch2'), (1.0, 1.0), ('A', 'm')),
])
def test_units_from_the_names_and_scales(names, scales, expected):
    units = data_units(*names, input_scale=scales[0], output_scale=scales[1])
    assert (units['input'], units['output']) == expected


def test_combined_and_weak_verdicts_are_written(tmp_path, capsys):
    """A verdict of two causes joined by ' + ' and the label 'present, weak' reach the prose."""
    _record(tmp_path / 'data.csv', {})
    facts, _, _ = _diagnose(tmp_path, capsys, tmp_path / 'data.csv')
    first, second = facts['candidates'][:2]
    combined = {**first, 'cause': f'{first["cause"]} + {second["cause"]}',
                'parameters': {**first['parameters'], **second['parameters']}}
    facts = {**facts, 'cause': combined['cause'], 'gain': 0.1,
             'candidates': [*facts['candidates'], combined],
             'decision': {**facts['decision'], 'verdict': 'present, weak',
                          'weak_reason': 'the gain 0.1 is below 0.2'}}
    text = markdown(facts)
    assert f'**Verdict: {combined["cause"]}** (present, weak)' in text
    assert 'Weak: the gain 0.1 is below 0.2' in text
    assert re.search(rf'\| \d+ \| {re.escape(combined["cause"])} \(chosen\) \|', text)
    _check_prose(text)


def test_dead_time_plot_has_its_minimum_at_the_fitted_delay():
    """The signature plot's minimum lies on the fitted L (within one grid step)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from mpi_ros.extensions import EFFECTS
    rate, dead = 1000.0, 0.0123
    t = np.arange(5000) / rate
    x = 1.0 + 0.6 * np.sin(2.0 * np.pi * 2.0 * t)
    measured = np.interp(t - dead, t, np.tanh(x))
    fitted = 0.012                                   # the fit's L, off the truth a little
    extended = np.interp(t - fitted, t, np.tanh(x))
    fig, ax = plt.subplots()
    EFFECTS['dead_time'].plot(ax, t, x, measured, np.tanh(x), extended, 1000,
                              parameters={'model.dead_time': fitted})
    curve = ax.get_lines()[0]
    delays, rms = curve.get_xdata(), curve.get_ydata()
    plt.close(fig)
    step = float(delays[1] - delays[0])
    # The shifted extended simulation matches best where the delay is the truth.
    assert abs(delays[int(np.argmin(rms))] - 1e3 * dead) <= step
    # The title states both numbers, the minimum as the curve has it, and whether they meet.
    title = re.search(r'fitted L = (\S+) ms; the residual is smallest at\sd = (\S+) ms'
                      r' \((.+)\)', ax.get_title())
    assert title is not None, ax.get_title()
    assert _close(title.group(1), 1e3 * fitted)
    assert _close(title.group(2), float(delays[int(np.argmin(rms))]))
    meets = abs(float(title.group(2)) - 1e3 * fitted) <= step
    assert title.group(3) == ('at the fitted delay' if meets else 'not at the fitted delay')


def test_dead_time_plot_title_says_when_the_minimum_is_elsewhere():
    """A fitted delay far from the residual's minimum (0.0382 ms vs 0.0833 ms, seen)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from mpi_ros.extensions import EFFECTS
    rate, dead, fitted = 10000.0, 0.0833e-3, 0.0382e-3
    t = np.arange(20000) / rate
    x = 1.0 + 0.6 * np.sin(2.0 * np.pi * 20.0 * t)
    measured = np.interp(t - dead, t, np.tanh(x))
    fig, ax = plt.subplots()
    EFFECTS['dead_time'].plot(ax, t, x, measured, np.tanh(x), np.interp(t - fitted, t,
                                                                        np.tanh(x)),
                              100, parameters={'model.dead_time': fitted})
    delays, rms = ax.get_lines()[0].get_xdata(), ax.get_lines()[0].get_ydata()
    title = ax.get_title()
    plt.close(fig)
    minimum = float(delays[int(np.argmin(rms))])
    assert f'smallest at\nd = {minimum:.3g} ms (not at the fitted delay)' in title, title
    assert f'fitted L = {1e3 * fitted:.3g} ms' in title


def test_resonance_plot_of_a_sine_says_there_is_no_step_and_has_a_caption():
    """A 100 Hz sine has no step: the title must not claim ringing after one."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from mpi_ros.diagnosis.report import markdown
    from mpi_ros.extensions import EFFECTS
    t = np.arange(5000) / 10000.0
    x = 1.0 + 0.5 * np.sin(2.0 * np.pi * 100.0 * t)
    fig, ax = plt.subplots()
    EFFECTS['resonance'].plot(ax, t, x, x, x, x, 0, parameters={})
    title = ax.get_title()
    plt.close(fig)
    assert 'has no step' in title and 'rings after a step' not in title, title
    assert 'no mode fitted' in title
    x[2500:] += 0.5                                         # now a step
    fig, ax = plt.subplots()
    EFFECTS['resonance'].plot(ax, t, x, x, x, x, 0, parameters={})
    assert 'after the largest input step' in ax.get_title()
    plt.close(fig)
    facts = {'cause': 'none', 'gain': 0.0, 'candidates': [], 'baseline': {}, 'data': {},
             'evidence': ''}
    text = markdown(facts, images=['signature_resonance.png', 'signature_creep.png'])
    captions = re.findall(r'^\*(.+)\*$', text, flags=re.MULTILINE)
    assert len(captions) == 2 and all(not c.endswith('.png') for c in captions), captions
    assert captions[0].startswith('Resonance:')


def test_a_pair_states_each_effect_and_a_weak_strength(tmp_path, capsys):
    """The diagnosis' keys: a pair's parts with each gain, decision.strength 'present, weak'."""
    _record(tmp_path / 'data.csv', {})
    facts, _, _ = _diagnose(tmp_path, capsys, tmp_path / 'data.csv')
    first, second = facts['candidates'][:2]
    names = sorted([first['cause'], second['cause']])
    pair = {**first, 'cause': ' + '.join(names), 'gain': 0.15, 'parts': names,
            'part_gains': {names[0]: 0.12, names[1]: 0.09},
            'part_z': {names[0]: 2.5, names[1]: -1.8}}
    facts = {**facts, 'cause': pair['cause'], 'gain': 0.15,
             'candidates': [*facts['candidates'], pair],
             'decision': {**facts['decision'], 'strength': 'present, weak',
                          'weak_reason': f'{pair["cause"]} is present, weak'}}
    text = markdown(facts)
    assert f'**Verdict: {pair["cause"]}** (present, weak)' in text
    assert (f'{names[0]} +12.0 % (z 2.50, significantly better), {names[1]} +9.00 % (z -1.80,'
            ' significantly worse)') in text
    _check_prose(text)


@pytest.mark.parametrize('config', [
    {'eddy_time_constant_s': 0.005},
    {'thermal_gain_m_per_a2': 1.2e-6},
    {'resonance_frequency_hz': 120.0},
], ids=['rate_dependence', 'thermal_drift', 'resonance'])
def test_synthetic_plants_of_every_effect(tmp_path, capsys, config):
    """A plant of each other effect (seeds fixed before looking), through the command line."""
    _record(tmp_path / 'data.csv', config, seed=3)
    facts, summary, err = _diagnose(tmp_path, capsys, tmp_path / 'data.csv')
    _check_agreement(facts, summary, err)


@pytest.mark.parametrize('name, options', [
    ('tum_piezo/rs_100hz_lp_20140608.csv', ()),
    ('tum_piezo/rs_40hz_nolp_20140608.csv', ()),
    ('pnzt-aixacct-tue/csv/SLOW_table01_TEST_0_1Hz.csv',
     ('--time-column', 'Time_s', '--input-column', 'Vplus_V', '--output-column', 'D1_nm')),
])
def test_measured_records(tmp_path, capsys, name, options):
    """Real records of ../shared/data/measured (skipped when absent), with their own units."""
    path = MEASURED / name
    if not path.exists():
        pytest.skip(f'{name} is not in ../shared/data/measured')
    argv = ['diagnose', str(path), *options, '--order', '8', '4', '--json',
            str(tmp_path / 'r.json'), '--report', str(tmp_path / 'report')]
    code = main(argv)
    err = capsys.readouterr().err
    if code != 0:                          # a refusal: one line naming the cause, no report
        assert code == 1 and re.search(r'^error: ', err, re.MULTILINE), err
        assert not (tmp_path / 'r.json').exists()
        pytest.skip(f'diagnose refuses {name}: {err.strip().splitlines()[-1]}')
    facts = json.loads((tmp_path / 'r.json').read_text(encoding='utf-8'))
    summary = (tmp_path / 'report' / 'summary.md').read_text(encoding='utf-8')
    _check_plots(facts, summary, tmp_path / 'report')
    if facts['cause'] == 'outside_invertible_class':
        # No model: the verdict, why, and the units; no table, no gains.
        assert summary.splitlines()[2] == ('**Verdict: outside_invertible_class** (outside the'
                                           ' invertible class: no model fitted)')
        why = summary.split('## Why no model was fitted\n\n', 1)[1].split('\n', 1)[0]
        assert why == facts['evidence'] and '| rank |' not in summary
        assert 'Holds: not counted (no model fitted)' in summary
        units = re.search(r'Units: input (\S+), output (\S+), time s', summary)
        assert (units.group(1), units.group(2)) == (facts['data']['units']['input'],
                                                    facts['data']['units']['output'])
        _check_prose(summary)
        _count('refusal: verdict, why, holds, units', 4)
        return
    _check_agreement(facts, summary, err)


@pytest.fixture(scope='module', autouse=True)
def _sentences_checked():
    """Print how many sentences of each kind were checked (shown with -s or -rA)."""
    yield
    print('\nsentences checked against the JSON:', ', '.join(
        f'{kind} {n}' for kind, n in sorted(CHECKED.items())), f'(total {sum(CHECKED.values())})')
