# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The interface of a physical effect, and the registry that finds every effect.

One module per effect (the built-in ones are registered in :mod:`mpi_ros.extensions`)
owns everything about it and describes it by one :class:`Effect`:

- its parameter keys, their units and the values that switch it off
  (:class:`EffectParameter`; the compensator node declares them from here);
- its extended model class: ``from_params``, ``to_params``, ``simulate(time, current)``,
  the Gamma it extends (``.model``) and, when the effect can be inverted causally,
  ``inverse_step()``, the exact per-step inverse :class:`~mpi_ros.compensation.Compensator`
  plugs in;
- its fit (``fit(time, current, displacement, order=(n, l))``) and free-parameter count;
- its diagnosis signature (a verdict from the residual signatures), the evidence sentence,
  the report plot and its caption, and what separates it from another effect that a record
  ties with it;
- its step in the simulated plant (:class:`PlantEffect`, optional): the ``actuator.*``
  parameters with defaults, units and ranges (:class:`PlantParameter`), how its state starts
  and a vectorised pass over a chunk of samples, at its place in the plant's signal chain
  (input side: on the current the material sees; output side: on the displacement).
  :class:`mpi_ros.plant.actuator.MagnetostrictiveActuator` composes the passes of the registered
  effects around its compiled hysteresis core, and the plant simulator node declares their
  parameters.

:func:`register_effect` adds an effect to :data:`EFFECTS`; the built-in ones are registered
in :mod:`mpi_ros.extensions` (one line each).  The identification, the compensators, the
diagnosis, its report, the compensator node's parameters and the simulated plant all read
the registry, never a list of names.  Adding an effect is one new module and one registry
line (docs/design.md).
"""

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, cast, ClassVar, NamedTuple, Protocol

import numpy as np
import numpy.typing as npt

from ..errors import ModelError
from ..operators.model import MPIModel

__all__ = ['Effect', 'EffectModel', 'EffectParameter', 'ExtendedModelBase', 'EFFECTS',
           'register_effect', 'unregister_effect', 'effect_keys', 'effect_off_values',
           'effects_present', 'FAST_TIME_LIMIT', 'SLOW_TIME_LIMIT', 'PlantChunk', 'PlantEffect',
           'PlantParameter', 'PLANT_STAGES', 'EFFECT_STAGES', 'plant_effects', 'plant_switch',
           'unidentified_parameters', 'SIGNATURE_TESTS', 'separating_measurement',
           'effect_caption', 'key_words']

FloatArray = npt.NDArray[np.float64]

#: The places of a plant step in the signal chain, in order: ``'input'`` acts on the
#: current the material sees (before the compiled hysteresis core), ``'output'`` on the
#: displacement (after it, before the sensor zero and the sensor noise).
PLANT_STAGES = ('input', 'output')

#: The places of an effect's model in the signal chain, in order (:attr:`Effect.stage`).
EFFECT_STAGES = ('input', 'material', 'output')

#: What part of the diagnostic excitation shows an effect (:attr:`Effect.signature_test`).
SIGNATURE_TESTS = ('', 'hold', 'burst')

#: Longest dead time or rate lag [s] plausible for a smart-material actuator: amplifier,
#: sensor and eddy-current delays are microseconds to milliseconds.  A fitted value above it
#: most often means a time column in ms (or us) read as s.
FAST_TIME_LIMIT = 1.0
#: Longest creep or thermal time constant [s] plausible for one actuator record (about
#: 3 h); creep and coil heating settle within minutes to an hour.
SLOW_TIME_LIMIT = 1.0e4


class EffectModel(Protocol):
    """
    The extended model of an effect: Gamma plus the effect, with its parameter form.

    An effect that can be inverted causally also has ``inverse_step()``, the exact
    per-step inverse :class:`~mpi_ros.compensation.Compensator` plugs in (see
    :func:`mpi_ros.compensation.inverse_step_of`).

    """

    @property
    def model(self) -> MPIModel:
        """Return the Gamma the effect extends."""

    @property
    def cause(self) -> str:
        """Return the effect's name, as in :attr:`Effect.name`."""

    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'EffectModel':
        """Build the model from flat parameters (Gamma's ``model.*`` plus the effect's)."""

    def to_params(self) -> dict[str, Any]:
        """Return the flat parameter form that :meth:`from_params` reads."""

    def simulate(self, time: npt.ArrayLike,
                 current: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Return the output [m] for a current [A] sampled at ``time`` [s]."""


class ExtendedModelBase:
    """
    The :class:`~mpi_ros.operators.model.ActuatorModel` interface of an extended model.

    An effect's model class (a frozen dataclass whose field ``model`` is its Gamma) derives
    from it and defines ``simulate(time, current)``; an effect that can be inverted causally
    also overrides :meth:`inverse_step`.
    """

    model: MPIModel
    #: The response of an effect depends on the sample times.
    timed: ClassVar[bool] = True

    @property
    def gamma(self) -> MPIModel:
        """Return the (forward) Gamma the effect extends."""
        return self.model.gamma

    def simulate(self, time: npt.ArrayLike, current: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Return the output [m] for a current [A] sampled at ``time`` [s]."""
        raise NotImplementedError

    def response(self, time: npt.ArrayLike, current: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Return :meth:`simulate` (the interface's name for it)."""
        return self.simulate(time, current)

    def inverse_step(self) -> Any:
        """Return None: the effect has no causal inverse (a dead time needs the future)."""
        return None

    def with_gamma(self, gamma: MPIModel) -> Any:
        """Return the same model around another Gamma (e.g. another start state)."""
        return replace(cast(Any, self), model=gamma)


def key_words(key: str) -> str:
    """
    Return a parameter key's last part in words.

    Examples
    --------
    >>> key_words('model.resonance.initial_deflection')
    'initial deflection'

    """
    return key.rsplit('.', 1)[-1].replace('_', ' ')


@dataclass(frozen=True)
class EffectParameter:
    """
    One parameter key of an effect.

    Attributes
    ----------
    key : str
        Parameter name, e.g. ``model.creep.weights``.
    kind : {'double', 'double_array'}
        Its type.
    off : float or tuple of float
        The value that switches the effect off (0.0, or an empty tuple).
    description : str
        What it is, shown by ``ros2 param describe``.
    unit : str
        SI unit, empty when dimensionless.
    value_range : (float, float) or None
        Inclusive range of a double.
    plausible_max : float or None
        Largest value (of any element) plausible for a smart-material actuator, in
        `unit`; the diagnosis warns about a fitted value above it (for a time constant,
        a time base in ms or us read as s).  None: no such bound.
    name : str
        Its name in a report's words, e.g. ``displacement coefficient k_T``; empty: the
        key's last part (:attr:`words`).

    """

    key: str
    kind: str
    off: float | tuple[float, ...]
    description: str
    unit: str = ''
    value_range: tuple[float, float] | None = None
    plausible_max: float | None = None
    name: str = ''

    @property
    def words(self) -> str:
        """Return :attr:`name`, or else the key's last part with spaces: ``time constant``."""
        return self.name or key_words(self.key)


@dataclass(frozen=True)
class PlantParameter:
    """
    One parameter of the simulated plant (an ``ActuatorConfig`` field).

    Attributes
    ----------
    name : str
        Field name, e.g. ``creep_gain``; the plant simulator node's parameter is
        ``actuator.<name>``.
    default : float or int
        Default value; an int makes an integer parameter.
    description : str
        What it is (one line; the unit is appended from `unit`).
    unit : str
        SI unit, ``'1'`` when dimensionless, empty for a count.
    low, high : float or None
        Bounds of the value (None: unbounded on that side).
    low_open, high_open : bool
        Whether the bound itself is excluded.
    note : str
        Added to the "must be" message, e.g. ``'(0 switches it off)'``.
    switch : bool
        A value other than 0 switches the effect on (the effect runs only then).

    """

    name: str
    default: float | int
    description: str
    unit: str = ''
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    note: str = ''
    switch: bool = False

    @property
    def text(self) -> str:
        """Return the description with its unit, for parameter descriptors."""
        return f'{self.description} [{self.unit}]' if self.unit else self.description

    @property
    def expected(self) -> str:
        """Return what a valid value is, in words (``'>= 0'``, ``'in [1, 100]'``)."""
        if self.low is not None and self.high is not None:
            text = (f'in {"(" if self.low_open else "["}{self.low:g}, {self.high:g}'
                    f'{")" if self.high_open else "]"}')
        elif self.low is not None:
            text = f'{">" if self.low_open else ">="} {self.low:g}'
        elif self.high is not None:
            text = f'{"<" if self.high_open else "<="} {self.high:g}'
        else:
            text = 'any finite number'
        return f'{text} {self.note}' if self.note else text

    def accepts(self, value: float) -> bool:
        """Tell whether a finite value lies within the bounds."""
        low_ok = (self.low is None or value > self.low
                  or (not self.low_open and value == self.low))
        high_ok = (self.high is None or value < self.high
                   or (not self.high_open and value == self.high))
        return low_ok and high_ok


class PlantChunk(NamedTuple):
    """
    What a plant step sees of a chunk of samples, besides the signal it transforms.

    Attributes
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s], strictly increasing, after the previous chunk's.
    current : ndarray of float, shape (N,)
        Coil current [A] as commanded.
    material : ndarray of float, shape (N,), or None
        Output side only: the hysteresis core's displacement [m] before any output-side
        step (what creep relaxes towards); None on the input side.

    """

    time: FloatArray
    current: FloatArray
    material: FloatArray | None = None


@dataclass(frozen=True)
class PlantEffect:
    """
    An effect's step in the simulated plant (the ``MagnetostrictiveActuator``).

    Attributes
    ----------
    stage : {'input', 'output'}
        Its place in the signal chain (:data:`PLANT_STAGES`): ``'input'`` transforms the
        current [A] the material sees (eddy-current lag); ``'output'`` transforms the
        displacement [m] after the hysteresis core (creep, thermal expansion, dead time).
        Within a stage the steps run in the order of registration.
    parameters : tuple of PlantParameter
        Its ``actuator.*`` parameters; at least one is a switch.
    start : callable
        ``start(values)`` -> a fresh state at rest (called at construction and on every
        reset); ``values`` maps every actuator parameter name to its value.
    run : callable
        ``run(state, chunk, signal)`` -> the transformed signal, a new array of shape (N,):
        a vectorised pass over the chunk (:class:`PlantChunk`) that advances ``state`` in
        place, so that chunked runs equal one run.  It leaves ``chunk`` and ``signal``
        unchanged.
    label : str
        The effect in words for logs (``'eddy-current lag'``).
    check : callable or None
        ``check(values)`` -> None, or ``(name, expected)`` for a value that is wrong given
        the others (e.g. a range whose end lies below its start).

    """

    stage: str
    parameters: tuple[PlantParameter, ...]
    start: Callable[[Mapping[str, Any]], Any]
    run: Callable[[Any, PlantChunk, FloatArray], FloatArray]
    label: str
    check: Callable[[Mapping[str, Any]], 'tuple[str, str] | None'] | None = None

    def __post_init__(self) -> None:
        """Check the stage and that some parameter switches the effect on."""
        if self.stage not in PLANT_STAGES:
            msg = (f'plant effect {self.label!r}: stage must be one of {PLANT_STAGES};'
                   f' found {self.stage!r}')
            raise ModelError(msg)
        if not any(p.switch for p in self.parameters):
            msg = (f'plant effect {self.label!r}: no parameter is a switch; mark the one'
                   ' whose 0 switches the effect off with switch=True')
            raise ModelError(msg)

    @property
    def switch(self) -> PlantParameter:
        """Return the (first) parameter whose 0 switches the effect off."""
        return next(p for p in self.parameters if p.switch)

    def is_on(self, values: Mapping[str, Any]) -> bool:
        """Tell whether a switch parameter is not 0 (missing ones count as their default)."""
        return any(values.get(p.name, p.default) != 0 for p in self.parameters if p.switch)


@dataclass(frozen=True)
class Effect:
    """
    Everything about one physical effect, for the registry.

    Attributes
    ----------
    name : str
        The cause's name (``creep``): the diagnosis verdict, the compensator's ``kind``.
    formula : str
        The extended model in words (docs, reports).
    parameters : tuple of EffectParameter
        Its parameter keys (besides Gamma's).
    model_class : type of EffectModel
        The extended model: ``from_params(mapping)``, ``to_params()``, ``simulate(time,
        current)``, ``model`` (Gamma), ``cause``; ``inverse_step()`` when invertible.
    fit : callable
        ``fit(time, current, displacement, *, order)`` -> extended model.
    parameter_count : callable
        Free parameters of a fitted model's parameter form (for the diagnosis).
    signature : callable
        ``signature(residual, level)`` -> ``'present'``, ``'absent'`` or ``'unavailable'``:
        whether the residual of Gamma shows the effect's physical signature (``residual``
        holds ``hold_signature`` and ``burst_signature``, see :mod:`mpi_ros.diagnosis`).
    evidence : callable
        ``evidence(residual)`` -> the sentence that names the physical evidence, or None.
    plot : callable or None
        ``plot(ax, time, current, measured, baseline, extended, start)`` draws the
        effect's signature plot on a matplotlib axes (for the report).
    stage : {'material', 'input', 'output'}
        Where the effect acts in the actuator's signal chain: ``'input'`` changes the
        current the material sees (its model has ``input_signal(time, current)``);
        ``'material'`` acts in or after the hysteresis; ``'output'`` is a linear stage on
        the displacement after everything else (a mechanical mode; its model has
        ``output_signal(time, displacement)``).  Effects combine along the chain
        (:mod:`mpi_ros.extensions.composite`): any input stages, at most one material effect,
        any output stages.
    plant : PlantEffect or None
        Its step in the simulated plant; None when the plant cannot show the effect.
    caption : str
        The caption of its signature plot in the diagnosis report, one sentence ('': a
        general one naming the effect).
    signature_test : {'', 'hold', 'burst'}
        Which part of the diagnostic excitation shows its signature: ``'hold'`` (the
        residual keeps moving while the input holds), ``'burst'`` (bursts at several
        rates; silent during a hold), '' (neither).  The diagnosis says from it what
        separates tied causes.
    separations : Mapping of str to str
        Another effect's name -> the measurement that separates the two when a record ties
        them (given on one of the two; read both ways by
        :func:`separating_measurement`).
    dynamics_finding : str
        The kind of the dynamics finding of :func:`mpi_ros.identify` that this effect is
        (``'lag'``, ``'dead_time'``; '' for none): the diagnosis' verdict on such an
        effect never contradicts that finding.

    """

    name: str
    formula: str
    parameters: tuple[EffectParameter, ...]
    model_class: type[EffectModel]
    fit: Callable[..., Any]
    parameter_count: Callable[[Mapping[str, Any]], int]
    signature: Callable[[Mapping[str, Any], float], str] = field(
        default=lambda residual, level: 'unavailable')
    evidence: Callable[[Mapping[str, Any]], 'str | None'] = field(
        default=lambda residual: None)
    plot: Callable[..., None] | None = None
    stage: str = 'material'
    plant: PlantEffect | None = None
    caption: str = ''
    signature_test: str = ''
    separations: Mapping[str, str] = field(default_factory=dict)
    dynamics_finding: str = ''

    def __post_init__(self) -> None:
        """Check the stage and the signature test."""
        if self.stage not in EFFECT_STAGES:
            msg = (f'effect {self.name!r}: stage must be one of {", ".join(EFFECT_STAGES)},'
                   f' not {self.stage!r}')
            raise ModelError(msg)
        if self.signature_test not in SIGNATURE_TESTS:
            msg = (f'effect {self.name!r}: signature_test must be one of'
                   f' {", ".join(repr(t) for t in SIGNATURE_TESTS)}, not'
                   f' {self.signature_test!r}')
            raise ModelError(msg)

    @property
    def keys(self) -> tuple[str, ...]:
        """Return the effect's parameter keys."""
        return tuple(p.key for p in self.parameters)

    def is_off(self, mapping: Mapping[str, Any]) -> bool:
        """Tell whether every key of the effect is absent, None or at its "off" value."""
        return all(_is_off(mapping.get(p.key)) for p in self.parameters)


#: The registry: effect name -> :class:`Effect` (built-ins registered by mpi_ros.extensions).
EFFECTS: dict[str, Effect] = {}


def register_effect(effect: Effect) -> Effect:
    """
    Add an effect to :data:`EFFECTS`.

    Parameters
    ----------
    effect : Effect
        The effect; its name and keys must be new.

    Returns
    -------
    Effect
        The same effect.

    Raises
    ------
    ModelError
        When the name, a key or a plant parameter name is taken already.

    """
    if effect.name in EFFECTS:
        msg = f'an effect named {effect.name!r} is registered already'
        raise ModelError(msg)
    missing = [name for name in ('gamma', 'response', 'inverse_step', 'with_gamma', 'timed')
               if not hasattr(effect.model_class, name)]
    if missing:
        msg = (f'effect {effect.name!r}: its model class {effect.model_class.__name__} lacks'
               f' {", ".join(missing)} of the model interface'
               ' (mpi_ros.operators.model.ActuatorModel);'
               ' derive it from mpi_ros.extensions.ExtendedModelBase')
        raise ModelError(msg)
    taken = set(effect_keys())
    clash = [key for key in effect.keys if key in taken]
    if clash:
        msg = f'effect {effect.name!r}: parameter keys {clash} belong to another effect'
        raise ModelError(msg)
    if effect.plant is not None:
        names = {p.name for _, other in plant_effects() for p in other.parameters}
        clash = [p.name for p in effect.plant.parameters if p.name in names]
        if clash:
            msg = (f'effect {effect.name!r}: plant parameters {clash} belong to another'
                   ' effect; give them names of their own')
            raise ModelError(msg)
    EFFECTS[effect.name] = effect
    return effect


def unregister_effect(name: str) -> None:
    """Remove an effect from :data:`EFFECTS` (tests and plug-in hosts)."""
    EFFECTS.pop(name, None)


def effect_keys() -> tuple[str, ...]:
    """Return every registered effect's parameter keys."""
    return tuple(key for effect in EFFECTS.values() for key in effect.keys)


def effect_off_values() -> dict[str, Any]:
    """Return each effect key's "off" value (a list for arrays, a float otherwise)."""
    return {p.key: list(p.off) if isinstance(p.off, tuple) else p.off
            for effect in EFFECTS.values() for p in effect.parameters}


def effects_present(mapping: Mapping[str, Any]) -> list[Effect]:
    """Return the effects some of whose keys the mapping holds."""
    return [effect for effect in EFFECTS.values() if any(k in mapping for k in effect.keys)]


def plant_effects() -> list[tuple[str, PlantEffect]]:
    """
    Return the plant steps of the registered effects, in signal-chain order.

    Returns
    -------
    list of (str, PlantEffect)
        Effect name and its plant step: input-side steps first, then output-side ones;
        within a stage in the order of registration.

    """
    chain = [(e.name, e.plant) for e in EFFECTS.values() if e.plant is not None]
    return sorted(chain, key=lambda item: PLANT_STAGES.index(item[1].stage))


def plant_switch(name: str) -> str:
    """
    Return the actuator parameter that switches an effect on in the simulated plant.

    Parameters
    ----------
    name : str
        A registered effect's name (``'creep'``).

    Returns
    -------
    str
        The field of :class:`mpi_ros.plant.actuator.ActuatorConfig` (``'creep_gain'``); the plant
        simulator node's parameter is ``actuator.<field>``.

    Raises
    ------
    ModelError
        When no effect of that name with a plant step is registered.

    Examples
    --------
    >>> plant_switch('rate_dependence')
    'eddy_time_constant_s'

    """
    effect = EFFECTS.get(name)
    if effect is None or effect.plant is None:
        known = ', '.join(n for n, _ in plant_effects())
        msg = (f'no registered effect {name!r} with a plant step; the plant simulates: {known};'
               ' register the effect with plant=PlantEffect(...)')
        raise ModelError(msg)
    return effect.plant.switch.name


def separating_measurement(causes: Sequence[str]) -> str:
    """
    Say what measurement separates causes that a record ties, from the registered effects.

    Each pair of causes with a text (:attr:`Effect.separations`, given on either effect)
    contributes it; causes whose signature shows in holds beside causes whose signature
    shows in bursts (:attr:`Effect.signature_test`) get a hold; else the general answer
    names every registered effect by the part of the excitation that shows it.

    Parameters
    ----------
    causes : sequence of str
        The tied causes (effect names; unknown names are ignored).

    Returns
    -------
    str
        One clause, or several joined by ``'; '``.

    Examples
    --------
    >>> separating_measurement(['creep', 'dead_time'])[:40]
    'a hold separates creep (the residual kee'

    """
    known = [c for c in causes if c in EFFECTS]
    said = []
    for k, a in enumerate(known):
        for b in known[k + 1:]:
            text = EFFECTS[a].separations.get(b) or EFFECTS[b].separations.get(a)
            if text:
                said.append(text)
    held = [c for c in known if EFFECTS[c].signature_test == 'hold']
    burst = [c for c in known if EFFECTS[c].signature_test == 'burst']
    if held and burst:
        said.append(f'a hold separates {" and ".join(_words(held))} (the residual keeps moving'
                    f' while the input holds) from {" and ".join(_words(burst))} (silent during'
                    ' a hold)')
    if said:
        return '; '.join(said)
    every = {test: [name for name, e in EFFECTS.items() if e.signature_test == test]
             for test in ('hold', 'burst')}
    return (f'holds ({", ".join(_words(every["hold"]))}) and bursts at several rates'
            f' ({", ".join(_words(every["burst"]))})')


def effect_caption(name: str) -> str:
    """
    Return the report's caption of an effect's signature plot (:attr:`Effect.caption`).

    Parameters
    ----------
    name : str
        The effect's name (or a pair's, joined by ``' + '``).

    Returns
    -------
    str
        Its caption; a general one for an effect without one, or an unknown name.

    """
    effect = EFFECTS.get(name)
    if effect is not None and effect.caption:
        return effect.caption
    return (f'The {name.replace("_", " ")} candidate against the measured output, validation'
            ' data.')


def unidentified_parameters(model: Any) -> dict[str, str]:
    """
    Return the parameters of a fitted model that its fit could not identify.

    A fit whose best value of a parameter lies at a bound of its search range (a time
    constant at the longest or shortest trial) has not found the parameter, only that it lies
    beyond that bound; the model keeps the bound's value to run, but reports must say "not
    identified" instead of stating it as physics.  An effect's model holds them in its
    ``not_identified`` field (key -> the reason); a composite model gathers its parts'.

    Parameters
    ----------
    model : object
        A fitted extended model (or a plain Gamma, which has none).

    Returns
    -------
    dict of str to str
        Parameter key -> why it is not identified (empty when every one is).

    """
    out: dict[str, str] = {}
    for part in getattr(model, 'parts', ()) or ():
        out.update(unidentified_parameters(part))
    out.update(dict(getattr(model, 'not_identified', None) or {}))
    return out


def _words(names: Sequence[str]) -> list[str]:
    return [name.replace('_', ' ') for name in names]


def _is_off(value: Any) -> bool:
    if value is None:
        return True
    if isinstance(value, (int, float)):
        return value == 0.0
    return len(value) == 0
