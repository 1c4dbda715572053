"""The model file format: JSON encoding of parameters, and the check of a file on load.

A model file is a JSON object written by :meth:`mrdamper.models.FittedModel.save`::

    {"schema": "mrdamper.model", "schema_version": 2, "kind": "lpv", "input": "i",
     "input_range": [lo, hi], "range_policy": "error", "sample_time": 0.005,
     "parameters": {...}, "provenance": {...}}

``sample_time`` [s] is the sampling interval the model was fitted at (a discrete model's own
sample time ``1 / fs``; else that of the training records, the largest when they differ), the
default step of its C and FMU exports; ``null`` for a model built by hand. Version 1 files (before
``sample_time``) still load, without it.

Arrays are ``{"__ndarray__": [flat values], "dtype": "float64", "shape": [...]}`` and non-finite
floats ``{"__float__": "inf"}``. :func:`check_model_dict` checks a loaded file against this
schema and against the field types of the model class before anything is built from it: a
damaged or hand-edited file (a ``null`` coefficient, a list instead of an object, an array whose
shape does not match its values, a string where a number belongs, a missing field) is one
:class:`~mrdamper.errors.SchemaError` naming the field, never a traceback later.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping
from typing import Any

import numpy as np

from mrdamper.errors import SchemaError

__all__ = [
    "READABLE_VERSIONS",
    "SCHEMA_NAME",
    "SCHEMA_VERSION",
    "check_header",
    "check_model_dict",
    "decode_value",
    "encode_value",
    "has_nan",
]

SCHEMA_NAME = "mrdamper.model"
SCHEMA_VERSION = 2
#: Versions this release reads (1: before ``sample_time``).
READABLE_VERSIONS: tuple[int, ...] = (1, 2)

#: Array element types a model file may hold.
_DTYPES: frozenset[str] = frozenset({"float64", "float32", "int64", "int32", "bool", "complex128"})
#: Fields of the file every model has, and their JSON types.
_REQUIRED: tuple[str, ...] = ("kind", "input", "input_range", "parameters")


def encode_value(value: Any) -> Any:
    """Encode a parameter value as JSON-safe data (ndarrays keep dtype and shape exactly).

    Parameters
    ----------
    value : object
        Number, array, sequence or mapping of them.
    """
    if isinstance(value, np.ndarray):
        return {
            "__ndarray__": value.ravel().tolist(),
            "dtype": str(value.dtype),
            "shape": list(value.shape),
        }
    if isinstance(value, (np.floating, float)):
        f = float(value)
        if not math.isfinite(f):
            return {"__float__": repr(f)}
        return f
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (list, tuple)):
        return [encode_value(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): encode_value(v) for k, v in value.items()}
    return value


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_bool(v: Any) -> bool:
    return isinstance(v, bool)


def _decode_array(value: Mapping[str, Any], field: str) -> np.ndarray:
    flat, dtype, shape = value["__ndarray__"], value.get("dtype", "float64"), value.get("shape")
    if not isinstance(flat, list):
        raise SchemaError(f"{field}: expected a list of array values, got {type(flat).__name__}")
    if dtype not in _DTYPES:
        raise SchemaError(f"{field}: expected a dtype among {sorted(_DTYPES)}, got {dtype!r}")
    ok = _is_bool if dtype == "bool" else _is_number
    bad = next((k for k, v in enumerate(flat) if not ok(v)), None)
    if bad is not None:
        raise SchemaError(
            f"{field}: value {bad} is {flat[bad]!r}, expected a number; the model file is damaged "
            "or was edited"
        )
    if shape is None:
        shape = [len(flat)]
    if not (isinstance(shape, list) and all(isinstance(n, int) and n >= 0 for n in shape)):
        raise SchemaError(f"{field}: shape: expected a list of sizes, got {shape!r}")
    if math.prod(shape) != len(flat):
        raise SchemaError(
            f"{field}: shape {shape} needs {math.prod(shape)} values, the file holds {len(flat)}"
        )
    return np.array(flat, dtype=dtype).reshape(shape)


def decode_value(value: Any, field: str = "value") -> Any:
    """Inverse of :func:`encode_value` (lists stay lists; dataclasses convert where needed).

    Parameters
    ----------
    value : object
        JSON data written by :func:`encode_value`.
    field : str
        Where ``value`` is in the file (in messages), e.g. ``"parameters.alpha"``.

    Raises
    ------
    SchemaError
        A malformed array (values that are not numbers, a shape that does not match) or float.
    """
    if isinstance(value, dict):
        if "__ndarray__" in value:
            return _decode_array(value, field)
        if "__float__" in value:
            try:
                return float(value["__float__"])
            except (TypeError, ValueError):
                raise SchemaError(
                    f"{field}: expected a number, got {value['__float__']!r}"
                ) from None
        return {k: decode_value(v, f"{field}.{k}") for k, v in value.items()}
    if isinstance(value, list):
        return [decode_value(v, f"{field}[{k}]") for k, v in enumerate(value)]
    return value


def has_nan(value: Any) -> bool:
    """True if a decoded parameter (number, array, nested list / dict) contains a NaN."""
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "fc" and bool(np.isnan(value).any())
    if isinstance(value, float):
        return math.isnan(value)
    if isinstance(value, (list, tuple)):
        return any(has_nan(v) for v in value)
    if isinstance(value, Mapping):
        return any(has_nan(v) for v in value.values())
    return False


def check_header(data: Any) -> None:
    """Check the top level of a model file: an object with schema, version and common fields.

    Raises
    ------
    SchemaError
        Naming the first field that is missing or malformed.
    """
    if not isinstance(data, Mapping):
        raise SchemaError(
            f"model file: expected a JSON object written by 'mrdamper fit', got a JSON "
            f"{_json_type(data)}"
        )
    if data.get("schema") != SCHEMA_NAME:
        raise SchemaError(f"schema: expected {SCHEMA_NAME!r}, got {data.get('schema')!r}")
    ver = data.get("schema_version")
    if ver not in READABLE_VERSIONS or isinstance(ver, bool):
        raise SchemaError(f"schema_version: expected one of {list(READABLE_VERSIONS)}, got {ver!r}")
    dt = data.get("sample_time")
    if dt is not None and not (_is_number(dt) and math.isfinite(dt) and dt > 0):
        raise SchemaError(f"sample_time: expected a positive interval [s] or null, got {dt!r}")
    for key in _REQUIRED:
        if key not in data:
            raise SchemaError(f"{key}: missing from model file")
    if not isinstance(data["kind"], str):
        raise SchemaError(f"kind: expected a model kind (text), got {data['kind']!r}")
    if data["input"] not in ("i", "voltage"):
        raise SchemaError(f"input: expected 'i' or 'voltage', got {data['input']!r}")
    rng = data["input_range"]
    if not (isinstance(rng, list) and len(rng) == 2 and all(_is_number(v) for v in rng)):
        raise SchemaError(f"input_range: expected two numbers [low, high], got {rng!r}")
    if not isinstance(data["parameters"], Mapping):
        raise SchemaError(
            f"parameters: expected an object, got a JSON {_json_type(data['parameters'])}"
        )
    if not isinstance(data.get("provenance", {}), Mapping):
        raise SchemaError(
            f"provenance: expected an object, got a JSON {_json_type(data['provenance'])}"
        )


def _json_type(value: Any) -> str:
    names = {dict: "object", list: "list", str: "string", bool: "boolean", type(None): "null"}
    return names.get(type(value), "number")


def _fits(value: Any, hint: Any) -> bool:
    """True when the decoded ``value`` has the type ``hint`` asks for (loosely: numbers for
    floats, sequences of numbers for tuples, arrays for ndarrays)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is Any:
        return True
    if origin is typing.Union or (origin is not None and type(None) in args):
        return any(_fits(value, a) for a in args)
    if hint is type(None):
        return value is None
    if origin is typing.Literal:
        return value in args and not isinstance(value, bool)
    if hint is float:
        return _is_number(value)
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if hint is bool:
        return isinstance(value, bool)
    if hint is str:
        return isinstance(value, str)
    if hint is np.ndarray:
        return isinstance(value, np.ndarray)
    if origin is tuple:
        if not isinstance(value, (list, tuple)):
            return False
        if len(args) == 2 and args[1] is Ellipsis:
            return all(_fits(v, args[0]) for v in value)
        return len(value) == len(args) and all(_fits(v, a) for v, a in zip(value, args))
    if origin in (Mapping, dict) or hint in (Mapping, dict):
        return isinstance(value, Mapping)
    return True  # another class (zone laws...): its own constructor checks it


def check_model_dict(cls: type, params: Mapping[str, Any]) -> None:
    """Check the decoded ``parameters`` of a model file against the fields of ``cls``.

    Raises
    ------
    SchemaError
        An unknown or missing field, a field of the wrong type, or a NaN.
    """
    fields = {f.name: f for f in dataclasses.fields(cls)}
    common = {"input", "input_range", "range_policy", "provenance"}
    unknown = sorted(set(params) - set(fields))
    if unknown:
        raise SchemaError(f"parameters: unknown field(s) {unknown} for {cls.kind!r}")  # type: ignore[attr-defined]
    missing = sorted(
        name
        for name, f in fields.items()
        if name not in common
        and name not in params
        and f.default is dataclasses.MISSING
        and f.default_factory is dataclasses.MISSING
    )
    if missing:
        raise SchemaError(f"parameters.{missing[0]}: missing from model file")
    try:
        hints = typing.get_type_hints(cls)
    except (NameError, TypeError):  # pragma: no cover - unresolvable annotation: no type check
        hints = {}
    for key, value in params.items():
        if has_nan(value):
            raise SchemaError(
                f"parameters.{key}: holds NaN; the model file is damaged or was edited"
            )
        if key in hints and not _fits(value, hints[key]):
            raise SchemaError(
                f"parameters.{key}: expected {_describe(hints[key])}, got {_short(value)}"
            )


def _describe(hint: Any) -> str:
    text = str(hint).replace("typing.", "").replace("<class '", "").replace("'>", "")
    return text.replace("numpy.ndarray", "an array").replace("collections.abc.", "")


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
