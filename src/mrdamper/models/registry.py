"""Name-to-class registry of model families, loaded lazily (no import-time side effects).

The kind table (:mod:`mrdamper.kinds`) says which module defines which kind and the names of its
classes, so ``get_estimator("lpv")`` imports only ``mrdamper.models.lpv``; family modules do not
import the registry. A family defined elsewhere joins with :func:`register` (this process) or
with an entry point of the group ``mrdamper.kinds`` naming its row (every process; see
:mod:`mrdamper.kinds`); a plug-in whose module or classes cannot be loaded is refused in one line
naming them (:class:`~mrdamper.errors.PluginError`) when its kind is used.
"""

from __future__ import annotations

import importlib
import json
import os
from pathlib import Path
from typing import Any

from mrdamper import kinds
from mrdamper.errors import PluginError, SchemaError
from mrdamper.models._schema import check_header
from mrdamper.models.base import Estimator, FittedModel

__all__ = [
    "available_models",
    "get_estimator",
    "known_kinds",
    "load_model",
    "model_class",
    "model_from_dict",
    "register",
    "takes_lag",
]

_ESTIMATORS: dict[str, type[Estimator]] = {}
_FITTED: dict[str, type[FittedModel]] = {}


def register(
    estimator: type[Estimator],
    fitted: type[FittedModel],
    *,
    summary: str = "",
    color: str = "0.4",
    default: bool = False,
) -> None:
    """Add a model family defined outside this package under ``fitted.kind``.

    The kind gets a row in the kind table (:mod:`mrdamper.kinds`), so it appears in
    :func:`known_kinds`, the study (its local workers are handed the row), ``select`` and the
    closed loop like the built-in kinds, in this process. For every process (the command line,
    Dask workers) a package gives the row through an entry point of the group
    ``mrdamper.kinds`` instead (``docs/adding-a-model.md``).

    Parameters
    ----------
    estimator : type of Estimator
        Estimator class (its ``kind`` must equal the model's).
    fitted : type of FittedModel
        Fitted-model class.
    summary : str
        One line for help texts and reports.
    color : str
        Matplotlib colour of the kind in figures.
    default : bool
        Run by the study when no model list is given.
    """
    kind = fitted.kind
    if estimator.kind != kind:
        raise ValueError(f"kind: estimator says {estimator.kind!r}, model says {kind!r}")
    kinds.add(
        kinds.KindSpec(
            kind,
            fitted.__module__,
            estimator.__qualname__,
            fitted.__qualname__,
            summary or (fitted.__doc__ or kind).strip().splitlines()[0],
            color,
            default=default,
        )
    )
    _ESTIMATORS[kind] = estimator
    _FITTED[kind] = fitted


def _load(kind: str) -> None:
    if kind in _FITTED:
        return
    row = kinds.spec(kind)
    if row is None:
        broken = kinds.plugin_errors().get(kind)
        if broken is not None:
            raise SchemaError(f"model: kind {kind!r}: {broken}")
        raise SchemaError(f"model: unknown kind {kind!r}; expected one of {known_kinds()}")
    if any(k.kind == kind for k in kinds.KINDS):
        module = importlib.import_module(row.module)
        _ESTIMATORS[kind] = getattr(module, row.estimator)
        _FITTED[kind] = getattr(module, row.model)
        return
    try:  # a plug-in's module: a failure names the kind's row, not a traceback
        module = importlib.import_module(row.module)
        estimator, fitted = getattr(module, row.estimator), getattr(module, row.model)
    except Exception as exc:  # any error of another package's code
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise PluginError(
            f"model: kind {kind!r}: its row names {row.module}.{row.estimator} and "
            f"{row.model}, which cannot be loaded ({type(exc).__name__}: {reason})"
        ) from exc
    if not (isinstance(estimator, type) and issubclass(estimator, Estimator)):
        raise PluginError(f"model: kind {kind!r}: {row.estimator} is not an Estimator class")
    if not (isinstance(fitted, type) and issubclass(fitted, FittedModel)):
        raise PluginError(f"model: kind {kind!r}: {row.model} is not a FittedModel class")
    if estimator.kind != kind or fitted.kind != kind:
        raise PluginError(
            f"model: kind {kind!r}: its classes say {estimator.kind!r} (estimator) and "
            f"{fitted.kind!r} (model); expected {kind!r}"
        )
    _ESTIMATORS[kind] = estimator
    _FITTED[kind] = fitted


def known_kinds() -> list[str]:
    """Every model kind this version defines (and those added with :func:`register`), in
    display order (nothing imported)."""
    return [row.kind for row in kinds.rows()]


def available_models() -> list[str]:
    """Kinds whose modules import on this installation, in display order."""
    out = []
    for kind in known_kinds():
        try:
            _load(kind)
        except (ImportError, SchemaError, PluginError):
            continue
        out.append(kind)
    return out


def get_estimator(kind: str, **settings: Any) -> Estimator:
    """Instantiate the estimator of ``kind`` with ``settings``.

    Parameters
    ----------
    kind : str
        Model kind (see :func:`known_kinds`).
    **settings
        Estimator settings (see the estimator's docstring).

    Raises
    ------
    SchemaError
        An unknown kind.
    DataValidationError
        A setting the estimator does not take (the message names it and lists the others).
    """
    _load(kind)
    return _ESTIMATORS[kind].from_settings(**settings)


def takes_lag(kind: str) -> bool:
    """Whether the estimator of ``kind`` has a lag setting ``eta`` (:mod:`mrdamper.models.lag`).

    Parameters
    ----------
    kind : str
        Model kind (see :func:`known_kinds`).
    """
    _load(kind)
    return "eta" in _ESTIMATORS[kind].settings_names()


def model_class(kind: str) -> type[FittedModel]:
    """The fitted-model class of ``kind``.

    Parameters
    ----------
    kind : str
        Model kind (see :func:`known_kinds`).
    """
    _load(kind)
    return _FITTED[kind]


def model_from_dict(data: dict[str, Any]) -> FittedModel:
    """Rebuild any saved model from its dict (dispatch on ``kind``).

    Parameters
    ----------
    data : dict
        The dict written by :meth:`FittedModel.to_dict`.
    """
    check_header(data)
    return model_class(data["kind"]).from_dict(data)


def load_model(path: str | Path) -> FittedModel:
    """Load a model saved with :meth:`FittedModel.save`.

    A model whose fit explained nothing of its training force (provenance ``training_fit``,
    :mod:`mrdamper.models.fit_check`) is loaded with that note as a warning.

    Parameters
    ----------
    path : str or Path
        Model file (JSON).
    """
    p = Path(path)
    if os.path.lexists(p) and not p.exists():
        raise FileNotFoundError(f"{p}: a broken symbolic link or a symbolic link loop")
    if p.is_dir():
        raise SchemaError(f"{p}: is a folder; expected a model file written by 'mrdamper fit'")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"{p}: model file not found") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SchemaError(f"{p}: not valid JSON ({exc})") from None
    try:
        model = model_from_dict(data)
    except SchemaError as exc:
        raise SchemaError(f"{p}: {exc}") from None
    check = dict(model.provenance or {}).get("training_fit")
    if isinstance(check, dict) and isinstance(check.get("note"), str):
        from mrdamper._warn import warn_user

        warn_user(f"{p.name}: {check['note']}")  # every command that uses it says so
    return model
