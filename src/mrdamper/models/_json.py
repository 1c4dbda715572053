"""The model file's JSON encoding: arrays and non-finite floats as exact JSON, the schema check.

Re-exported by :mod:`mrdamper.models.base` (where the model file is written and read).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from mrdamper.errors import SchemaError

__all__ = ["SCHEMA_NAME", "SCHEMA_VERSION", "decode_value", "encode_value"]

SCHEMA_NAME = "mrdamper.model"
SCHEMA_VERSION = 1


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


def decode_value(value: Any) -> Any:
    """Inverse of :func:`encode_value` (lists stay lists; dataclasses convert where needed).

    Parameters
    ----------
    value : object
        JSON data written by :func:`encode_value`.
    """
    if isinstance(value, dict):
        if "__ndarray__" in value:
            arr = np.array(value["__ndarray__"], dtype=value.get("dtype", "float64"))
            return arr.reshape(value["shape"])
        if "__float__" in value:
            return float(value["__float__"])
        return {k: decode_value(v) for k, v in value.items()}
    if isinstance(value, list):
        return [decode_value(v) for v in value]
    return value


def _has_nan(value: Any) -> bool:
    """True if a decoded parameter (number, array, nested list / dict) contains a NaN."""
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "fc" and bool(np.isnan(value).any())
    if isinstance(value, float):
        return math.isnan(value)
    if isinstance(value, (list, tuple)):
        return any(_has_nan(v) for v in value)
    if isinstance(value, Mapping):
        return any(_has_nan(v) for v in value.values())
    return False


def _check_schema(data: Mapping[str, Any]) -> None:
    if data.get("schema") != SCHEMA_NAME:
        raise SchemaError(f"schema: expected {SCHEMA_NAME!r}, got {data.get('schema')!r}")
    ver = data.get("schema_version")
    if ver != SCHEMA_VERSION:
        raise SchemaError(f"schema_version: expected {SCHEMA_VERSION}, got {ver!r}")
    for key in ("kind", "input", "input_range", "parameters"):
        if key not in data:
            raise SchemaError(f"{key}: missing from model file")
