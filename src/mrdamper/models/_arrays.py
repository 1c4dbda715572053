"""Array helpers shared by the compiled kernel modules of the model families (private)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["readonly"]


def readonly(a: Any, dtype: Any = np.float64) -> np.ndarray:
    """``a`` as a C-contiguous array of ``dtype`` that is read-only (a view: no copy when ``a``
    already has that type and layout), so that kernels see one argument type.

    A read-only array and a writable one are different argument types to numba; passing every
    input array through this keeps one compiled signature per kernel (see
    :mod:`mrdamper.compiled`).
    """
    out = np.ascontiguousarray(a, dtype=dtype)
    if out.flags.writeable:
        out = out.view()
        out.flags.writeable = False
    return out
