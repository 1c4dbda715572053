"""Study protocols.

A protocol says which records train the analysis and the models, which are scored, which models
run.

A :class:`Protocol` is a frozen value. It can be built in Python, taken from the presets
(:mod:`mrdamper.study.presets`) or loaded from a small JSON or
TOML file with :func:`load_protocol` (schema in ``docs/study.md``). How records are turned into
training and scoring sets (folds) lives in :mod:`mrdamper.study.splits`.
"""

from __future__ import annotations

import fnmatch
import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal, overload

from mrdamper import kinds
from mrdamper.data import ExperimentSet, SourceSet
from mrdamper.data.experiment_set import metadata_equal
from mrdamper.errors import SchemaError
from mrdamper.study.records import Record, Records, same_kind

__all__ = [
    "DEFAULT_MODELS",
    "PROTOCOL_SCHEMA",
    "PROTOCOL_SCHEMA_VERSION",
    "ModelSpec",
    "Protocol",
    "Selection",
    "Split",
    "protocol_from_dict",
]

PROTOCOL_SCHEMA = "mrdamper.protocol"
PROTOCOL_SCHEMA_VERSION = 1

#: Models run by default, in display order (the kind table's defaults, :mod:`mrdamper.kinds`);
#: kinds that are not installed are left out.
DEFAULT_MODELS: tuple[str, ...] = kinds.default_kinds()

SplitKind = Literal["fixed", "leave-one-group-out", "k-fold", "time"]
RangePolicyName = Literal["error", "warn", "clip", "ignore"]


def _frozen_mapping(value: Any, field_name: str) -> Mapping[str, Any]:
    if value is None:
        return MappingProxyType({})
    if not isinstance(value, Mapping):
        raise SchemaError(f"{field_name}: expected a table/object of key = value, got {value!r}")
    out: dict[str, Any] = {}
    for k, v in value.items():
        out[str(k)] = tuple(v) if isinstance(v, list) else v
    return MappingProxyType(out)


@dataclass(frozen=True)
class Selection:
    """Which records of a data set take a role (analysis, training or scoring).

    A record is selected when every condition holds. An empty selection selects every record.

    Parameters
    ----------
    match : mapping
        Metadata ``key: value`` pairs the record must have; a list value accepts any member.
    names : sequence of str
        Shell-style globs on the record name (``"exp1_*"``); the record must match at least one.
        Empty: any name.
    exclude : mapping
        Metadata ``key: value`` pairs that reject a record.
    group_by : str, optional
        Metadata key used with ``take``.
    take : int, optional
        Keep only the first ``take`` selected records of each ``group_by`` value (in data order),
        e.g. the first replicate of each experiment.

    Examples
    --------
    >>> Selection(match={"experiment": [6, 7, 8]}, group_by="experiment", take=1).describe()
    'experiment in [6, 7, 8]; first 1 per experiment'
    """

    match: Mapping[str, Any] = field(default_factory=dict)
    names: tuple[str, ...] = ()
    exclude: Mapping[str, Any] = field(default_factory=dict)
    group_by: str | None = None
    take: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "match", _frozen_mapping(self.match, "match"))
        object.__setattr__(self, "exclude", _frozen_mapping(self.exclude, "exclude"))
        if isinstance(self.names, str):
            object.__setattr__(self, "names", (self.names,))
        object.__setattr__(self, "names", tuple(self.names))
        for g in self.names:
            if not isinstance(g, str) or not g:
                raise SchemaError(f"names: expected non-empty glob strings, got {g!r}")
        if self.take is not None:
            if isinstance(self.take, bool) or not isinstance(self.take, int) or self.take < 1:
                raise SchemaError(f"take: expected a positive integer, got {self.take!r}")
            if not self.group_by:
                raise SchemaError("group_by: 'take' needs a metadata key to group by, got none")

    def _accepts(self, e: Record) -> bool:
        for key, want in self.match.items():
            if key not in e.metadata:
                return False
            options = want if isinstance(want, tuple) else (want,)
            if not any(metadata_equal(e.metadata[key], w) for w in options):
                return False
        for key, bad in self.exclude.items():
            if key in e.metadata:
                options = bad if isinstance(bad, tuple) else (bad,)
                if any(metadata_equal(e.metadata[key], w) for w in options):
                    return False
        return not self.names or any(fnmatch.fnmatchcase(e.name, g) for g in self.names)

    @overload
    def select(self, data: ExperimentSet) -> ExperimentSet: ...
    @overload
    def select(self, data: SourceSet) -> SourceSet: ...
    def select(self, data: Records) -> Records:
        """Return the selected records, in data order (a set of the same kind as ``data``).

        Parameters
        ----------
        data : ExperimentSet or SourceSet
            Records to select from (only names and metadata are looked at).
        """
        chosen = [e for e in data if self._accepts(e)]
        if self.take is not None and self.group_by:
            counts: dict[Any, int] = {}
            kept = []
            for e in chosen:
                g = e.metadata.get(self.group_by)
                if counts.get(g, 0) < self.take:
                    kept.append(e)
                counts[g] = counts.get(g, 0) + 1
            chosen = kept
        return same_kind(data, chosen)

    def describe(self) -> str:
        """One-line human description."""
        parts = [
            f"{k} in {list(v)}" if isinstance(v, tuple) else f"{k} = {v!r}"
            for k, v in self.match.items()
        ]
        parts += [
            f"{k} not in {list(v)}" if isinstance(v, tuple) else f"{k} != {v!r}"
            for k, v in self.exclude.items()
        ]
        if self.names:
            parts.append("name matches " + " or ".join(self.names))
        if self.take is not None:
            parts.append(f"first {self.take} per {self.group_by}")
        return "; ".join(parts) if parts else "all records"

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe form (the protocol file layout)."""
        out: dict[str, Any] = {}
        if self.match:
            out["match"] = {
                k: list(v) if isinstance(v, tuple) else v for k, v in self.match.items()
            }
        if self.names:
            out["names"] = list(self.names)
        if self.exclude:
            out["exclude"] = {
                k: list(v) if isinstance(v, tuple) else v for k, v in self.exclude.items()
            }
        if self.group_by is not None:
            out["group_by"] = self.group_by
        if self.take is not None:
            out["take"] = self.take
        return out


@dataclass(frozen=True)
class Split:
    """How training and scoring sets are formed from the selected records.

    Parameters
    ----------
    kind : {"fixed", "leave-one-group-out", "k-fold", "time"}
        ``"fixed"``: one fold; the selections are used as they are. ``"leave-one-group-out"``:
        one fold per group; the group's records are scored, the other groups' records train.
        ``"k-fold"``: ``k`` folds by record; the scored records are dealt to the folds in turn
        (record ``j`` of the data order to fold ``j mod k``) and each fold trains on the others.
        ``"time"``: every selected record is cut in time; the first ``fraction`` of its samples
        trains, the rest is scored.
    key : str, optional
        Metadata key defining the groups (leave-one-group-out).
    name_regex : str, optional
        Alternative to ``key``: the group is the first capture group (or whole match) of this
        regular expression searched in the record name.
    fraction : float
        Training fraction of each record for ``"time"`` [-], in (0, 1).
    k : int
        Number of folds for ``"k-fold"`` (at least 2).
    """

    kind: SplitKind = "fixed"
    key: str | None = None
    name_regex: str | None = None
    fraction: float = 0.7
    k: int = 5

    def __post_init__(self) -> None:
        if self.kind not in ("fixed", "leave-one-group-out", "k-fold", "time"):
            raise SchemaError(
                "split.kind: expected 'fixed', 'leave-one-group-out', 'k-fold' or 'time', got "
                f"{self.kind!r}"
            )
        if isinstance(self.k, bool) or not isinstance(self.k, int) or self.k < 2:
            raise SchemaError(f"split.k: expected an integer of at least 2, got {self.k!r}")
        if self.kind == "leave-one-group-out" and not (self.key or self.name_regex):
            raise SchemaError(
                "split.key: leave-one-group-out needs 'key' or 'name_regex', got neither"
            )
        if self.name_regex is not None:
            try:
                re.compile(self.name_regex)
            except re.error as exc:
                raise SchemaError(
                    f"split.name_regex: invalid regular expression {self.name_regex!r} ({exc})"
                ) from None
        if (
            isinstance(self.fraction, bool)
            or not isinstance(self.fraction, (int, float))
            or not 0.0 < float(self.fraction) < 1.0
        ):
            raise SchemaError(f"split.fraction: expected a number in (0, 1), got {self.fraction!r}")

    def group_of(self, e: Record) -> Any:
        """Group value of a record (leave-one-group-out).

        Parameters
        ----------
        e : Experiment or RecordSource
            The record (its name and metadata).
        """
        if self.name_regex is not None:
            m = re.search(self.name_regex, e.name)
            if m is None:
                raise SchemaError(
                    f"split.name_regex: record name {e.name!r} does not match {self.name_regex!r}"
                )
            return m.group(1) if m.groups() else m.group(0)
        if self.key is None or self.key not in e.metadata:
            raise SchemaError(f"split.key: record {e.name!r} has no metadata {self.key!r}")
        return e.metadata[self.key]

    def describe(self) -> str:
        """One-line human description."""
        if self.kind == "fixed":
            return "one fold (fixed training and scoring sets)"
        if self.kind == "time":
            return (
                f"each record cut in time: first {self.fraction:.0%} trains, last "
                f"{1 - self.fraction:.0%} is scored"
            )
        if self.kind == "k-fold":
            return (
                f"{self.k}-fold by record: each record is scored once, by models trained on the "
                "other folds"
            )
        by = f"metadata {self.key!r}" if self.key else f"name pattern {self.name_regex!r}"
        return f"leave one group out, groups by {by}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe form."""
        out: dict[str, Any] = {"kind": self.kind}
        if self.key is not None:
            out["key"] = self.key
        if self.name_regex is not None:
            out["name_regex"] = self.name_regex
        if self.kind == "time":
            out["fraction"] = float(self.fraction)
        if self.kind == "k-fold":
            out["k"] = int(self.k)
        return out


@dataclass(frozen=True)
class ModelSpec:
    """One model to run: registry kind, estimator settings and the label used in tables.

    Parameters
    ----------
    kind : str
        Registry kind (``"lpv"``, ``"sp1"``, ...).
    settings : mapping
        Keyword settings of the estimator (``get_estimator(kind, **settings)``).
    label : str, optional
        Name in tables and figures; defaults to ``kind``. Labels must be unique in a protocol.
    """

    kind: str
    settings: Mapping[str, Any] = field(default_factory=dict)
    label: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or not self.kind:
            raise SchemaError(f"models.kind: expected a registry kind string, got {self.kind!r}")
        object.__setattr__(self, "settings", MappingProxyType(dict(self.settings or {})))
        if not self.label:
            object.__setattr__(self, "label", self.kind)

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe form."""
        out: dict[str, Any] = {"kind": self.kind}
        if self.settings:
            out["settings"] = dict(self.settings)
        if self.label != self.kind:
            out["label"] = self.label
        return out


def _as_spec(item: Any) -> ModelSpec:
    if isinstance(item, ModelSpec):
        return item
    if isinstance(item, str):
        return ModelSpec(item)
    if isinstance(item, Mapping):
        unknown = set(item) - {"kind", "settings", "label"}
        if unknown:
            raise SchemaError(
                f"models: unknown key(s) {sorted(unknown)}; expected kind, settings, label"
            )
        if "kind" not in item:
            raise SchemaError(f"models: entry {dict(item)!r} has no 'kind'")
        return ModelSpec(item["kind"], item.get("settings") or {}, item.get("label") or "")
    raise SchemaError(f"models: expected a kind string or a table with 'kind', got {item!r}")


@dataclass(frozen=True)
class Protocol:
    """A complete comparison protocol.

    Parameters
    ----------
    name : str
        Short name shown in the report.
    analysis : Selection, optional
        Records for the force-velocity analysis (zones and laws across current, paper III-C);
        ``None`` skips the analysis.
    train : Selection
        Records that identify the models.
    score : Selection
        Records that are scored.
    split : Split
        How folds are formed (see :class:`Split`).
    models : sequence of ModelSpec or str
        Models to run; an empty sequence means :data:`DEFAULT_MODELS` (those installed).
    input : {"i", "voltage"}
        Electrical input every model reads (added to settings unless a model sets it).
    exclude_trained : bool
        If true (default), records used for training or analysis in a fold are not scored in
        that fold, so every score is on unseen data.
    range_policy : {"error", "warn", "clip", "ignore"}
        Out-of-range policy applied to every fitted model before scoring; extrapolation is
        reported in the ``note`` column.
    settings : mapping
        Default estimator settings per kind (``{"lpv": {"model_fs": 200.0}}``), applied to every
        model of that kind unless the model entry sets the same key.
    showcase : str, optional
        Glob of the record drawn in the time-domain figures (Figs. 6, 9, 10, 11); default: the
        most informative scored record (varying current if any, else the highest current level,
        then the widest velocity spread).
    hysteresis_record : str, optional
        Glob of the record of the LTI hysteresis figure (Fig. 4); default: the first scored
        record of the analysis selection, else the showcase.
    description : str
        Free text shown in the report.
    """

    name: str = "study"
    analysis: Selection | None = None
    train: Selection = field(default_factory=Selection)
    score: Selection = field(default_factory=Selection)
    split: Split = field(default_factory=Split)
    models: tuple[ModelSpec, ...] = ()
    input: Literal["i", "voltage"] = "i"
    exclude_trained: bool = True
    range_policy: RangePolicyName = "warn"
    settings: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    showcase: str | None = None
    hysteresis_record: str | None = None
    description: str = ""

    def __post_init__(self) -> None:
        specs = tuple(_as_spec(m) for m in self.models)
        object.__setattr__(self, "models", specs)
        labels = [s.label for s in specs]
        dup = sorted({x for x in labels if labels.count(x) > 1})
        if dup:
            raise SchemaError(
                f"models: duplicate label(s) {dup}; give each entry a distinct 'label'"
            )
        if self.input not in ("i", "voltage"):
            raise SchemaError(f"input: expected 'i' or 'voltage', got {self.input!r}")
        if self.range_policy not in ("error", "warn", "clip", "ignore"):
            raise SchemaError(
                f"range_policy: expected error, warn, clip or ignore, got {self.range_policy!r}"
            )
        for name in ("analysis", "train", "score"):
            val = getattr(self, name)
            if val is not None and not isinstance(val, Selection):
                raise SchemaError(f"{name}: expected a Selection, got {type(val).__name__}")
        if not isinstance(self.split, Split):
            raise SchemaError(f"split: expected a Split, got {type(self.split).__name__}")
        if not isinstance(self.settings, Mapping) or not all(
            isinstance(v, Mapping) for v in self.settings.values()
        ):
            raise SchemaError(
                f"settings: expected a table of kind = {{setting = value}}, got {self.settings!r}"
            )
        object.__setattr__(
            self,
            "settings",
            MappingProxyType({str(k): MappingProxyType(dict(v)) for k, v in self.settings.items()}),
        )

    def settings_for(self, spec: ModelSpec) -> dict[str, Any]:
        """Estimator settings of ``spec``: the protocol's defaults for its kind, then its own."""
        return {**dict(self.settings.get(spec.kind, {})), **dict(spec.settings)}

    def resolved_models(self) -> tuple[ModelSpec, ...]:
        """The model specs to run: the protocol's, or the installed default models, each followed
        by its default variants (:data:`mrdamper.kinds.VARIANTS`: the paper's LPV, label
        ``lpv-paper``, after the default LPV)."""
        if self.models:
            return self.models
        from mrdamper.models import available_models

        have = set(available_models())
        out: list[ModelSpec] = []
        for k in kinds.default_kinds():
            if k not in have:
                continue
            out.append(ModelSpec(k))
            out += [
                ModelSpec(v.kind, dict(v.settings), v.label) for v in kinds.VARIANTS if v.kind == k
            ]
        return tuple(out)

    def with_models(self, models: Sequence[ModelSpec | str | Mapping[str, Any]]) -> Protocol:
        """Copy with another model list."""
        from dataclasses import replace

        return replace(self, models=tuple(_as_spec(m) for m in models))

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe form; :func:`protocol_from_dict` reads it back."""
        out: dict[str, Any] = {
            "schema": PROTOCOL_SCHEMA,
            "schema_version": PROTOCOL_SCHEMA_VERSION,
            "name": self.name,
            "description": self.description,
            "input": self.input,
            "analysis": None if self.analysis is None else self.analysis.to_dict(),
            "train": self.train.to_dict(),
            "score": self.score.to_dict(),
            "split": self.split.to_dict(),
            "exclude_trained": self.exclude_trained,
            "range_policy": self.range_policy,
            "models": [m.to_dict() for m in self.models],
        }
        if self.settings:
            out["settings"] = {k: dict(v) for k, v in self.settings.items()}
        if self.showcase is not None:
            out["showcase"] = self.showcase
        if self.hysteresis_record is not None:
            out["hysteresis_record"] = self.hysteresis_record
        return out

    def to_json(self) -> str:
        """The protocol as indented JSON text."""
        return json.dumps(self.to_dict(), indent=2)


_TOP_KEYS = {
    "schema",
    "schema_version",
    "name",
    "description",
    "input",
    "analysis",
    "train",
    "score",
    "split",
    "exclude_trained",
    "range_policy",
    "models",
    "settings",
    "showcase",
    "hysteresis_record",
}
_SEL_KEYS = {"match", "names", "exclude", "group_by", "take"}
_SPLIT_KEYS = {"kind", "key", "name_regex", "fraction", "k"}


def _selection(value: Any, where: str) -> Selection:
    if value is None:
        return Selection()
    if not isinstance(value, Mapping):
        raise SchemaError(f"{where}: expected a table/object, got {value!r}")
    unknown = set(value) - _SEL_KEYS
    if unknown:
        raise SchemaError(
            f"{where}: unknown key(s) {sorted(unknown)}; expected {sorted(_SEL_KEYS)}"
        )
    names = value.get("names", ())
    return Selection(
        match=value.get("match") or {},
        names=(names,) if isinstance(names, str) else tuple(names),
        exclude=value.get("exclude") or {},
        group_by=value.get("group_by"),
        take=value.get("take"),
    )


def protocol_from_dict(data: Mapping[str, Any]) -> Protocol:
    """Build a :class:`Protocol` from its dict form (a parsed JSON or TOML protocol file).

    Parameters
    ----------
    data : mapping
        The protocol's keys (see ``docs/study.md``).

    Returns
    -------
    Protocol

    Raises
    ------
    SchemaError
        Unknown keys, wrong schema name or version, or invalid values; the message names the key.
    """
    if not isinstance(data, Mapping):
        raise SchemaError(
            f"protocol: expected a table/object at top level, got {type(data).__name__}"
        )
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise SchemaError(
            f"protocol: unknown key(s) {sorted(unknown)}; expected some of {sorted(_TOP_KEYS)}"
        )
    if data.get("schema", PROTOCOL_SCHEMA) != PROTOCOL_SCHEMA:
        raise SchemaError(f"schema: expected {PROTOCOL_SCHEMA!r}, got {data.get('schema')!r}")
    if data.get("schema_version", PROTOCOL_SCHEMA_VERSION) != PROTOCOL_SCHEMA_VERSION:
        raise SchemaError(
            f"schema_version: expected {PROTOCOL_SCHEMA_VERSION}, got "
            f"{data.get('schema_version')!r}"
        )
    split = data.get("split") or {}
    if not isinstance(split, Mapping):
        raise SchemaError(f"split: expected a table/object, got {split!r}")
    bad = set(split) - _SPLIT_KEYS
    if bad:
        raise SchemaError(f"split: unknown key(s) {sorted(bad)}; expected {sorted(_SPLIT_KEYS)}")
    models = data.get("models", [])
    if not isinstance(models, (list, tuple)):
        raise SchemaError(f"models: expected a list, got {models!r}")
    excl = data.get("exclude_trained", True)
    if not isinstance(excl, bool):
        raise SchemaError(f"exclude_trained: expected true or false, got {excl!r}")
    return Protocol(
        name=str(data.get("name", "study")),
        description=str(data.get("description", "")),
        input=data.get("input", "i"),
        analysis=None if data.get("analysis") is None else _selection(data["analysis"], "analysis"),
        train=_selection(data.get("train"), "train"),
        score=_selection(data.get("score"), "score"),
        split=Split(**dict(split)),
        models=tuple(_as_spec(m) for m in models),
        exclude_trained=excl,
        range_policy=data.get("range_policy", "warn"),
        settings=data.get("settings") or {},
        showcase=data.get("showcase"),
        hysteresis_record=data.get("hysteresis_record"),
    )
