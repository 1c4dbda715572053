"""Shipped reference dampers: calibrated model files in ``mrdamper/rig/parameters/*.json``.

``quiroz2022`` is the Spencer (modified Bouc-Wen) model calibrated on the Quiroz (UTFSM, 2022)
constant-current sine records, 0-1 A (input ``i``); ``spencer1997`` is the published prototype
damper of Spencer et al. (1997), driven by command voltage 0-2.25 V (input ``voltage``). How they
were calibrated is described in ``docs/calibration.md``.
"""

from __future__ import annotations

import dataclasses
from importlib import resources
from typing import Any

from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.models.registry import load_model

__all__ = [
    "CUSTOM_DAMPER",
    "DEFAULT_REFERENCE",
    "REFERENCE_DAMPERS",
    "REFERENCE_KEY",
    "available_reference_dampers",
    "reference_damper",
    "reference_name",
    "resolve_damper",
]

#: Names of the reference dampers the package is meant to ship.
REFERENCE_DAMPERS: tuple[str, ...] = ("quiroz2022", "spencer1997")

#: The damper the virtual rig uses when none is given.
DEFAULT_REFERENCE = "quiroz2022"

#: Provenance key of a loaded reference damper, and metadata key of the records the rig makes with
#: it: the reference damper's name.
REFERENCE_KEY = "reference_damper"
#: The ``reference_damper`` metadata of records made with a damper that is not a shipped one.
CUSTOM_DAMPER = "custom"


def _parameters_dir() -> Any:  # importlib Traversable
    return resources.files("mrdamper.rig").joinpath("parameters")


def available_reference_dampers() -> list[str]:
    """Names of the reference dampers whose parameter file is installed."""
    folder = _parameters_dir()
    return [n for n in REFERENCE_DAMPERS if folder.joinpath(f"{n}.json").is_file()]


def reference_damper(name: str = DEFAULT_REFERENCE) -> FittedModel:
    """Load a shipped reference damper model.

    Parameters
    ----------
    name : {"quiroz2022", "spencer1997"}
        Which damper.

    Returns
    -------
    FittedModel
        The model (a :class:`~mrdamper.models.spencer.SpencerModel`), loaded with
        :func:`mrdamper.models.load_model`.

    Raises
    ------
    DataValidationError
        For an unknown name.
    FileNotFoundError
        If the parameter file is not installed.

    Examples
    --------
    >>> damper = reference_damper()  # doctest: +SKIP
    >>> damper.kind, damper.input, damper.input_range  # doctest: +SKIP
    ('spencer', 'i', (0.0, 1.0))
    """
    if name not in REFERENCE_DAMPERS:
        raise DataValidationError(
            "name", f"unknown reference damper {name!r}; expected one of {list(REFERENCE_DAMPERS)}"
        )
    res = _parameters_dir().joinpath(f"{name}.json")
    if not res.is_file():
        raise FileNotFoundError(
            f"reference damper {name!r}: parameter file parameters/{name}.json is not installed "
            f"(installed: {available_reference_dampers()})"
        )
    with resources.as_file(res) as path:
        model = load_model(path)
    # the name travels with the model, so records of the rig can say which damper made them
    return dataclasses.replace(model, provenance={**model.provenance, REFERENCE_KEY: name})


def reference_name(model: Any) -> str | None:
    """The name of the shipped reference damper ``model`` was loaded as, else None."""
    name = dict(getattr(model, "provenance", None) or {}).get(REFERENCE_KEY)
    return str(name) if name in REFERENCE_DAMPERS else None


def resolve_damper(spec: str | None) -> FittedModel | None:
    """The damper a command names: a shipped reference damper or a saved model file.

    Parameters
    ----------
    spec : str or None
        A name of :data:`REFERENCE_DAMPERS`, or the path of a model JSON file; None for the
        default (the caller's default reference damper).

    Returns
    -------
    FittedModel or None
        None when ``spec`` is None.

    Raises
    ------
    DataValidationError
        ``spec`` is neither a reference damper name nor a ``.json`` / existing file.
    """
    from pathlib import Path

    if spec is None:
        return None
    if spec in REFERENCE_DAMPERS:
        return reference_damper(spec)
    path = Path(spec)
    if path.suffix.lower() == ".json" or path.exists():
        return load_model(path)
    raise DataValidationError(
        "--damper",
        f"expected a reference damper name {list(REFERENCE_DAMPERS)} or a model JSON file, "
        f"got {spec!r}",
    )
