# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Effect fits that generalise (issue 24 item 4, issue 26): nesting, folds, bounds."""

from mpi_ros import identify
from mpi_ros.diagnosis import diagnose
from mpi_ros.errors import DataError
from mpi_ros.extensions import CreepModel, DeadTimeModel, fit_creep, fit_dead_time, \
    fit_rate_dependence, fit_thermal_drift, RateDependentModel, ThermalDriftModel
from mpi_ros.extensions.creep import CREEP_TIME_CONSTANTS, creep_time_constants
from mpi_ros.extensions.dead_time import DEAD_TIME
from mpi_ros.extensions.effect import unidentified_parameters
from mpi_ros.extensions.fitting import determined_start, fit_gamma, lag_search_limits
from mpi_ros.extensions.rate_dependence import RATE_TIME_CONSTANT
from mpi_ros.extensions.thermal_drift import THERMAL_TIME_CONSTANT
from mpi_ros.identification import identify_weights
from mpi_ros.identification.folds import blocked_folds
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import diagnostic_excitation, identification_excitation
from mpi_ros.plant.preisach import random_preisach_core
from mpi_ros.recordings import Recording
import numpy as np
import pytest

ORDER = (10, 5)
RATE = 200.0
DURATION = 30.0


def _input():
    return identification_excitation(DURATION, sample_rate=RATE, seed=3,
                                     burst_frequency=5.0, hold_duration=3.0)


def _record(core=None, **effect):
    t, x = _input()
    plant = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=2e-8, **effect), seed=1,
                                     core=core)
    return t, x, plant.simulate(t, x)


def _gamma():
    t, x, y = _record()
    design, w_h, w_s_inv, _, constant, _ = identify_weights(x, y, *ORDER)
    return t, x, design.model(w_h, w_s_inv, constant)


# -- folds -------------------------------------------------------------------------------

def test_blocked_folds_are_disjoint_contiguous_blocks_covering_the_record():
    masks = blocked_folds(1000, 3, start=100, blocks=30)
    assert len(masks) == 3
    total = np.sum(masks, axis=0)
    assert np.all(total[:100] == 0) and np.all(total[100:] == 1)
    for mask in masks:
        starts = np.flatnonzero(np.diff(mask.astype(int)) == 1)
        assert starts.size == 10          # ten contiguous blocks per fold, 30 blocks dealt
        assert 250 <= mask.sum() <= 350


def test_blocked_folds_refuse_too_few_samples_or_folds():
    with pytest.raises(DataError, match='count >= 2'):
        blocked_folds(100, 1)
    with pytest.raises(DataError, match='too few samples'):
        blocked_folds(10, 3, start=8)


# -- nesting: the effect switched off is the baseline exactly ------------------------------

def test_each_effect_switched_off_gives_gamma_exactly():
    t, x, gamma = _gamma()
    plain = gamma.simulate(x)
    taus = creep_time_constants(t)
    for model in (RateDependentModel(gamma, 0.0), DeadTimeModel(gamma, 0.0),
                  ThermalDriftModel(gamma, 30.0, 0.0),
                  CreepModel(gamma, taus, np.zeros(taus.size))):
        assert np.array_equal(model.simulate(t, x), plain), model.cause


# -- on the training data, never worse than the baseline ------------------------------------

def _mse(sim, y, keep):
    return float(np.mean((sim[keep] - y[keep]) ** 2))


@pytest.fixture(scope='module')
def hard_record():
    # No effect, a discrete Preisach core with a rough random density: the baseline MPI
    # misses it (a staircase), the effects' fits have room to chase that misfit.
    return _record(core=random_preisach_core(7))


@pytest.mark.parametrize('fit', [fit_rate_dependence, fit_dead_time])
def test_input_stage_fits_are_never_worse_than_gamma_on_the_training_record(hard_record, fit):
    t, x, y = hard_record
    _, longest = lag_search_limits(t)
    settle = 3.0 * longest if fit is fit_rate_dependence else longest
    start = determined_start(t, x, y, ORDER, settle=settle)
    base, _ = fit_gamma(x, y, ORDER, 1e-6, start=start)
    model = fit(t, x, y, order=ORDER)
    keep = np.arange(t.size) >= start
    assert _mse(model.simulate(t, x), y, keep) <= _mse(base.simulate(x), y, keep)


@pytest.mark.parametrize('fit', [fit_thermal_drift, fit_creep])
def test_material_fits_are_never_worse_than_gamma_on_the_training_record(hard_record, fit):
    # Against identify's Gamma, the baseline a diagnosis compares with, on every sample,
    # each simulated from its record start.
    t, x, y = hard_record
    base = identify(x, y, n=ORDER[0], l=ORDER[1]).model
    model = fit(t, x, y, order=ORDER)
    every = np.ones(t.size, dtype=bool)
    assert _mse(model.response(t, x), y, every) <= _mse(base.response(t, x), y, every)


_RAMP_EFFECTS = {
    'creep': (fit_creep, {'creep_gain': 0.08, 'creep_time_constant_min_s': 0.3,
                          'creep_time_constant_max_s': 60.0}),
    'thermal_drift': (fit_thermal_drift, {'thermal_gain_m_per_a2': 2e-6,
                                          'thermal_time_constant_s': 20.0})}


@pytest.mark.parametrize('core_seed', [None, 5, 8])
@pytest.mark.parametrize('cause', sorted(_RAMP_EFFECTS))
def test_material_fits_model_the_first_ramp_from_rest_as_identify_does(cause, core_seed):
    # The record starts at rest (0 A) and ramps up: the only currents below the excitation's
    # range.  The creep rounds and the drift trials fit Gamma after the plays are
    # determined; their final Gamma extrapolated that ramp (3-9x identify's error over the
    # first second, and up to 1.5x over the whole record).  Now it is fitted as identify's.
    fit, effect = _RAMP_EFFECTS[cause]
    core = None if core_seed is None else random_preisach_core(core_seed)
    t, x, y = _record(core=core, **effect)
    assert x[0] == 0.0 and np.min(x[int(RATE):]) > 0.1
    base = identify(x, y, n=ORDER[0], l=ORDER[1]).model.response(t, x)
    sim = fit(t, x, y, order=ORDER).response(t, x)
    first = np.arange(t.size) < int(RATE)
    every = np.ones(t.size, dtype=bool)
    assert _mse(sim, y, first) <= 1.5 ** 2 * _mse(base, y, first)
    assert _mse(sim, y, every) <= _mse(base, y, every)


def test_creep_fit_at_a_high_order_minimises_the_output_error_and_generalises():
    # Issue 24: the wide sweep's creep plant 102 (built-in core, creep 8.5 % over
    # 0.04-15 s), fitted at (12, 6) as the diagnosis does.  The QP rounds alone minimise
    # the generalised error and landed at 2x the baseline's output error; the held-out
    # blocks then fitted creep off.  The fit must keep creep, fit the training record
    # better than Gamma alone, and predict another trajectory (the diagnostic
    # excitation, a new noise draw) better than Gamma alone.  Seeds chosen before the run.
    cfg = ActuatorConfig(noise_std_m=1e-8, coercive_current_a=0.345, coercive_spread_a=0.067,
                         interaction_spread_a=0.517, reversible_fraction=0.098,
                         map_knee=0.510, creep_gain=0.085, creep_time_constant_min_s=0.041,
                         creep_time_constant_max_s=14.8, creep_lag_count=3)
    t, x = identification_excitation(60.0, sample_rate=1000.0, burst_frequency=40.0,
                                     hold_duration=5.0, seed=11)
    y = MagnetostrictiveActuator(cfg, seed=1).simulate(t, x)
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=12)
    yv = MagnetostrictiveActuator(cfg, seed=2).simulate(tv, xv)
    order = (12, 6)
    design, w_h, w_s_inv, _, constant, _ = identify_weights(x, y, *order)
    base = design.model(w_h, w_s_inv, constant)
    model = fit_creep(t, x, y, order=order)
    assert np.any(model.weights > 0.0)
    keep = np.arange(t.size) >= design.burn_in
    assert _mse(model.simulate(t, x), y, keep) < 0.5 * _mse(base.simulate(x), y, keep)
    later = tv > 2.0
    assert _mse(model.simulate(tv, xv), yv, later) < _mse(base.simulate(xv), yv, later)
    # Its record start is the record's: simulated from it, the fit follows the whole record,
    # the samples before the burn-in included, better than identify's Gamma with its own
    # estimated start (fitted from the design's default start, the slow lags carried that
    # start's error through the record: 6.4x identify's RMS error here, 0.5x now).
    whole = np.ones(t.size, dtype=bool)
    plain = identify(x, y, n=order[0], l=order[1]).model
    assert _mse(model.simulate(t, x), y, whole) < _mse(plain.simulate(x), y, whole)


def test_creep_is_not_named_for_a_lag_on_a_record_without_holds():
    # Issue 24: a 20 s record of a plant with a 5 ms eddy-current lag and no creep, no
    # holds long enough for the creep signature (the decision on the gain alone;
    # test_report_agrees' synthetic plant, seed 3).  A creep bank reaching down to 10 ms,
    # fitted on the output error, took the lag on its 30-90 ms lags and was named creep
    # (+15 %, z 6.5).  Creep faster than the lag search's range is the input stages'.
    t, x = identification_excitation(20.0, sample_rate=1000.0, seed=3)
    y = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=2e-8, eddy_time_constant_s=0.005),
                                 seed=3).simulate(t, x)
    _, longest = lag_search_limits(t)
    assert creep_time_constants(t)[0] >= longest
    report = diagnose(Recording(t, x, y, source='lag'), order=(8, 4),
                      causes=('creep', 'rate_dependence'))
    assert report.cause != 'creep', report.decision.steps
    creep = next(c for c in report.candidates if c.cause == 'creep')
    assert not creep.significant


# -- a value between the smallest trial and the next is refined, not pinned -------------------

@pytest.mark.parametrize('fit, effect, value', [
    (fit_dead_time, 'dead_time_s', 0.007),              # 1.4 samples; trials 5, 10.6 ms
    (fit_rate_dependence, 'eddy_time_constant_s', 0.004),   # trials 2.5, 5.8 ms
])
def test_a_value_just_above_the_smallest_trial_is_refined(fit, effect, value):
    # Issue 24: the smallest trial (one sample for a delay, half for a lag) is a physical
    # limit, not a bound; a value between it and the next trial won there and was returned
    # unrefined: a 1.83 ms dead time on a 1 kHz sweep plant was fitted as 1 ms (validation
    # gain 0.12, 0.21 at the true value); here 7 ms and 4 ms came back as 5 and 2.5 ms.
    t, x, y = _record(**{effect: value})
    model = fit(t, x, y, order=ORDER)
    fitted = model.dead_time if fit is fit_dead_time else model.time_constant
    assert fitted == pytest.approx(value, rel=0.1)
    assert not model.not_identified


# -- a parameter at a bound of its search range is not identified ---------------------------

def test_a_lag_far_beyond_the_search_range_is_not_identified():
    t, x, y = _record(eddy_time_constant_s=1.5)         # the longest trial is 1 s
    model = fit_rate_dependence(t, x, y, order=ORDER)
    _, longest = lag_search_limits(t)
    assert model.time_constant == pytest.approx(longest)
    assert 'upper bound' in model.not_identified[RATE_TIME_CONSTANT]


def test_a_dead_time_far_beyond_the_search_range_is_not_identified():
    t, x, y = _record(dead_time_s=3.0)                  # the longest trial is 1 s
    model = fit_dead_time(t, x, y, order=ORDER)
    _, longest = lag_search_limits(t)
    assert model.dead_time == pytest.approx(longest)
    assert 'upper bound' in model.not_identified[DEAD_TIME]


def test_a_thermal_time_constant_far_beyond_the_search_range_is_not_identified():
    # 5000 s on a 30 s record (the longest trial is five records, 150 s).
    t, x, y = _record(thermal_gain_m_per_a2=3e-4, thermal_time_constant_s=5000.0)
    model = fit_thermal_drift(t, x, y, order=ORDER)
    assert model.gain != 0.0 and model.weight == 0.0      # the drift on the displacement
    assert model.time_constant == pytest.approx(5.0 * (t[-1] - t[0]))
    assert 'upper bound' in model.not_identified[THERMAL_TIME_CONSTANT]


def test_creep_far_slower_than_the_record_is_not_identified():
    # Creep lags of 3000-10000 s on a 30 s record (the bank ends at 60 s).
    t, x, y = _record(creep_gain=10.0, creep_time_constant_min_s=3000.0,
                      creep_time_constant_max_s=1e4, creep_lag_count=2)
    model = fit_creep(t, x, y, order=ORDER)
    assert np.any(model.weights > 0.0)
    assert 'not identified' in unidentified_parameters(model)[CREEP_TIME_CONSTANTS]


def test_the_diagnosis_reports_a_bound_as_not_identified_never_as_a_value():
    slow = {'thermal_gain_m_per_a2': 3e-4, 'thermal_time_constant_s': 5000.0}
    t, x, y = _record(**slow)
    tv, xv = identification_excitation(DURATION, sample_rate=RATE, seed=4, burst_frequency=5.0,
                                       hold_duration=3.0)
    plant = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=2e-8, **slow), seed=2)
    yv = plant.simulate(tv, xv)
    report = diagnose(Recording(t, x, y, source='slow thermal'), order=ORDER,
                      validation=Recording(tv, xv, yv, source='validation'),
                      causes=('thermal_drift',))
    form = report.to_json()
    candidate = form['candidates'][0]
    assert THERMAL_TIME_CONSTANT in candidate['not_identified']
    assert THERMAL_TIME_CONSTANT not in candidate['parameters']
    if report.cause == 'thermal_drift':
        assert THERMAL_TIME_CONSTANT in form['extended']['not_identified']
        assert THERMAL_TIME_CONSTANT not in form['extended']['parameters']
        assert f'{THERMAL_TIME_CONSTANT} not identified' in report.evidence


# -- the discrete Preisach core -----------------------------------------------------------------

def test_the_discrete_preisach_core_is_hysteretic_streams_and_starts_at_rest():
    core = random_preisach_core(5)
    t = np.arange(2000) / 100.0
    x = 1.0 + 0.8 * np.sin(2 * np.pi * 0.25 * t) * np.minimum(t / 4.0, 1.0)
    plant = MagnetostrictiveActuator(ActuatorConfig(creep_gain=0.05), core=core)
    whole = plant.simulate(t, x)
    plant.reset()
    chunks = np.concatenate([plant.advance(t[:777], x[:777]), plant.advance(t[777:], x[777:])])
    assert np.array_equal(whole, chunks)
    assert not core.start().any()            # at rest every relay is down
    # Rising and falling through 1 A on the last loop give different outputs (hysteresis).
    last = slice(1600, 2000)
    near = np.flatnonzero(np.abs(x[last] - 1.0) < 0.02)
    rising = np.gradient(x[last])[near] > 0
    assert rising.any() and (~rising).any()
    gap = np.mean(whole[last][near][~rising]) - np.mean(whole[last][near][rising])
    assert gap > 0.02 * np.ptp(whole)


# -- the record's start: a material fit simulates its own record from the first sample ------

def test_a_thermal_fit_carries_the_record_start_it_was_fitted_on():
    """
    A record that starts after an unrecorded sweep: the thermal fit's record start.

    The fit's burn-in left the plays at the design's default (at rest at the first input,
    no memory), which is not where this record starts; simulated from its first sample
    (what ``simulate --start record`` and a compensator started from the record do) the
    fit missed its own first 3 s by 10.5 % of the range RMS (on a wide-sweep plant by
    1.06 um on average over 5 s).  Its start is now estimated as ``identify`` estimates
    one (2.9 % here: the rest is the weights of the plays only the burn-in shows, which
    the fit leaves out; ``identify``'s model, fitted on them too, 0.5 %).
    """
    from mpi_ros.identification.start_states import with_initial_states
    t, x = _input()
    top = float(np.max(x))
    up, down = np.linspace(x[0], top, int(RATE)), np.linspace(top, x[0], int(RATE))
    history = np.concatenate([up, down])
    whole = np.concatenate([history, x])
    plant = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=2e-8, thermal_gain_m_per_a2=1e-6,
                                                    thermal_time_constant_s=10.0), seed=1)
    y = plant.simulate(np.arange(whole.size) / RATE, whole)[history.size:]
    model = fit_thermal_drift(t, x, y, order=ORDER)
    gamma = model.model
    default = with_initial_states(model, np.full(gamma.hysteresis.thresholds.size,
                                                 float(x[0]) - gamma.input_offset))
    first = t < t[0] + 3.0

    def rms(m):
        e = (m.simulate(t, x) - y)[first]
        return float(np.sqrt(np.mean(e * e)))
    assert rms(model) < 0.5 * rms(default)


@pytest.mark.parametrize('preisach_seed', [None, 2, 3, 4])
def test_a_drift_the_holds_do_not_show_is_fitted_off(preisach_seed):
    """
    A plant without thermal drift: the drift fitted beside Gamma must explain the holds.

    Beside Gamma's misfit a drift column wins on held-out blocks (the misfit follows the
    excitation, and so does the lagged power): without the hold check the fit kept a drift
    on all four of these records (built-in core: tau_T 2.7 s, k_T -0.01 um/A^2; Preisach
    cores 2, 3, 4: 32 s, 0.17; 18 s, 0.18; 27 s, -0.56 um/A^2), whose changes during the
    record's holds, where Gamma stands still, are further from the measured ones than no
    drift (Preisach 4: 36 nm RMS against 20 nm).
    """
    core = None if preisach_seed is None else random_preisach_core(preisach_seed, relays=2000)
    t, x, y = _record(core)
    model = fit_thermal_drift(t, x, y, order=ORDER)
    assert model.gain == 0.0 and model.weight == 0.0
    assert 'holds of the record' in model.not_identified[THERMAL_TIME_CONSTANT]


@pytest.mark.parametrize(('preisach_seed', 'gain', 'tau'), [
    (2, 1.0e-6, 8.0), (3, 0.6e-6, 25.0), (4, 1.0e-6, 8.0), (5, 0.6e-6, 25.0)])
def test_the_drift_is_measured_in_the_holds_where_gamma_stands_still(preisach_seed, gain, tau):
    """
    On a Preisach core Gamma misses the output; in the record's holds it stands still.

    Fitted beside Gamma, the drift column took part of Gamma's misfit, which follows the
    excitation as the lagged power does, and the held-out blocks share that misfit: on
    these four records ``k_T`` came out 1.27x, 1.42x, 0.68x and 4.2x the plant's and
    ``tau_T`` 1.56x, 1.08x, 0.48x and 6.0x (the last at the upper bound).  Each hold,
    predicted by the drift fitted on the other holds, measures both within 20 %.
    """
    core = random_preisach_core(preisach_seed, relays=2000)
    t, x, y = _record(core, thermal_gain_m_per_a2=gain, thermal_time_constant_s=tau)
    model = fit_thermal_drift(t, x, y, order=ORDER)
    assert not model.not_identified, model.not_identified
    assert 0.8 < model.gain / gain < 1.25, model.gain
    assert 0.8 < model.time_constant / tau < 1.25, model.time_constant


@pytest.mark.parametrize('preisach', [False, True])
def test_the_thermal_fit_finds_the_drift_on_the_displacement(preisach):
    # The plant adds k_T T to the displacement (1.5 um/A^2, tau 10 s); the fit puts it
    # there (w_T 0) with about the plant's gain, on the built-in core and on a Preisach
    # core whose output map bends more (the wide sweep's misses of issue 24).
    core = random_preisach_core(3, relays=2000) if preisach else None
    t, x, y = _record(core, thermal_gain_m_per_a2=1.5e-6, thermal_time_constant_s=10.0)
    model = fit_thermal_drift(t, x, y, order=ORDER)
    assert model.weight == 0.0 and not model.not_identified
    assert 0.75 * 1.5e-6 < model.gain < 1.33 * 1.5e-6, model.gain
