# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mpi-ros diagnose``: summary.md, the stderr summary and the plots say what the fields say.

Each record goes through the command line as a user runs it, and the typed report it
wrote is kept: its JSON form must be report.json, and summary.md, stderr and the plots'
words are parsed back and every sentence that states a fact is checked against the typed
fields (:mod:`mpi_ros.diagnosis.facts`): the verdict and its label (clear, weak,
ambiguous), the holds count and the holds the signature test used, the bursts, the scored
part; every candidate's errors, gain, z and the z test's wording (table, summary line,
decision steps, stderr, evidence), its signature, fitted values with their units and the
parameters not identified; the extended model (the chosen candidate), who decided (the
signature or the gain alone), a pair's effects, a weak verdict, the ties (who, why, the
ranking's gains and z against the chosen one); the fitted parameters in the plot titles
and legends (read back from each PNG's text), the captions (each effect's own, from the
registry) and the units.  No line of summary.md may look like JSON or carry more than 4
significant digits, and every error or gain printed on stderr is a percentage.  The
records: synthetic plants of every effect (mpi_ros.plant) and the measured records of
``../shared/data/measured`` when present.
"""

from dataclasses import replace
import importlib
import json
import math
from pathlib import Path
import re

from mpi_ros.app import diagnose_cli
from mpi_ros.app.cli import main
from mpi_ros.diagnosis.diagnose import DiagnosisReport
from mpi_ros.diagnosis.facts import Baseline, Extended, OperatingPoint, RecordFacts, \
    Refusal, Reversals, ScoredCandidate, Series
from mpi_ros.diagnosis.report import data_units, markdown, report_facts, summary_lines, \
    z_wording
from mpi_ros.errors import IdentificationError
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


def _diagnose(tmp_path, capsys, monkeypatch, data, *extra, order=('8', '4')):
    argv = ['diagnose', str(data), '--order', *order, '--json', str(tmp_path / 'r.json'),
            '--report', str(tmp_path / 'report'), *extra]
    reports = _capture(monkeypatch)
    assert main(argv) == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    facts = json.loads((tmp_path / 'r.json').read_text(encoding='utf-8'))
    summary = (tmp_path / 'report' / 'summary.md').read_text(encoding='utf-8')
    report = reports[-1]
    _check_typed_is_json(report, facts)
    _check_plots(report, summary, tmp_path / 'report')
    return facts, summary, err, report


def _capture(monkeypatch):
    """Keep the typed report the command line writes (its last call of diagnose)."""
    reports = []
    real = diagnose_cli.diagnose

    def keep(*args, **kwargs):
        reports.append(real(*args, **kwargs))
        return reports[-1]
    monkeypatch.setattr(diagnose_cli, 'diagnose', keep)
    return reports


def _check_typed_is_json(report, facts):
    """Check that the JSON is the typed fields' form, candidates and extended model typed."""
    assert json.loads(json.dumps(report_facts(report))) == facts
    assert all(isinstance(c, ScoredCandidate) for c in report.candidates)
    assert isinstance(report.extended, Extended) == (report.baseline is not None)
    _count('typed report is the JSON')


def _close(text, value):
    """Whether a number printed with 3 significant digits is ``value`` rounded."""
    return math.isclose(float(text), value, rel_tol=ROUNDING, abs_tol=1e-12)


def _check_agreement(report, facts, summary, err):
    lines = summary.splitlines()
    # Verdict.
    verdict = re.fullmatch(r'\*\*Verdict: (.+?)\*\* \((.+)\)', lines[2])
    assert verdict is not None, lines[:4]
    assert verdict.group(1) == report.cause == facts['cause']
    assert verdict.group(2).startswith('no effect found' if report.cause == 'none'
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
    # Units.
    units = re.search(r'Units: input (\S+), output (\S+), time s', summary)
    assert (units.group(1), units.group(2)) == (facts['data']['units']['input'],
                                                facts['data']['units']['output'])
    # The holds the evidence speaks of are the holds the signature test used.
    if residual['hold_signature'] is not None:
        assert 'no hold of' not in facts['evidence']
    # stdout/stderr state errors and gains in percent of the range, never as fractions.
    for line in err.splitlines():
        for number in re.finditer(r'(?:RMS error|gain) ([-+]?\d[\d.]*(?:e[-+]?\d+)?)( %)?',
                                  line):
            assert number.group(2), line
    # The stderr summary is the summary's head, line by line.
    for line in summary_lines(report):
        assert line in err.splitlines()
        assert f'- {line[0].upper()}{line[1:]}' in lines
    _check_prose(summary)
    _check_candidates(report, summary, err)
    _check_sentences(report, facts, summary, err)


#: Sentences checked against the typed fields, by kind (counted over the module's records).
CHECKED = {}


def _count(kind, n=1):
    CHECKED[kind] = CHECKED.get(kind, 0) + n


def _table_rows(summary):
    rows = {}
    for line in summary.splitlines():
        row = re.fullmatch(r'\| (\d+) \| (.+?)( \(chosen\))? \| (\S+) % \| (\S+) % \|'
                           r' (\S+) % \| (\S+) \| ([a-z ]+) \| (\w+) \| (.*) \|', line)
        if row:
            rows[row.group(2)] = row
    return rows


def _check_fitted(c, text):
    """Every fitted value of candidate C, with its unit, as TEXT (a table cell) states it."""
    for p in c.fitted():
        name = re.escape(p.name)
        if isinstance(p.value, tuple):
            if not p.value:
                continue
            said = re.search(rf'(?:^|; ){name} (\S+)( [^;| ]+)? to (\S+)( [^;| (]+)?'
                             r' \((\d+) values\)', text)
            assert said is not None, (p, text)
            assert int(said.group(5)) == len(p.value)
            for number, unit, value in ((said.group(1), said.group(2), min(p.value)),
                                        (said.group(3), said.group(4), max(p.value))):
                _check_unit(p, unit, text)
                assert _close(number, (1e3 if unit == ' ms' else 1.0) * value), (p, text)
        else:
            said = re.search(rf'(?:^|; ){name} (\S+)( [^;| ]+)?(?:;|$)', text)
            assert said is not None, (p, text)
            _check_unit(p, said.group(2), text)
            scale = 1e3 if said.group(2) == ' ms' else 1.0
            assert _close(said.group(1), scale * p.value), (p, text)
        _count('fitted parameter with its unit (table)')


def _check_unit(p, unit, text):
    # A time in ms or s, every other unit stated with its number (Hz, m, 1/A), none for a
    # dimensionless value.
    if p.unit == 's':
        assert unit in (' ms', ' s'), (p, text)
    else:
        assert (unit or '') == (f' {p.unit}' if p.unit else ''), (p, text)


def _check_candidates(report, summary, err):
    """Every sentence naming a candidate's fact, against the typed fields."""
    decision = report.decision
    zc = decision.z_critical
    by_cause = {c.cause: c for c in report.candidates}
    chosen = by_cause.get(report.cause)
    assert (chosen is None) == (report.cause == 'none')
    # The extended model is the chosen candidate (the baseline for none).
    ext = report.extended
    if chosen is None:
        assert ext.cause is None and ext.rms_error == report.baseline.rms_error
        assert ext.order == report.baseline.order and not ext.parameters
        assert report.gain == 0.0
    else:
        assert (ext.cause, ext.rms_error, ext.nonlinearity_error) == (
            chosen.cause, chosen.rms_error, chosen.nonlinearity_error)
        assert ext.parameters == chosen.parameters
        assert ext.not_identified == chosen.not_identified and report.gain == chosen.gain
    for c in report.candidates:
        assert not set(c.not_identified) & set(c.parameters), c
    _count('extended model is the chosen candidate')
    # The table: rank by gain, errors, gain, z and its wording, signature, fitted values,
    # the parameters not identified.
    rows = _table_rows(summary)
    assert sorted(rows) == sorted(by_cause)
    ranked = sorted(report.candidates, key=lambda c: -c.gain)
    for rank, c in enumerate(ranked, 1):
        row = rows[c.cause]
        assert int(row.group(1)) == rank
        assert bool(row.group(3)) == (c is chosen)
        assert _close(row.group(4), 100 * c.rms_error)
        assert _close(row.group(5), 100 * c.nonlinearity_error)
        assert _close(row.group(6), 100 * c.gain)
        assert _close(row.group(7), c.z)
        assert row.group(8) == z_wording(c.z, zc)
        assert row.group(9) == c.signature
        cell = row.group(10)
        _check_fitted(c, cell)
        said = re.findall(r'; (\S+) not identified \(at a search bound\)', cell)
        assert said == list(c.not_identified), (cell, c.not_identified)
        _count('candidate row: rank, errors, gain, z, test, signature', 8)
        _count('not identified (table)', len(said))
    # The summary line of gains (summary.md and stderr): every gain, z and wording.
    line = next(x for x in summary.splitlines() if x.startswith('- Gains on the validation'))
    said = re.findall(r'(\S+(?: \+ \S+)?) ([-+]\S+) % \(z (\S+), ([a-z ]+)\)',
                      line.split(': ', 1)[1])
    assert [cause for cause, *_ in said] == [c.cause for c in ranked]
    for cause, gain, z, wording in said:
        c = by_cause[cause]
        assert _close(gain, 100 * c.gain) and _close(z, c.z)
        assert wording == z_wording(c.z, zc)
        _count('gain and significance (summary line)')
    # A pair: each effect beyond the other alone.
    each = next((x for x in summary.splitlines() if x.startswith('- Each effect beyond')),
                None)
    assert (each is not None) == bool(chosen is not None and chosen.parts)
    if each is not None:
        for name in chosen.parts:
            got = re.search(rf'{re.escape(name)} ([-+]\S+) % \(z (\S+), ([a-z ]+)\)', each)
            assert _close(got.group(1), 100 * chosen.part_gains[name])
            assert _close(got.group(2), chosen.part_z[name])
            assert got.group(3) == z_wording(chosen.part_z[name], zc)
            _count('pair: each effect')
    # The decision steps: each candidate's gain, z, wording, whether it counts, signature.
    for c in report.candidates:
        for step in (s for s in decision.steps if s.startswith(f'{c.cause}: gain ')):
            got = re.match(rf'{re.escape(c.cause)}: gain ([-+]\S+) %, z (\S+) \(([a-z ]+)\)',
                           step)
            assert _close(got.group(1), 100 * c.gain) and _close(got.group(2), c.z), step
            assert got.group(3) == z_wording(c.z, zc), step
            if c.parts:
                continue
            assert (', counts;' in step) == c.significant, step
            assert step.endswith(f'; signature {c.signature}'), step
            _count('decision step: gain, z, counts, signature', 4)
    best = [s for s in decision.steps if s.startswith('largest gain among the eligible: ')]
    for step in best:
        got = re.match(r'largest gain among the eligible: (\S+) \((\S+) %; (.+)\)$', step)
        c = by_cause[got.group(1)]
        assert _close(got.group(2), 100 * c.gain), step
        assert got.group(3) == (
            'its signature is unavailable in this record: decided on the gain alone'
            if c.signature == 'unavailable' else f'its physical signature is {c.signature}')
        _count('who decided (decision step)')
    # stderr: each candidate's line as scored, and the verdict's gain and unidentified keys.
    for c in report.candidates:
        got = list(re.finditer(rf'^  {re.escape(c.cause)}: validation RMS error (\S+) %'
                               r' of the output range, gain (\S+) %, z (\S+)$', err,
                               re.MULTILINE))
        assert got, c.cause
        assert _close(got[-1].group(1), 100 * c.rms_error)
        assert _close(got[-1].group(2), 100 * c.gain) and _close(got[-1].group(3), c.z)
        _count('stderr: candidate scored', 3)
    verdict = re.findall(r'^verdict: (.+) \(validation gain (\S+) %(?:; not identified: (.+))?\)$',
                         err, re.MULTILINE)
    cause, gain, unknown = verdict[-1]
    assert cause == report.cause and _close(gain, 100 * report.gain)
    head = re.fullmatch(r'verdict: (.+?) \((.+?)\)(?:, validation gain (\S+) %)?',
                        summary_lines(report)[0])
    assert head.group(1) == report.cause
    assert (head.group(3) is None) == (report.gain == 0.0)
    assert head.group(3) is None or _close(head.group(3), 100 * report.gain)
    assert (unknown.split(', ') if unknown else []) == list(report.extended.not_identified)
    _count('stderr: verdict, gain, not identified', 3)
    # The evidence: the chosen gain and z, every gain, who decided, weak, not identified.
    evidence = report.evidence
    listing = re.search(r'(?:all: |significantly \()([^;)]+)', evidence).group(1)
    said = re.findall(r'(\S+(?: \+ \S+)?) ([-+]\d+) %', listing)
    assert [cause for cause, _ in said] == [c.cause for c in ranked], listing
    for cause, gain in said:
        assert int(gain) == round(100 * by_cause[cause].gain), (cause, listing)
    _count('evidence: every gain', len(said))
    cut = re.search(r'extension cuts it by (-?\d+) % \(z = (\S+);', evidence)
    assert (cut is None) == (chosen is None), evidence
    if chosen is not None:
        assert int(cut.group(1)) == round(100 * chosen.gain)
        assert math.isclose(float(cut.group(2)), chosen.z, abs_tol=0.051)
        for says in re.findall(r'its physical signature is (\w+)', evidence):
            assert says == chosen.signature, evidence
        assert ('decided on the gain alone' in evidence) <= (chosen.signature == 'unavailable')
        _count('evidence: chosen gain, z, who decided', 3)
    weak = re.search(r'Weak: (\S+(?: \+ \S+)?) is present, weak: its extension cuts the'
                     r' validation error by only'
                     r' (\d+) %.*physical signature is (\w+);', evidence)
    assert (weak is not None) == (decision.strength == 'present, weak')
    if weak is not None:
        assert weak.group(1) == chosen.cause and int(weak.group(2)) == round(100 * chosen.gain)
        assert weak.group(3) == chosen.signature
        _count('evidence: weak', 3)
    unknown = re.search(r'Not identified \(.*?\): (.+)\.', evidence)
    assert (unknown is not None) == bool(report.extended.not_identified)
    if unknown is not None:
        for key, why in report.extended.not_identified.items():
            assert f'{key} {why}' in unknown.group(1)
            _count('evidence: not identified')
    # Ties: who, why, the ranking's gains and z against the chosen one.
    assert decision.ambiguous == bool(decision.tied_with)
    for row in decision.ranking:
        c = by_cause[row.cause]
        assert (row.gain, row.significant, row.signature) == (c.gain, c.significant,
                                                              c.signature)
    assert [row.cause for row in decision.ranking] == [c.cause for c in ranked]
    if not decision.ambiguous:
        assert '## Ambiguous' not in summary and 'ambiguous:' not in err
        return
    label = re.search(r'\*\*Verdict: .+?\*\* \((.+)\)', summary).group(1)
    if decision.strength != 'present, weak':
        assert label == f'present, ambiguous: tied with {" and ".join(decision.tied_with)}'
    line = next(x for x in err.splitlines() if x.startswith('ambiguous: '))
    z_of = {r.cause: r.z_against_chosen for r in decision.ranking}
    for cause in decision.tied_with:
        reason = decision.tie_reasons.get(cause)
        assert f'{cause} is tied with {report.cause}' + (f': {reason}' if reason else '') in line
        # A tie on the validation data words its z as the z test does (within the noise:
        # not significant; significantly better: the chosen one significantly worse).
        said = [re.search(r'(within the noise of|significantly better than) (\S+) on the'
                          r' validation data \(z (\S+) (<|<=) (\S+)\)', reason or '')]
        said += [re.match(rf'{re.escape(cause)} is (within the noise of|significantly better'
                          r' than) (\S+) \(z (\S+) (<|<=) (\S+)\)[^:]*: ambiguous$', step)
                 for step in decision.steps if step.startswith(f'{cause} is ')]
        for got in (g for g in said if g is not None):
            assert got.group(2) == report.cause and _close(got.group(3), z_of[cause])
            assert got.group(1) == ('within the noise of'
                                    if z_wording(z_of[cause], zc) == 'not significant'
                                    else 'significantly better than'), (got.group(0), zc)
            assert float(got.group(5)) == (zc if got.group(4) == '<' else -zc)
            if got.group(1) == 'significantly better than':
                assert (f"{cause}'s physical signature is {by_cause[cause].signature},"
                        f" {report.cause}'s {chosen.signature}") in got.string
            _count('tie: z worded as the z test')
        _count('tie: who and why')
    # The evidence says whether the chosen one ranks first by its gain.
    top = ranked[0]
    if chosen.gain >= top.gain:
        assert f'{chosen.cause} ranks first by its validation gain' in evidence
    else:
        assert (f'{chosen.cause} is chosen although {top.cause} has a larger validation gain'
                in evidence), evidence
    assert 'ranks first by its validation gain' not in evidence or chosen.gain >= top.gain
    _count('tie: who ranks first by gain')
    section = summary.split('## Ambiguous', 1)[1].split('\n## ', 1)[0]
    tied = [report.cause, *decision.tied_with]
    shown = re.findall(r'^\d+\. (\S+): gain ([-+]\S+) % \((.+); signature (\w+)\)$', section,
                       re.MULTILINE)
    assert [cause for cause, *_ in shown] == [r.cause for r in decision.ranking
                                              if r.cause in tied]
    rows = {r.cause: r for r in decision.ranking}
    for cause, gain, against, signature in shown:
        row = rows[cause]
        assert _close(gain, 100 * row.gain) and signature == row.signature
        if cause == report.cause:
            assert against == 'chosen'
        else:
            z = re.fullmatch(rf'z (\S+) against {re.escape(report.cause)}', against)
            assert _close(z.group(1), row.z_against_chosen), against
        _count('tie: ranked gain, z against the chosen one, signature', 3)
    assert '`mpi-ros diagnose --excitation' in section


def _check_sentences(report, facts, summary, err):
    """Check the sentences beyond the candidates: label, baseline, holds, bursts, noise."""
    decision, residual = facts['decision'], facts['residual']
    # The label: ambiguous, weak or clear as the decision says.
    label = re.search(r'\*\*Verdict: .+?\*\* \((.+)\)', summary).group(1)
    assert label.startswith('present, ambiguous') == (
        decision['ambiguous'] and decision.get('strength') != 'present, weak'), label
    assert (label == 'present, weak') == (decision.get('strength') == 'present, weak'), label
    _count('verdict label')
    # The baseline's row and the straight line.
    base = report.baseline
    row = re.search(r'\| - \| baseline MPI, order (\d+), (\d+) \| (\S+) % \| (\S+) % \|', summary)
    assert (int(row.group(1)), int(row.group(2))) == tuple(base.order)
    assert _close(row.group(3), 100 * base.rms_error)
    assert _close(row.group(4), 100 * base.nonlinearity_error)
    line = re.search(r'Straight line fitted on the training data: (\S+) % RMS', summary)
    assert _close(line.group(1), 100 * base.linear_rms_error)
    _count('baseline errors', 2)
    # The evidence sentence (JSON) and the evidence section (summary.md).
    evidence = facts['evidence']
    miss = re.search(r'misses (\S+) % of the output range', evidence)
    assert _close(miss.group(1), 100 * base.rms_error)
    _count('evidence: baseline error')
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
    # The noise floor of the evidence section.
    floor = re.search(r'noise floor \S+ \S+ \((\S+) % of the output range\)', summary)
    assert _close(floor.group(1), 100 * residual['noise_floor_relative'])
    _count('noise floor')
    # stderr: every error, gain and noise floor a percentage; the offset a length with its unit.
    for line in err.splitlines():
        for number in re.finditer(r'(?:error|gain|noise floor|line) ([-+]?\d[\d.]*(?:e[-+]?\d+)?)'
                                  r'(?=[ ,;)])( %)?', line):
            assert number.group(2), line
        for number in re.finditer(r'offset re-estimated: (\S+)( [pnµm]?m\b)?', line):
            assert number.group(2), line
            # 3 significant digits, as every other number.
            assert len(number.group(1).lstrip('+-').replace('.', '').lstrip('0')) <= 3, line
    _count('stderr units')


def _png_text(path):
    with Image.open(path) as image:
        return dict(image.text)


def _check_plots(report, summary, folder):
    """Check each plot's words (title, labels, legend) and its caption against the fields."""
    images = re.findall(r'^!\[(\S+)\]\(\S+\)\n\n\*(.+)\*$', summary, flags=re.MULTILINE)
    assert images, summary[-500:]
    parameters = {c.cause: c.parameters for c in report.candidates}
    fitted_model = report.baseline is not None
    for name, caption in images:
        text = _png_text(folder / name)
        title, words = text['Title'], text['Description']
        if name in ('loops.png', 'residual.png'):
            assert ('no extension was chosen' in title) == (report.cause == 'none'), title
            assert ('no model was fitted' in title) == (not fitted_model), title
            assert ('simulated' in caption) == fitted_model, caption
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


def test_no_effect_record(tmp_path, capsys, monkeypatch):
    _record(tmp_path / 'data.csv', {})
    facts, summary, err, report = _diagnose(tmp_path, capsys, monkeypatch,
                                            tmp_path / 'data.csv')
    _check_agreement(report, facts, summary, err)
    assert facts['data']['units'] == data_units('current', 'displacement')
    assert (facts['data']['units']['input'], facts['data']['units']['output']) == ('A', 'm')


def test_creep_record_with_holds(tmp_path, capsys, monkeypatch):
    _record(tmp_path / 'data.csv', {'creep_gain': 0.06}, seconds=30.0, hold_duration=2.0)
    facts, summary, err, report = _diagnose(tmp_path, capsys, monkeypatch,
                                            tmp_path / 'data.csv')
    assert facts['residual']['holds']['count'] > 0          # the record holds the input
    _check_agreement(report, facts, summary, err)


def test_a_weak_verdict_is_stated_with_its_cause_as_written(tmp_path, capsys, monkeypatch):
    """
    A weak verdict's evidence names the cause as the identifier, never capitalised.

    The creep record above with the strength bar raised to 0.999, so that its clear creep is
    reported as present but weak through the real decision: the evidence sentence opened
    with ``Creep is present, weak`` and the cause read from it was not the chosen one.
    """
    # The package exports the function diagnose under the module's name.
    module = importlib.import_module('mpi_ros.diagnosis.diagnose')
    monkeypatch.setattr(module, 'STRONG_GAIN', 0.999)
    _record(tmp_path / 'data.csv', {'creep_gain': 0.06}, seconds=30.0, hold_duration=2.0)
    facts, summary, err, report = _diagnose(tmp_path, capsys, monkeypatch,
                                            tmp_path / 'data.csv')
    assert report.decision.strength == 'present, weak', report.decision
    assert f'Weak: {report.cause} is present, weak' in report.evidence
    _check_agreement(report, facts, summary, err)


def test_an_effect_whose_fit_fails_is_left_out_and_the_others_judged(
        tmp_path, capsys, monkeypatch):
    """
    One candidate's fit refused does not end the diagnosis: the others are still judged.

    The creep record above with the thermal-drift fit raising IdentificationError: creep is
    still named, thermal drift is not ranked, and a warning and a decision step say why.
    """
    def refused(*args, **kwargs):
        raise IdentificationError('the drift fit refuses this record (test)')

    monkeypatch.setitem(EFFECTS, 'thermal_drift', replace(EFFECTS['thermal_drift'], fit=refused))
    _record(tmp_path / 'data.csv', {'creep_gain': 0.06}, seconds=30.0, hold_duration=2.0)
    facts, summary, err, report = _diagnose(tmp_path, capsys, monkeypatch,
                                            tmp_path / 'data.csv')
    assert report.cause == 'creep'
    assert 'thermal_drift' not in [c.cause for c in report.candidates]
    said = [w for w in report.warnings if 'thermal_drift candidate could not be fitted' in w]
    assert len(said) == 1 and 'the drift fit refuses this record (test)' in said[0]
    assert said[0] in report.decision.steps
    assert 'thermal_drift candidate could not be fitted' in err
    _check_agreement(report, facts, summary, err)


def test_tie_is_ranked_with_how_to_separate(tmp_path, capsys, monkeypatch):
    """A 10 ms dead time without holds or bursts: the record cannot separate the causes."""
    _record(tmp_path / 'data.csv', {'dead_time_s': 0.01}, holds=False, bursts=False)
    facts, summary, err, report = _diagnose(tmp_path, capsys, monkeypatch,
                                            tmp_path / 'data.csv')
    assert facts['decision']['ambiguous'], facts['decision']['steps']
    _check_agreement(report, facts, summary, err)
    assert 'ambiguous' in err


def test_dead_time_validation_scored_from_a_later_sample_in_volts_and_nm(
        tmp_path, capsys, monkeypatch):
    """A separate validation record in V and nm, with its own zero, scored after its burn-in."""
    cfg = ActuatorConfig(noise_std_m=NOISE, dead_time_s=0.0099)
    t, x = identification_excitation(20.0, sample_rate=1000.0, seed=1)
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=2, repeats=1, hold_duration=1.5)
    for name, (tk, xk), zero, seed in (('data', (t, x), -123e-6, 1),
                                       ('val', (tv, xv), -116e-6, 2)):
        y = MagnetostrictiveActuator(cfg, seed=seed).simulate(tk, xk)
        columns = {'time': tk, 'u_V': 10.0 * xk, 'D1_nm': (zero - y) * 1e9}
        write_csv_columns(tmp_path / f'{name}.csv', columns)
    facts, summary, err, report = _diagnose(tmp_path, capsys, monkeypatch,
                                            tmp_path / 'data.csv', '--validate',
                                            str(tmp_path / 'val.csv'), '--output-scale', '1e-9')
    assert facts['data']['validation_scored']['from_sample'] > 0
    assert (facts['data']['units']['input'], facts['data']['units']['output']) == ('V', 'm')
    _check_agreement(report, facts, summary, err)
    assert 'current [A]' not in summary and 'input V' in summary
    # The fitted dead time, 3 significant digits, in the table; the sensor zero in nm or um.
    chosen = next(c for c in report.candidates if c.cause == 'dead_time')
    fitted = re.search(r'\| dead time (\S+) ms \|', summary)
    assert _close(fitted.group(1), 1e3 * chosen.parameters['model.dead_time'])
    shift = re.search(r'\(baseline: (\S+) (µm|nm)\)', summary)
    factor = 1e6 if shift.group(2) == 'µm' else 1e9
    assert _close(shift.group(1), factor * report.baseline.validation_output_offset)


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


def test_combined_and_weak_verdicts_are_written(tmp_path, capsys, monkeypatch):
    """A verdict of two causes joined by ' + ' and the label 'present, weak' reach the prose."""
    _record(tmp_path / 'data.csv', {})
    _, _, _, report = _diagnose(tmp_path, capsys, monkeypatch, tmp_path / 'data.csv')
    first, second = report.candidates[:2]
    combined = replace(first, cause=f'{first.cause} + {second.cause}',
                       parameters={**first.parameters, **second.parameters})
    report = replace(report, cause=combined.cause, gain=0.1,
                     candidates=[*report.candidates, combined],
                     decision=replace(report.decision, strength='present, weak',
                                      weak_reason='the gain 0.1 is below 0.2'))
    text = markdown(report)
    assert f'**Verdict: {combined.cause}** (present, weak)' in text
    assert 'Weak: the gain 0.1 is below 0.2' in text
    assert re.search(rf'\| \d+ \| {re.escape(combined.cause)} \(chosen\) \|', text)
    _check_fitted(combined, _table_rows(text)[combined.cause].group(10))
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
    report = DiagnosisReport(cause='none', baseline=None, extended=None, gain=0.0,
                             candidates=[], evidence='', residual=Reversals(0.0, 0),
                             decision=Refusal(''), data=RecordFacts('', 0, ''),
                             series=Series(t, x, x, 0))
    text = markdown(report, images=['signature_resonance.png', 'signature_creep.png'])
    captions = re.findall(r'^\*(.+)\*$', text, flags=re.MULTILINE)
    assert len(captions) == 2 and all(not c.endswith('.png') for c in captions), captions
    assert captions[0].startswith('Resonance:')


def test_a_pair_states_each_effect_and_a_weak_strength(tmp_path, capsys, monkeypatch):
    """The diagnosis' keys: a pair's parts with each gain, decision.strength 'present, weak'."""
    _record(tmp_path / 'data.csv', {})
    _, _, _, report = _diagnose(tmp_path, capsys, monkeypatch, tmp_path / 'data.csv')
    first, second = report.candidates[:2]
    names = sorted([first.cause, second.cause])
    pair = replace(first, cause=' + '.join(names), gain=0.15, parts=names,
                   part_gains={names[0]: 0.12, names[1]: 0.09},
                   part_z={names[0]: 2.5, names[1]: -1.8})
    report = replace(report, cause=pair.cause, gain=0.15, candidates=[*report.candidates, pair],
                     decision=replace(report.decision, strength='present, weak',
                                      weak_reason=f'{pair.cause} is present, weak'))
    text = markdown(report)
    assert f'**Verdict: {pair.cause}** (present, weak)' in text
    assert (f'{names[0]} +12.0 % (z 2.50, significantly better), {names[1]} +9.00 % (z -1.80,'
            ' significantly worse)') in text
    _check_prose(text)


@pytest.mark.parametrize('config', [
    {'eddy_time_constant_s': 0.005},
    {'thermal_gain_m_per_a2': 1.2e-6},
    {'resonance_frequency_hz': 120.0},
], ids=['rate_dependence', 'thermal_drift', 'resonance'])
def test_synthetic_plants_of_every_effect(tmp_path, capsys, monkeypatch, config):
    """A plant of each other effect (seeds fixed before looking), through the command line."""
    _record(tmp_path / 'data.csv', config, seed=3)
    facts, summary, err, report = _diagnose(tmp_path, capsys, monkeypatch,
                                            tmp_path / 'data.csv')
    _check_agreement(report, facts, summary, err)


@pytest.mark.parametrize('name, options', [
    ('tum_piezo/rs_100hz_lp_20140608.csv', ()),
    ('tum_piezo/rs_40hz_nolp_20140608.csv', ()),
    ('pnzt-aixacct-tue/csv/SLOW_table01_TEST_0_1Hz.csv',
     ('--time-column', 'Time_s', '--input-column', 'Vplus_V', '--output-column', 'D1_nm')),
])
def test_measured_records(tmp_path, capsys, monkeypatch, name, options):
    """Real records of ../shared/data/measured (skipped when absent), with their own units."""
    path = MEASURED / name
    if not path.exists():
        pytest.skip(f'{name} is not in ../shared/data/measured')
    argv = ['diagnose', str(path), *options, '--order', '8', '4', '--json',
            str(tmp_path / 'r.json'), '--report', str(tmp_path / 'report')]
    reports = _capture(monkeypatch)
    code = main(argv)
    err = capsys.readouterr().err
    if code != 0:                          # a refusal: one line naming the cause, no report
        assert code == 1 and re.search(r'^error: ', err, re.MULTILINE), err
        assert not (tmp_path / 'r.json').exists()
        pytest.skip(f'diagnose refuses {name}: {err.strip().splitlines()[-1]}')
    facts = json.loads((tmp_path / 'r.json').read_text(encoding='utf-8'))
    summary = (tmp_path / 'report' / 'summary.md').read_text(encoding='utf-8')
    report = reports[-1]
    _check_typed_is_json(report, facts)
    _check_plots(report, summary, tmp_path / 'report')
    if report.cause == 'outside_invertible_class':
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
    _check_agreement(report, facts, summary, err)


def test_json_keys_of_the_candidates_and_the_extended_model():
    """The JSON keys of a candidate and of the extended model, as users read them."""
    single = ScoredCandidate('dead_time', 0.01, 0.02, 0.3, 4.0, 7, 0.011, 1e-6, 1,
                             {'model.dead_time': 0.002}, {}, 'present', True)
    keys = ['cause', 'rms_error', 'nonlinearity_error', 'gain', 'z', 'bandwidth',
            'training_rms_error', 'validation_output_offset', 'parameter_count',
            'parameters', 'not_identified', 'signature', 'significant']
    assert list(single.to_json()) == keys
    pair = replace(single, cause='creep + dead_time', parts=['creep', 'dead_time'],
                   part_gains={'creep': 0.1, 'dead_time': 0.2},
                   part_z={'creep': 2.0, 'dead_time': 3.0})
    assert list(pair.to_json()) == [*keys, 'parts', 'part_gains', 'part_z']
    assert pair.effects == ['creep', 'dead_time'] and single.effects == ['dead_time']
    assert [(p.name, p.value, p.unit) for p in single.fitted()] == [('dead time', 0.002, 's')]
    thermal = replace(single, cause='thermal_drift', parameters={
        'model.thermal_drift.time_constant': 12.0, 'model.thermal_drift.weight': 0.0,
        'model.thermal_drift.gain': 1.5e-6})
    # k_T is not called "gain" beside the table's validation gain column.
    assert [(p.name, p.unit) for p in thermal.fitted()] == [
        ('time constant', 's'), ('input weight w_T', '1/A'),
        ('displacement coefficient k_T', 'm/A^2')]
    chosen = Extended.of_candidate(single)
    assert chosen.to_json() == {'cause': 'dead_time', 'rms_error': 0.01,
                                'nonlinearity_error': 0.02,
                                'parameters': {'model.dead_time': 0.002}, 'not_identified': {}}
    baseline = Baseline((8, 4), 0.02, 0.05, 0.018, 0.0, 0.2,
                        OperatingPoint(0.0, 1e-6, 1))
    none = Extended.of_baseline(baseline)
    assert none.to_json() == {**baseline.to_json(), 'parameters': {}, 'not_identified': {}}
    assert list(none.to_json()) == [*baseline.to_json(), 'parameters', 'not_identified']


@pytest.fixture(scope='module', autouse=True)
def _sentences_checked():
    """Print how many sentences of each kind were checked (shown with -s or -rA)."""
    yield
    print('\nsentences checked against the typed report:', ', '.join(
        f'{kind} {n}' for kind, n in sorted(CHECKED.items())), f'(total {sum(CHECKED.values())})')
