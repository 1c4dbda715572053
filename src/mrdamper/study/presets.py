"""Preset protocols: the Table II design of experiments, the Quiroz sine records (leave one
condition out) and the Dyke random-excitation record (70 % / 30 % in time), and
:func:`load_protocol`, which reads a protocol file or a preset name."""

from __future__ import annotations

import json
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mrdamper.errors import SchemaError
from mrdamper.study.protocol import Protocol, Selection, Split, protocol_from_dict

__all__ = [
    "PRESETS",
    "doe_protocol",
    "dyke_protocol",
    "load_protocol",
    "preset_protocol",
    "quiroz_protocol",
]


def doe_protocol(models: Sequence[Any] = ()) -> Protocol:
    """The default protocol on the Table II design of experiments (virtual rig or a real rig).

    * Force-velocity analysis: the first replicate of each stepped-current experiment (6-8).
    * Identification: the first replicate of the varying-current experiments 1-3 (ICPS, APRBS,
      PRBS; 30 s each). The long road-profile experiments 4-5 (600 s) are kept for validation
      only, which keeps identification time bounded.
    * Scoring: every other record of experiments 1-8; records used for the analysis or the
      identification are never scored (``exclude_trained``).

    Parameters
    ----------
    models : sequence
        Models to run: kinds (``"lpv"``), :class:`~mrdamper.study.ModelSpec` or dicts; empty:
        every installed default model.

    Returns
    -------
    Protocol
    """
    return Protocol(
        name="doe",
        description=(
            "Table II design of experiments. F-v analysis on the first replicate of the "
            "stepped-current experiments 6-8; identification on the first replicate of "
            "experiments 1-3; every remaining record (replicates 2.. of 1-3 and 6-8, all of the "
            "long-road experiments 4-5) is scored."
        ),
        analysis=Selection(match={"experiment": (6, 7, 8)}, group_by="experiment", take=1),
        train=Selection(match={"experiment": (1, 2, 3)}, group_by="experiment", take=1),
        score=Selection(),
        split=Split("fixed"),
        models=tuple(models),
        hysteresis_record="*exp8*",
    )


def quiroz_protocol(models: Sequence[Any] = ()) -> Protocol:
    """Leave-one-condition-out on the Quiroz constant-current sine records.

    LPV and LTI run at their default model rate, 500 Hz here (the records are at 200 Hz and 1 kHz;
    :data:`~mrdamper.models.lpv.estimator.MIN_MODEL_FS`); no setting is fixed a priori.

    Each fold holds out one amplitude/frequency condition (all five currents) and trains the
    analysis and the models on the other conditions. The condition is the metadata ``condition``
    that the folder reader takes from the file name
    (``sine_5mm_3Hz_0.5A`` -> ``5mm_3Hz``).

    Parameters
    ----------
    models : sequence
        Models to run: kinds (``"lpv"``), :class:`~mrdamper.study.ModelSpec` or dicts; empty:
        every installed default model.

    Returns
    -------
    Protocol
    """
    return Protocol(
        name="quiroz-loco",
        description=(
            "Quiroz (2022) sine records: leave one amplitude/frequency condition out, all currents."
        ),
        analysis=Selection(),
        train=Selection(),
        score=Selection(),
        split=Split("leave-one-group-out", key="condition"),
        models=tuple(models),
    )


def dyke_protocol(models: Sequence[Any] = ()) -> Protocol:
    """Dyke (1996) random-excitation record: first 70 % of each record trains, last 30 % is scored.

    The electrical input is the command voltage; the force-velocity analysis is skipped (the
    voltage switches on a 10 ms grid, there are no constant-current records). Every model with a
    drive-lag setting (LPV, LTI, P-15, SP-1..SP-4, tanh, Bouc-Wen, Dahl, LuGre) identifies its
    drive lag on the training part (its default ``eta="auto"``, :mod:`mrdamper.models.lag`); LPV
    and LTI run at the record rate 3004.8 Hz (their default). The test
    part's voltage exceeds the training range by < 0.1 %, so models are scored with
    ``range_policy="clip"``.

    Parameters
    ----------
    models : sequence
        Models to run: kinds (``"lpv"``), :class:`~mrdamper.study.ModelSpec` or dicts; empty:
        every installed default model.

    Returns
    -------
    Protocol
    """
    return Protocol(
        name="dyke-70-30",
        description=(
            "Dyke (1996) white-noise record, input = command voltage; first 70 % trains, last 30 "
            "% scored."
        ),
        analysis=None,
        train=Selection(),
        score=Selection(),
        split=Split("time", fraction=0.7),
        input="voltage",
        models=tuple(models),
        range_policy="clip",
    )


PRESETS = {"doe": doe_protocol, "quiroz": quiroz_protocol, "dyke": dyke_protocol}


def preset_protocol(name: str, models: Sequence[Any] = ()) -> Protocol:
    """A preset protocol by name: ``"doe"``, ``"quiroz"`` or ``"dyke"``.

    Parameters
    ----------
    name : {"doe", "quiroz", "dyke"}
        The preset.
    models : sequence
        Models to run (as for :func:`doe_protocol`).

    Returns
    -------
    Protocol
    """
    if name not in PRESETS:
        raise SchemaError(f"protocol: unknown preset {name!r}; expected one of {sorted(PRESETS)}")
    return PRESETS[name](models)


def load_protocol(path: str | Path) -> Protocol:
    """Read a protocol file (``.json`` or ``.toml``) or a preset name.

    The presets are ``"doe"``, ``"quiroz"`` and ``"dyke"``.

    Parameters
    ----------
    path : str or Path
        Protocol file, or a preset name.

    Returns
    -------
    Protocol

    Raises
    ------
    FileNotFoundError
        If the path does not exist and is not a preset name.
    SchemaError
        If the file cannot be parsed or does not follow the schema (see ``docs/study.md``).
    """
    if isinstance(path, str) and path in PRESETS:
        return preset_protocol(path)
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(
            f"{p}: protocol file not found (or use a preset: {', '.join(PRESETS)})"
        )
    text = p.read_text(encoding="utf-8")
    suffix = p.suffix.lower()
    try:
        if suffix == ".toml":
            data = tomllib.loads(text)
        elif suffix == ".json":
            data = json.loads(text)
        else:
            raise SchemaError(f"{p}: protocol file must end in .json or .toml, got {suffix!r}")
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SchemaError(f"{p}: cannot parse protocol file ({exc})") from None
    return protocol_from_dict(data)
