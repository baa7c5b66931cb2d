# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Physically motivated extensions of the MPI model, one module per cause.

The built-in effects (the registry :data:`EFFECTS` is the list; ``Effect.formula`` and
``Effect.keys`` say the same for any registered effect):

=====================  =============================================  ===========================
cause                  model                                          extra parameter keys
=====================  =============================================  ===========================
``creep``              ``y0 + sign (G + sum_j w_Cj C_j[G])``,         ``model.creep.*``
                       ``G = S[H[u]]``
``rate_dependence``    ``Gamma[L_tau_e[x]]``                          ``model.rate_dependence.*``
``thermal_drift``      ``y0 + sign S[H[u] + w_T L_tau_T[x^2]]``       ``model.thermal_drift.*``
``dead_time``          ``Gamma[x](t - L)``                            ``model.dead_time``
``resonance``          ``R_(f, T)[Gamma[x]]`` (an output mode)         ``model.resonance.*``
=====================  =============================================  ===========================

``u = x - x0``; Gamma carries the operating point (``model.input_offset`` ``x0``,
``model.output_offset`` ``y0``, ``model.output_sign``), and every extended model keeps it
in ``simulate`` and in its parameter form.  The fits use
:func:`mpi_ros.model_fit.identify`'s design (operating point, detected sign, constant
term, burn-in), so an extension is fitted on the same samples as the plain model; with
``order='auto'`` a fit selects Gamma's order again on the effect-free signals.

Every module owns everything about its effect and describes it by one
:class:`~mpi_ros.extensions.effect.Effect` (parameter keys and "off" values, model class,
fit, exact per-step inverse, diagnosis signature, evidence, report plot); they are found
through one registry, :data:`EFFECTS`, filled below (one line per effect).  Every model has
``simulate(time, current)``, ``to_params()``, ``from_params(mapping)`` and a ``cause``
name; :func:`extended_model_from_params` picks the class from the keys present, and
:func:`start_model` gives a model the start of a new input (:mod:`mpi_ros.operators.start`).
"""

from collections.abc import Iterator, Mapping
from typing import Any

from . import creep, dead_time, rate_dependence, resonance, thermal_drift
from .composite import CompositeModel, fit_composite
from .creep import creep_time_constants, CreepModel, fit_creep
from .dead_time import DeadTimeModel, fit_dead_time
from .effect import Effect, EffectModel, EffectParameter, EFFECTS, effects_present, \
    ExtendedModelBase, register_effect, unregister_effect
from .rate_dependence import fit_rate_dependence, RateDependentModel
from .resonance import fit_resonance, ResonanceModel
from .thermal_drift import fit_thermal_drift, ThermalDriftModel
from ..operators.model import MPIModel, RECORD_START_STATES
from ..operators.start import StartState

__all__ = ['CreepModel', 'RateDependentModel', 'ThermalDriftModel', 'DeadTimeModel',
           'ResonanceModel', 'CompositeModel', 'ExtendedModel', 'fit_composite', 'fit_creep',
           'fit_rate_dependence', 'fit_thermal_drift', 'fit_dead_time', 'fit_resonance',
           'creep_time_constants',
           'extended_model_from_params', 'start_model', 'EXTENSION_KEYS', 'Effect', 'EffectModel',
           'EffectParameter', 'EFFECTS', 'ExtendedModelBase', 'register_effect',
           'unregister_effect']

#: The type of an extended model: any registered effect's model class (and a composite of
#: several) meets the :class:`EffectModel` protocol, so no list of classes is kept here.
ExtendedModel = EffectModel

# The registry of effects: one line per effect module.
register_effect(creep.EFFECT)
register_effect(rate_dependence.EFFECT)
register_effect(thermal_drift.EFFECT)
register_effect(dead_time.EFFECT)
register_effect(resonance.EFFECT)


class _ExtensionKeys(Mapping[str, tuple[str, ...]]):
    """Effect name -> its parameter keys, read from the registry (effects added later too)."""

    def __getitem__(self, name: str) -> tuple[str, ...]:
        return EFFECTS[name].keys

    def __iter__(self) -> Iterator[str]:
        return iter(EFFECTS)

    def __len__(self) -> int:
        return len(EFFECTS)


#: Parameter keys that mark each extension (used by :func:`extended_model_from_params`).
EXTENSION_KEYS: Mapping[str, tuple[str, ...]] = _ExtensionKeys()


def extended_model_from_params(mapping: Mapping[str, Any]) -> MPIModel | EffectModel:
    """
    Build the model a parameter set describes: Gamma alone, with one effect, or several.

    Parameters
    ----------
    mapping : Mapping[str, Any]
        Flat parameters: Gamma's ``model.*`` keys plus the keys of any effects that chain
        (input stages, at most one material effect, output stages; see
        :mod:`mpi_ros.extensions.composite`).

    Returns
    -------
    MPIModel, one of the extended models, or CompositeModel
        Validated.

    Raises
    ------
    ModelError
        When the effects cannot be chained (two material effects), or a value is invalid.

    """
    present = effects_present(mapping)
    if not present:
        return MPIModel.from_params(mapping)
    if len(present) > 1:
        return CompositeModel.from_params(mapping)
    return present[0].model_class.from_params(mapping)


def start_model(model: Any, start: StartState | str,
                current_range: tuple[float, float] | None,
                unit: str = 'A') -> tuple[Any, float | None, str]:
    """
    Return the model that starts a new input where ``start`` says, its current and the words.

    Parameters
    ----------
    model : MPIModel or extended model
        The model as read (its Gamma's initial states and a mode's deflection are the
        identification record's start).
    start : StartState or str
        ``rest_low``, ``rest_high``, ``record`` or explicit play states.
    current_range : (float, float) or None
        The identified current range [A] (None: unknown; a rest start then keeps the
        record start, and says so).
    unit : str
        The input's unit in the description (``'A'`` or ``'V'``).

    Returns
    -------
    model : the same kind of model
        Its plays start in the chosen states; a mode at rest unless the record's start is
        kept (then with the record's deflection too).
    current : float or None
        The current a rest start rests at [A].
    description : str
        The start in words.

    Raises
    ------
    ModelError
        Explicit states that do not fit the model.

    """
    chosen = StartState.parse(start)
    states, current, description = chosen.plays(model.gamma, current_range, unit=unit)
    params = model.to_params()
    params[RECORD_START_STATES] = [float(v) for v in states]
    if current is not None or chosen.name == 'explicit':
        for key in (resonance.RESONANCE_DEFLECTION, resonance.LEGACY_DEFLECTION):
            if key in params:
                params[key] = 0.0
    return extended_model_from_params(params), current, description
