"""Identification of the Bingham model: weighted linear least squares over all records, folded
record block by record block into a QR factor (never one big matrix). Private machinery of
:class:`~mrdamper.models.bingham.BinghamEstimator`."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from mrdamper.data import Experiment
from mrdamper.errors import DataValidationError, IdentificationError
from mrdamper.models import _scale
from mrdamper.progress import report

__all__ = ["identify"]


def identify(
    records: Sequence[Experiment],
    electrical: Sequence[np.ndarray],
    deg: int,
    weighting: str,
    sign: Callable[[np.ndarray], np.ndarray],
    source: str,
) -> tuple[np.ndarray, dict[str, Any]]:
    """Coefficients ``[fc_0..fc_deg, c0_0..c0_deg, f0]`` of ``F = fc(e) sign(v) + c0(e) v + f0``.

    Parameters
    ----------
    records : sequence of Experiment
        Training records.
    electrical : sequence of ndarray
        Their electrical input [A] or [V].
    deg : int
        Polynomial degree of ``fc`` and ``c0`` in the input.
    weighting : {"record", "none"}
        Each record weighted by ``1 / (std(F) sqrt(N))``, or every sample equally.
    sign : callable
        ``sign(v)`` or its smoothed version.
    source : str
        Name of the input (for messages).

    Raises
    ------
    IdentificationError
        The regression is rank deficient (e.g. fewer input levels than ``deg + 1``).
    """

    def blocks() -> Iterator[np.ndarray]:  # weighted rows [X y], folded into a QR factor
        for k, (exp, el) in enumerate(zip(records, electrical)):
            report("least squares: record", k, len(records))
            w = 1.0
            if weighting == "record":
                sd = float(np.std(exp.F))
                if sd == 0.0:
                    raise DataValidationError(
                        "F", f"record {exp.name!r} has constant force; use weighting='none'"
                    )
                w = 1.0 / (sd * math.sqrt(exp.n))
            for k0 in range(0, exp.n, _scale.QR_BLOCK):
                sl = slice(k0, k0 + _scale.QR_BLOCK)
                e, v = el[sl], exp.v[sl]
                powers = np.vander(e, deg + 1, increasing=True)
                yield (
                    np.hstack(
                        [
                            powers * sign(v)[:, None],
                            powers * v[:, None],
                            np.ones((e.size, 1)),
                            exp.F[sl, None],
                        ]
                    )
                    * w
                )

    Rf = _scale.fold_qr(blocks())  # Q Rf = [X y]: X c - y = Q (Rf[:, :-1] c - Rf[:, -1])
    report("least squares: record", len(records), len(records))
    n_rows = sum(e.n for e in records)
    X, y = Rf[:, :-1], Rf[:, -1]
    coef, _, rank, sv = np.linalg.lstsq(X, y, rcond=None)
    if rank < X.shape[1]:
        levels = np.unique(np.round(np.concatenate(list(electrical)), 9)).size
        raise IdentificationError(
            f"bingham: regression is rank deficient (rank {rank} of {X.shape[1]}); "
            f"degree={deg} needs at least {deg + 1} distinct '{source}' levels and "
            f"moving records (found {levels} level(s))"
        )
    provenance = {
        "method": "linear least squares",
        "records": [e.name for e in records],
        "n_samples": int(n_rows),
        "weighting": weighting,
        "degree": deg,
        "cond_X": float(sv[0] / sv[-1]),
        "weighted_rms_residual": float(np.linalg.norm(X @ coef - y) / math.sqrt(n_rows)),
    }
    return coef, provenance
