"""The contract every damper model follows: estimators hold settings, fitted models are values.

* An :class:`Estimator` stores settings only. ``fit(data)`` validates, identifies and returns a
  :class:`FittedModel`; it never mutates the input records.
* A :class:`FittedModel` is a frozen dataclass: parameters, the electrical input it uses
  (``"i"`` or ``"voltage"``), the input range it was identified on, and provenance. It predicts the
  force of any :class:`~mrdamper.data.Experiment` in free run (from the record's x, v and electrical
  input only; the measured force is never fed back), saves to versioned JSON and loads back
  bit-identically.
* Every family's ``predict`` (hence ``simulate`` and ``score``) says in one
  :class:`~mrdamper.errors.Note` when the record leaves the model's training envelope
  (``provenance["envelope"]``, written at fit time; :mod:`mrdamper.models.envelope`), naming the
  dimension and by how much. The check is added to the family's ``predict`` here, once, when its
  class is defined.
"""

from __future__ import annotations

import abc
import contextvars
import dataclasses
import functools
import json
import time
import typing
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, NamedTuple, cast

import numpy as np

from mrdamper._io import atomic_write_text, json_kind
from mrdamper._warn import warn_user
from mrdamper.data import Experiment, ExperimentSet, as_experiment_set
from mrdamper.data.experiment import ElectricalSource
from mrdamper.errors import DataValidationError, Note, SchemaError
from mrdamper.metrics import Scores, score_arrays
from mrdamper.models import _scale, lag
from mrdamper.models._schema import (
    SCHEMA_NAME,
    SCHEMA_VERSION,
    check_header,
    check_model_dict,
    decode_value,
    encode_value,
)
from mrdamper.models._values import Identified, SimulationResult, TrainingData
from mrdamper.models.envelope import envelope_note, envelope_of, training_envelope
from mrdamper.models.input_range import RangePolicy, check_input_range, single_level_note
from mrdamper.models.levels import single_level
from mrdamper.models.settings import (
    check_bool,
    check_choice,
    check_int,
    check_number,
    literal_choices,
    type_hints,
)
from mrdamper.models.step import Step
from mrdamper.progress import report

__all__ = [
    "MIN_PEAK_VELOCITY",
    "MODEL_FILE",
    "SCHEMA_NAME",
    "SCHEMA_VERSION",
    "STEP_VMAX",
    "TIMING_PROVENANCE",
    "Choice",
    "Estimator",
    "FittedModel",
    "Identified",
    "RangePolicy",
    "SimulationResult",
    "TrainingData",
    "check_bool",
    "check_choice",
    "check_input_range",
    "check_int",
    "check_number",
    "decode_value",
    "encode_value",
    "single_level",
    "single_level_note",
]

#: The kind of file :meth:`FittedModel.save` writes (``force`` replaces only such a file).
MODEL_FILE = json_kind("mrdamper model file (JSON)", SCHEMA_NAME)

#: Provenance entries that are wall-clock or CPU times [s]. They stay on the in-memory model but
#: are never written to a model file, so that the same fit gives the same bytes.
TIMING_PROVENANCE: frozenset[str] = frozenset(
    {"elapsed_s", "cpu_s", "fit_seconds", "fit_time_s", "lag_selection_s"}
)

#: Largest damper velocity [m/s] a continuous-time family's per-sample step resolves when no
#: other bound is given (beyond the velocities of a car suspension).
STEP_VMAX = 1.5

#: Smallest peak velocity of a training record [m/s]: below it the record has no motion (a rig at
#: rest records velocity noise only) and the fit is refused.
MIN_PEAK_VELOCITY = 1e-6


# ----------------------------------------------------------------------------- envelope check
#: True while an outer :meth:`Estimator.fit` runs (inner fits of candidates skip its final check).
_IN_FIT: contextvars.ContextVar[bool] = contextvars.ContextVar("_IN_FIT", default=False)
#: True while a ``predict`` that already checked the envelope runs (inner calls do not repeat it).
_IN_PREDICT: contextvars.ContextVar[bool] = contextvars.ContextVar("_IN_PREDICT", default=False)


def _with_envelope_check(predict: Any) -> Any:
    """``predict`` that first says when the record leaves the model's training envelope."""

    @functools.wraps(predict)
    def checked(self: FittedModel, experiment: Experiment) -> np.ndarray:
        if _IN_PREDICT.get():
            return cast(np.ndarray, predict(self, experiment))
        token = _IN_PREDICT.set(True)
        try:
            note = self.envelope_note(experiment)
            if note:
                warn_user(note, Note)
            return cast(np.ndarray, predict(self, experiment))
        finally:
            _IN_PREDICT.reset(token)

    checked.envelope_checked = True  # type: ignore[attr-defined]
    return checked


# ----------------------------------------------------------------------------- base classes
@dataclass(frozen=True)
class FittedModel(abc.ABC):
    """An identified damper model: an immutable value.

    Subclasses are frozen dataclasses (``@dataclass(frozen=True, kw_only=True)``, since the
    common fields below have defaults and come first in the field order) that add their
    parameters as fields, set ``kind`` and implement :meth:`predict`.

    Attributes
    ----------
    input : {"i", "voltage"}
        Electrical input channel the model reads from an Experiment.
    input_range : (float, float)
        Range of that input seen during identification [A] or [V].
    range_policy : {"error", "warn", "clip", "ignore"}
        What :meth:`predict` does when a record leaves ``input_range``.
    provenance : mapping
        Facts about the identification: training record names, settings, cost, time, version.
    sample_time : float or None
        Sampling interval [s] the model was fitted at: a discrete model's own ``1 / fs``, else
        the training records' (the largest when they differ); the default step of the C and FMU
        exports. None for a model built by hand (or read from a file written before it was
        recorded).
    """

    kind: ClassVar[str] = "abstract"

    input: ElectricalSource = "i"
    input_range: tuple[float, float] = (0.0, 0.0)
    range_policy: RangePolicy = "error"
    provenance: Mapping[str, Any] = field(default_factory=dict, compare=False)
    sample_time: float | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "input_range", tuple(float(b) for b in self.input_range))
        if self.sample_time is not None:
            dt = self.sample_time
            if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not 0 < dt < np.inf:
                raise DataValidationError(
                    "sample_time", f"expected a positive interval [s] or None, got {dt!r}"
                )
            object.__setattr__(self, "sample_time", float(dt))

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        own = cls.__dict__.get("predict")
        if (
            own is not None
            and not getattr(own, "__isabstractmethod__", False)
            and not getattr(own, "envelope_checked", False)
        ):
            cls.predict = _with_envelope_check(own)  # type: ignore[method-assign]

    @property
    def envelope(self) -> dict[str, Any] | None:
        """The training envelope (:mod:`mrdamper.models.envelope`) or None (a model saved before
        envelopes were recorded, or built by hand)."""
        env = dict(self.provenance or {}).get("envelope")
        return dict(env) if env else None

    def step_vmax(self, v: np.ndarray | None = None) -> float:
        """Velocity bound [m/s] that sets a continuous-time family's integration sub-steps.

        One rule for :meth:`predict`, the step and its exports: :data:`STEP_VMAX` (beyond a car
        suspension's velocities) or the training records' peak ``|v|`` (the envelope's
        ``v_max``) when larger, raised to the peak of ``v`` when a record faster than that is
        given. The step (:meth:`step`, whose default bound this is; what the C and FMU exports
        and the quarter car run) so integrates exactly the sub-steps of ``predict`` on every
        record at the step's interval within that bound. A model without an envelope (built by
        hand) takes the record's peak ``|v|``, or :data:`STEP_VMAX` without a record.

        Parameters
        ----------
        v : ndarray, optional
            The record's velocity [m/s].
        """
        env = self.envelope
        peak = float(np.max(np.abs(v))) if v is not None and np.size(v) else None
        if not env or env.get("v_max") is None:
            return STEP_VMAX if peak is None else peak
        bound = max(STEP_VMAX, float(env["v_max"]))
        return bound if peak is None else max(bound, peak)

    def envelope_note(self, experiment: Experiment) -> str:
        """One line saying how ``experiment`` leaves the training envelope (velocity,
        displacement, frequency content, electrical input, by how much), or ``""`` when it stays
        inside or the model carries no envelope."""
        env = self.envelope
        if env is None or not isinstance(experiment, Experiment):
            return ""
        try:
            e = experiment.electrical(self.input)
        except Exception:  # noqa: BLE001 - a missing channel is reported by predict itself
            return ""
        seen = envelope_of([experiment.x], [experiment.v], [e], dt=[experiment.dt])
        return envelope_note(self.kind, experiment.name, env, seen)

    # --- to implement -------------------------------------------------------------------
    @abc.abstractmethod
    def predict(self, experiment: Experiment) -> np.ndarray:
        """Free-run force prediction [N] for one record (uses x, v and the electrical input).

        A record outside the training envelope is predicted all the same, with one
        :class:`~mrdamper.errors.Note` saying where it leaves it (:meth:`envelope_note`)."""

    # --- shared behaviour ---------------------------------------------------------------
    def electrical_input(self, experiment: Experiment) -> np.ndarray:
        """The record's electrical input after applying ``range_policy``."""
        return check_input_range(
            experiment.electrical(self.input),
            self.input_range,
            self.range_policy,
            field_name=self.input,
            model=self.kind,
        )

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        """The model as a per-sample step (:mod:`mrdamper.models.step`).

        Every family takes ``dt`` and ``vmax`` (and may add keyword options of its own); the
        default refuses in one line.

        Parameters
        ----------
        dt : float
            Interval [s] the step will mostly be advanced by (continuous-time families choose
            their integration sub-step for it; discrete-time families run at their own rate).
        vmax : float
            Largest damper velocity [m/s] the step must resolve.

        Raises
        ------
        DataValidationError
            The family has no per-sample step.
        """
        raise DataValidationError("model", f"kind {self.kind!r} has no per-sample step")

    def with_range_policy(self, policy: RangePolicy) -> FittedModel:
        """Copy of the model with another out-of-range policy."""
        return dataclasses.replace(self, range_policy=policy)

    def simulate(self, experiment: Experiment) -> SimulationResult:
        """Free-run simulation of ``experiment``, timed, as a :class:`SimulationResult`."""
        t0 = time.perf_counter()
        F = self.predict(experiment)
        return SimulationResult(experiment, F, self.kind, time.perf_counter() - t0)

    def score(self, experiment: Experiment) -> Scores:
        """ESR, SSSE, NRMSE and fit of the free-run prediction of ``experiment``."""
        return score_arrays(experiment.F, self.predict(experiment))

    @property
    def parameters(self) -> dict[str, Any]:
        """Model-specific parameters (every dataclass field except the common ones)."""
        common = {f.name for f in dataclasses.fields(FittedModel)}
        return {
            f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in common
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict with schema name and version (timings of the provenance left out, see
        :data:`TIMING_PROVENANCE`)."""
        return {
            "schema": SCHEMA_NAME,
            "schema_version": SCHEMA_VERSION,
            "kind": self.kind,
            "input": self.input,
            "input_range": list(self.input_range),
            "range_policy": self.range_policy,
            "sample_time": self.sample_time,
            "parameters": encode_value(self.parameters),
            "provenance": encode_value(
                {k: v for k, v in self.provenance.items() if k not in TIMING_PROVENANCE}
            ),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> FittedModel:
        """Rebuild a model saved by :meth:`to_dict` (checks schema, version and kind)."""
        check_header(data)
        if data["kind"] != cls.kind:
            raise SchemaError(f"kind: file holds {data['kind']!r}, expected {cls.kind!r}")
        params = decode_value(data["parameters"], "parameters")
        check_model_dict(cls, params)
        policy = data.get("range_policy", "error")
        if policy not in typing.get_args(RangePolicy):
            raise SchemaError(
                f"range_policy: expected one of {list(typing.get_args(RangePolicy))}, got "
                f"{policy!r}"
            )
        try:
            return cls(
                input=data["input"],
                input_range=tuple(data["input_range"]),
                range_policy=policy,
                provenance=decode_value(data.get("provenance", {}), "provenance"),
                sample_time=data.get("sample_time"),
                **params,
            )
        except (TypeError, ValueError, KeyError, IndexError) as exc:
            if isinstance(exc, SchemaError):
                raise
            raise SchemaError(
                f"parameters: do not make a {cls.kind!r} model ({exc}); the model file is "
                "damaged or was edited"
            ) from None

    def save(self, path: str | Path, *, force: bool = False) -> Path:
        """Write the model as JSON, atomically; refuse to overwrite unless ``force``, and even
        then unless the existing file is a model file (:data:`MODEL_FILE`)."""
        text = json.dumps(self.to_dict(), indent=1, allow_nan=False)
        return atomic_write_text(path, text + "\n", force=force, kind=MODEL_FILE)


class Choice(NamedTuple):
    """Settings chosen on the training records (:meth:`Estimator._choose_settings`).

    Attributes
    ----------
    estimator : Estimator
        The estimator with the chosen settings; the fit template fits it on the training records.
    provenance : callable
        Adds the record of the choice to the fitted model's provenance (dict -> dict).
    """

    estimator: Estimator
    provenance: Callable[[dict[str, Any]], dict[str, Any]]


class Estimator(abc.ABC):
    """Identifies one model family. Holds settings only; ``fit`` returns a FittedModel.

    Subclasses are (mutable, non-frozen) dataclasses whose fields are the settings, plus the class
    attributes ``kind`` (matching the fitted model's ``kind``) and ``model_class``. They implement
    one method, :meth:`_identify`, and extend :meth:`_validate` for checks that the field types do
    not express. :meth:`fit` does everything else, the same way for every family:

    1. validate the settings (:meth:`_validate`: every ``Literal`` field against its choices,
       every ``bool`` field is a bool, then the family's own checks);
    2. if the family leaves settings open (:meth:`_open_settings`, e.g. the LPV hysteretic
       input's stroke and blend), let it choose them on the training records or records held
       out of them (:meth:`_choose_settings`; per-fit options in :attr:`choice_options` serve
       only this step), fit the estimator with the chosen settings instead and add the choice
       to its provenance; otherwise, a family whose drive-lag setting ``eta`` is
       ``"auto"`` or ``"identify"`` is fitted by :func:`mrdamper.models.lag.fit_with_lag`
       instead, which identifies the lag on an inner split and then runs steps 3-6 with it;
    3. gather the records into an :class:`ExperimentSet` (refusing an empty set or a record
       without motion);
    4. read the electrical input of every record, its identified range and whether it takes a
       single level (:class:`TrainingData`);
    5. call :meth:`_identify`;
    6. build ``model_class`` with the parameters, ``input``, ``input_range``, ``range_policy``
       and provenance (the single-level note, the training records' sampling intervals
       ``record_dt`` [s], wall-clock and CPU time: :data:`TIMING_PROVENANCE`) and the
       ``sample_time`` it was fitted at (:class:`FittedModel`).

    Progress (:mod:`mrdamper.progress`) is reported as the stages ``"preparing the training
    data"``, ``"identifying"`` (the family reports its own stages within it) and ``"done"``.

    At a single level the note (:func:`single_level_note`) is also emitted as a ``UserWarning``.
    """

    kind: ClassVar[str] = "abstract"
    #: Fitted-model class built by :meth:`fit`.
    model_class: ClassVar[type[FittedModel]]
    #: Names of the per-fit options the family's :meth:`_identify` takes (others are refused).
    fit_options: ClassVar[tuple[str, ...]] = ()
    #: Per-fit options that hold one value per training record (they follow a long record into
    #: its segments, :meth:`_training_set`).
    per_record_options: ClassVar[tuple[str, ...]] = ()
    #: Per-fit options used only by the settings choice (:meth:`_choose_settings`): not passed to
    #: the fit of the chosen estimator, and refused when no setting is left open.
    choice_options: ClassVar[tuple[str, ...]] = ()
    #: Old setting name -> current name. Old names are still accepted, with a note.
    renamed_settings: ClassVar[Mapping[str, str]] = {}
    #: Lowest default model rate of a discrete family [Hz] (None: the lowest record rate);
    #: :func:`mrdamper.models.rates.model_rate`.
    min_model_fs: ClassVar[float | None] = None

    @classmethod
    def settings_names(cls) -> list[str]:
        """Names of the settings this estimator takes (its init fields, old names excluded)."""
        if not dataclasses.is_dataclass(cls):
            return []
        return [
            f.name for f in dataclasses.fields(cls) if f.init and f.name not in cls.renamed_settings
        ]

    @classmethod
    def from_settings(cls, **settings: Any) -> Estimator:
        """The estimator with ``settings``; an unknown setting is refused, naming it.

        Raises
        ------
        DataValidationError
            A setting this estimator does not take (the message lists the ones it takes).
        """
        accepted = cls.settings_names()
        unknown = [k for k in settings if k not in accepted and k not in cls.renamed_settings]
        if unknown:
            raise DataValidationError(
                unknown[0],
                f"{cls.kind} does not take the setting {unknown[0]!r}; its settings are {accepted}",
            )
        return cls(**settings)

    def _check_fit_options(self, options: Mapping[str, Any]) -> None:
        """Refuse a per-fit option the family does not take (one line naming it)."""
        unknown = [k for k in options if k not in self.fit_options]
        if unknown:
            raise DataValidationError(
                unknown[0],
                f"{self.kind}: fit takes no option {unknown[0]!r}; its options are "
                f"{list(self.fit_options)}",
            )

    def fit(self, data: Experiment | Iterable[Experiment], **options: Any) -> FittedModel:
        """Identify the model from one record or a collection of records.

        The outermost fit ends by measuring the model's free-run training ESR: a fit that
        explains (almost) nothing of its training force (:mod:`mrdamper.models.fit_check`) gets
        a warning and the note in its provenance (``training_fit``).

        Parameters
        ----------
        data : Experiment or iterable of Experiment
            Training records (never modified).
        **options
            Per-fit options of the family (e.g. ``record_weights`` of the LPV estimator).

        Returns
        -------
        FittedModel
            The identified model, an immutable value.
        """
        if _IN_FIT.get():  # a candidate of a choice or of a drive lag: checked by the caller
            return self._fit(data, **options)
        records = self._as_set(data)
        token = _IN_FIT.set(True)
        try:
            model = self._fit(records, **options)
        finally:
            _IN_FIT.reset(token)
        from mrdamper.models.fit_check import training_fit_note

        value, note = training_fit_note(model, records)
        if note is None:
            return model
        warn_user(note, UserWarning)
        check = {"training_esr": value, "note": note}
        return dataclasses.replace(model, provenance={**model.provenance, "training_fit": check})

    def _fit(self, data: Experiment | Iterable[Experiment], **options: Any) -> FittedModel:
        """:meth:`fit` without the final check (the family's identification, with its choice of
        open settings or drive lag)."""
        t0, c0 = time.perf_counter(), time.process_time()
        self._check_fit_options(options)
        self._validate()
        open_settings = self._open_settings()
        for key in self.choice_options:
            if options.get(key) is not None and not open_settings:
                raise DataValidationError(
                    key, f"{self.kind}: no setting is left open to choose, so {key} has no use"
                )
        if open_settings:  # chosen on the training records, before the drive lag
            report("preparing the training data")
            records, options, segments = self._training_set(data, options)
            choice = self._choose_settings(records, options)
            fit_options = {k: v for k, v in options.items() if k not in self.choice_options}
            model = choice.estimator.fit(records, **fit_options)
            provenance = choice.provenance(dict(model.provenance))
            if segments:
                provenance["segments"] = segments
            return dataclasses.replace(model, provenance=provenance)
        if getattr(self, "eta", None) in lag.LAG_SETTINGS:
            fitted: FittedModel = lag.fit_with_lag(self, data, options)  # the lag, identified
            return fitted
        report("preparing the training data")
        records, options, segments = self._training_set(data, options)
        prepared = self._prepare(records)
        report("identifying")
        result = self._identify(prepared, **options)
        provenance = dict(result.provenance)
        provenance.setdefault("envelope", training_envelope(prepared.records, prepared.electrical))
        if segments:
            provenance["segments"] = segments
        if prepared.level is not None:
            note = single_level_note(self.kind, prepared.input, prepared.level)
            provenance["note"] = note
            warn_user(note, UserWarning)
        # the records' sampling intervals [s] (the default step of the model's exports)
        provenance["record_dt"] = sorted({float(e.dt) for e in prepared.records})
        damper = {str(e.metadata.get("reference_damper", "")) for e in prepared.records}
        if len(damper) == 1 and "" not in damper:  # the rig's damper behind every record
            provenance["training_damper"] = damper.pop()
        provenance["elapsed_s"] = time.perf_counter() - t0
        provenance["cpu_s"] = time.process_time() - c0
        fs = result.parameters.get("fs")  # a discrete model's own rate [Hz]
        model = self.model_class(
            **result.parameters,
            input=prepared.input,
            input_range=prepared.input_range,
            range_policy=getattr(self, "range_policy", "error"),
            provenance=provenance,
            sample_time=1.0 / float(fs) if fs else provenance["record_dt"][-1],
        )
        report("done")
        return model

    def _open_settings(self) -> bool:
        """Whether settings are left open, to be chosen on the training records (default: no)."""
        return False

    def _choose_settings(self, records: ExperimentSet, options: Mapping[str, Any]) -> Choice:
        """The settings left open (:meth:`_open_settings`), chosen on the training records.

        Called by :meth:`fit` with the records the fit sees and the per-fit options; the chosen
        estimator must leave nothing open.
        """
        raise NotImplementedError(f"{type(self).__name__} leaves no setting open")

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        """The family's identification step on the prepared training data (to implement)."""
        raise NotImplementedError(f"{type(self).__name__} does not implement _identify")

    def _validate(self) -> None:
        """Check the settings: ``Literal`` fields against their choices and ``bool`` fields.

        Families extend it (call ``super()._validate()``) with the checks of
        :func:`check_int`, :func:`check_number` for numbers.
        """
        if not dataclasses.is_dataclass(self):
            return
        hints = type_hints(type(self))
        for f in dataclasses.fields(self):
            hint = hints.get(f.name)
            value = getattr(self, f.name)
            choices = literal_choices(hint)
            if choices is not None:
                check_choice(f.name, value, choices[0], allow_none=choices[1])
            elif hint is bool:
                check_bool(f.name, value)

    def _prepare(self, records: ExperimentSet) -> TrainingData:
        source = cast(ElectricalSource, getattr(self, "input", "i"))
        check_choice("input", source, ("i", "voltage"))
        electrical = tuple(
            np.ascontiguousarray(e.electrical(source), dtype=np.float64) for e in records
        )
        ext = np.array([[float(np.min(a)), float(np.max(a))] for a in electrical])
        lo, hi = float(ext[:, 0].min()), float(ext[:, 1].max())
        return TrainingData(
            records=records,
            input=source,
            electrical=electrical,
            input_range=(lo, hi),
            level=single_level(np.array([lo, hi])),
        )

    def _training_set(
        self, data: Experiment | Iterable[Experiment], options: Mapping[str, Any]
    ) -> tuple[ExperimentSet, dict[str, Any], dict[str, int]]:
        """The training records, a record longer than :data:`~mrdamper.models._scale.\
SEGMENT_SAMPLES` cut into consecutive segments (bounded work arrays; a note says so), with the
        per-record options (:attr:`per_record_options`) repeated for each segment.

        Returns
        -------
        records : ExperimentSet
            What the fit sees.
        options : dict
            ``options`` with per-record values following their records.
        segments : dict
            Name of every record that was cut -> number of segments (empty when none was).
        """
        exps = self._as_set(data)
        records, owners = _scale.split_long(exps)
        out = dict(options)
        if records is exps:
            return records, out, {}
        for key in self.per_record_options:
            values = out.get(key)
            if values is not None:
                values = list(values)
                if len(values) != len(exps):
                    raise DataValidationError(
                        key, f"expected {len(exps)} values (one per record), got {len(values)}"
                    )
                out[key] = [values[k] for k in owners]
        counts: dict[str, int] = {}
        for k, e in enumerate(exps):
            parts = owners.count(k)
            if parts < 2:
                continue
            counts[e.name] = parts
            warn_user(
                f"{self.kind}: record {e.name!r} ({e.n} samples) is identified as {parts} "
                f"consecutive segments of at most {_scale.SEGMENT_SAMPLES} samples (bounded "
                "memory), each a record of its own to the fit (free runs start at rest)",
                Note,
            )
        return records, out, counts

    @staticmethod
    def _as_set(data: Experiment | Iterable[Experiment]) -> ExperimentSet:
        exps = as_experiment_set(data, name="training")
        if len(exps) == 0:
            raise SchemaError("data: no training records given")
        for e in exps:
            peak = float(np.max(np.abs(e.v))) if e.n else 0.0
            if not peak >= MIN_PEAK_VELOCITY:
                raise DataValidationError(
                    "v",
                    f"training record {e.name!r} has no motion (max |v| = {peak:.3g} m/s, below "
                    f"{MIN_PEAK_VELOCITY:g} m/s: zero velocity or noise); a damper model needs "
                    "motion (check the velocity column and its unit, or derive it from x with "
                    "derive_velocity / --derive-velocity)",
                )
        return exps
