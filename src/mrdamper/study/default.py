"""The protocol a study runs when none is given, chosen from the records themselves.

One rule, applied in order (:func:`default_protocol`):

1. every record has ``experiment`` metadata (a Table II design-of-experiments folder written by
   ``mrdamper rig doe``): the ``doe`` preset;
2. every record has ``condition`` metadata (constant-current sine records named
   ``sine_{A}mm_{f}Hz_{i}A``): the ``quiroz`` preset (leave one condition out);
3. any other records (the general case):

   * electrical input: the current ``i`` when every record has it, else the command ``voltage``;
   * one record: cut in time, the first 70 % trains and the last 30 % is scored;
   * several records: k-fold by record, ``k = min(5, number of records)``, each record scored
     once by models trained on the other folds;
   * force-velocity analysis on the records whose electrical input is constant (range within
     :data:`CONSTANT_INPUT_TOLERANCE` of the largest input), when they hold at least two
     distinct levels; otherwise no analysis (the LPV zone laws are then fitted on ``rho`` bins of
     the training records by the estimator itself).

The choice and its reason come back as one line, which ``mrdamper study`` prints.
"""

from __future__ import annotations

import dataclasses
import glob
from pathlib import Path

import numpy as np

from mrdamper.data.experiment import ElectricalSource
from mrdamper.data.inspection import common_input
from mrdamper.errors import SchemaError
from mrdamper.study.presets import doe_protocol, load_protocol, quiroz_protocol
from mrdamper.study.protocol import Protocol, Selection, Split
from mrdamper.study.records import Record, Records, as_list, as_loaded

__all__ = [
    "CONSTANT_INPUT_TOLERANCE",
    "DEFAULT_K",
    "DEFAULT_TIME_FRACTION",
    "choose_protocol",
    "default_protocol",
]

#: Largest number of folds of the default k-fold split.
DEFAULT_K = 5
#: Training fraction of a single record in the default time split [-].
DEFAULT_TIME_FRACTION = 0.7
#: A record's electrical input counts as constant when its range is at most this fraction of the
#: largest electrical input of the data set [-].
CONSTANT_INPUT_TOLERANCE = 0.01


def _input_of(data: Records) -> ElectricalSource:
    source = common_input(data)
    if source is not None:
        return source
    raise SchemaError(
        "protocol: the records do not share one electrical channel (some have only 'i', others "
        "only 'voltage'); pass --protocol FILE naming the input"
    )


def _levels(e: Record, source: ElectricalSource) -> tuple[float, float, float]:
    """``(max |input|, input range, mean input)`` of one record (a source is read for it)."""
    s = np.asarray(as_loaded(e).electrical(source))
    return float(np.max(np.abs(s))), float(np.ptp(s)), float(np.mean(s))


def default_protocol(data: Records) -> tuple[Protocol, str]:
    """The protocol for ``data`` when none is given, and one line saying which and why.

    Parameters
    ----------
    data : ExperimentSet or SourceSet
        Every record of the study (sources are read one at a time when the choice needs the
        electrical input).

    Returns
    -------
    (Protocol, str)
        The protocol and a one-line description of the choice.

    Raises
    ------
    SchemaError
        No records, or records without a common electrical channel.
    """
    if len(data) == 0:
        raise SchemaError("data: no records to study")
    if all("experiment" in e.metadata for e in data):
        # the design's input is the records' channel (a voltage-driven damper's rig writes
        # 'voltage')
        proto = dataclasses.replace(doe_protocol(), input=_input_of(data))
        return (
            proto,
            (
                f"protocol {proto.name!r} (records carry 'experiment' metadata: Table II design "
                f"of experiments; input {proto.input!r})"
            ),
        )
    if all("condition" in e.metadata for e in data):
        proto = quiroz_protocol()
        return proto, (
            f"protocol {proto.name!r} (records carry 'condition' metadata: leave one "
            "amplitude/frequency condition out)"
        )
    source = _input_of(data)
    stats = [_levels(e, source) for e in data]
    scale = max(peak for peak, _, _ in stats) or 1.0
    constant = [
        e for e, (_, rng, _) in zip(as_list(data), stats) if rng <= CONSTANT_INPUT_TOLERANCE * scale
    ]
    levels = {
        round(mean / scale, 3) for _, rng, mean in stats if rng <= CONSTANT_INPUT_TOLERANCE * scale
    }
    analysis = None
    what_analysis = "no force-velocity analysis (fewer than 2 constant-input levels)"
    if len(levels) >= 2:
        analysis = Selection(names=tuple(glob.escape(e.name) for e in constant))
        what_analysis = f"force-velocity analysis on the {len(constant)} constant-{source} records"
    if len(data) == 1:
        split = Split("time", fraction=DEFAULT_TIME_FRACTION)
        what = (
            f"one record: first {DEFAULT_TIME_FRACTION:.0%} trains, last "
            f"{1 - DEFAULT_TIME_FRACTION:.0%} scored"
        )
    else:
        k = min(DEFAULT_K, len(data))
        split = Split("k-fold", k=k)
        what = f"{k}-fold by record over {len(data)} records"
    proto = Protocol(
        name="default",
        description=f"Default protocol: {what}; input {source!r}; {what_analysis}.",
        analysis=analysis,
        train=Selection(),
        score=Selection(),
        split=split,
        input=source,
    )
    return (
        proto,
        (
            f"protocol 'default' ({what}; input {source!r}; {what_analysis}; pass --protocol to "
            "choose)"
        ),
    )


def choose_protocol(data: Records, protocol: str | Path | None = None) -> tuple[Protocol, str]:
    """The study's protocol: a file or preset when given, else :func:`default_protocol`.

    Parameters
    ----------
    data : ExperimentSet or SourceSet
        Every record of the study.
    protocol : str or Path, optional
        Protocol file (``.json`` / ``.toml``) or preset name (``doe``, ``quiroz``, ``dyke``).

    Returns
    -------
    (Protocol, str)
        The protocol and one line saying which it is (and why, when chosen from the records).
    """
    if protocol is not None:
        proto = load_protocol(protocol)
        return proto, f"protocol {proto.name!r}"
    return default_protocol(data)
