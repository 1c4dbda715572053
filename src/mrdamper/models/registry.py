"""Name-to-class registry of model families, loaded lazily (no import-time side effects).

Each model module registers its estimator and fitted-model classes with :func:`register`. The
map below says which module defines which kind, so ``get_estimator("lpv")`` imports only
``mrdamper.models.lpv``.
"""

from __future__ import annotations

import importlib
import json
import os
from pathlib import Path
from typing import Any

from mrdamper.errors import SchemaError
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
]

#: kind -> module that defines it. Order is the default display order.
_MODULES: dict[str, str] = {
    "lpv": "mrdamper.models.lpv",
    "lti": "mrdamper.models.lpv",
    "p15": "mrdamper.models.phenomenological",
    "sp1": "mrdamper.models.semiphenomenological",
    "sp2": "mrdamper.models.semiphenomenological",
    "sp3": "mrdamper.models.semiphenomenological",
    "sp4": "mrdamper.models.semiphenomenological",
    "spencer": "mrdamper.models.spencer",
    "bingham": "mrdamper.models.bingham",
    "narx": "mrdamper.models.narx",
}

_ESTIMATORS: dict[str, type[Estimator]] = {}
_FITTED: dict[str, type[FittedModel]] = {}


def register(estimator: type[Estimator], fitted: type[FittedModel]) -> None:
    """Register an estimator / fitted-model pair under ``fitted.kind``.

    Parameters
    ----------
    estimator : type of Estimator
        Estimator class (its ``kind`` must equal the model's).
    fitted : type of FittedModel
        Fitted-model class.
    """
    kind = fitted.kind
    if estimator.kind != kind:
        raise ValueError(f"kind: estimator says {estimator.kind!r}, model says {kind!r}")
    _ESTIMATORS[kind] = estimator
    _FITTED[kind] = fitted


def _load(kind: str) -> None:
    if kind in _FITTED:
        return
    if kind not in _MODULES:
        raise SchemaError(f"model: unknown kind {kind!r}; expected one of {sorted(_MODULES)}")
    importlib.import_module(_MODULES[kind])
    if kind not in _FITTED:
        raise SchemaError(f"model: module {_MODULES[kind]} did not register {kind!r}")


def known_kinds() -> list[str]:
    """Every model kind this version defines, in default display order (nothing imported)."""
    return list(_MODULES)


def available_models() -> list[str]:
    """Kinds whose modules import on this installation, in default display order."""
    out = []
    for kind in _MODULES:
        try:
            _load(kind)
        except (ImportError, SchemaError):
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
        return model_from_dict(data)
    except SchemaError as exc:
        raise SchemaError(f"{p}: {exc}") from None
