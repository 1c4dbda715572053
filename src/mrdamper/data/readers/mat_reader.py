"""Read MATLAB ``.mat`` files: v4/v5/v7 through SciPy, v7.3 (HDF5) through h5py.

Each channel is a numeric vector variable (row or column) at the top level of the file, or a
field of the struct named by ``struct=``. Variable names are matched to channels like CSV
headers (``columns=`` or the alias table).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mrdamper.data.experiment import DEFAULT_TIME_TOLERANCE, Experiment, NanPolicy
from mrdamper.data.readers._build import build_experiment, existing_file
from mrdamper.errors import DataValidationError, MrDamperError

__all__ = ["mat_version", "read_mat"]

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def mat_version(path: str | os.PathLike[str]) -> str:
    """Return ``"v4"``, ``"v5"`` (v5/v6/v7) or ``"v7.3"`` for a MATLAB file.

    Raises
    ------
    DataValidationError
        If the file is empty or not a MATLAB file.
    """
    from scipy.io.matlab import matfile_version

    p = Path(path)
    if p.stat().st_size == 0:
        raise DataValidationError("file", f"{p} is empty; expected a MATLAB .mat file")
    try:
        major, _minor = matfile_version(str(p))
    except Exception as exc:  # noqa: BLE001 - scipy raises ValueError / MatReadError for non-MAT content
        with p.open("rb") as fh:
            head = fh.read(520)
        if head[:8] == _HDF5_SIGNATURE or head[512:520] == _HDF5_SIGNATURE:
            return "v7.3"  # HDF5 without the MATLAB text header (e.g. written by h5py)
        raise DataValidationError("file", f"{p} is not a MATLAB .mat file ({exc})") from None
    return {0: "v4", 1: "v5", 2: "v7.3"}.get(major, f"unknown ({major})")


def _vectors(items: Mapping[str, Any]) -> tuple[dict[str, np.ndarray], list[str]]:
    """Keep numeric arrays that are vectors; return them and the names of the rest."""
    out: dict[str, np.ndarray] = {}
    skipped: list[str] = []
    for key, val in items.items():
        arr = np.asarray(val)
        if (
            arr.dtype.kind in "iufcb"
            and arr.ndim >= 1
            and max(arr.shape) == arr.size
            and arr.size > 1
        ):
            out[str(key)] = arr.ravel()
        else:
            skipped.append(str(key))
    return out, skipped


def _read_v5(p: Path, struct: str | None) -> tuple[dict[str, np.ndarray], list[str]]:
    from scipy.io import loadmat

    try:
        mat = loadmat(str(p), simplify_cells=True)
    except Exception as exc:  # noqa: BLE001
        raise DataValidationError(
            "file", f"{p} could not be read as a MATLAB v5 file ({exc})"
        ) from None
    variables = {k: v for k, v in mat.items() if not k.startswith("__")}
    if struct is not None:
        if struct not in variables or not isinstance(variables[struct], dict):
            structs = [k for k, v in variables.items() if isinstance(v, dict)]
            raise DataValidationError(
                "struct", f"{p} has no struct variable {struct!r}; structs found: {structs}"
            )
        variables = variables[struct]
    return _vectors(variables)


def _read_v73(p: Path, struct: str | None) -> tuple[dict[str, np.ndarray], list[str]]:
    try:
        import h5py
    except ImportError:
        raise MrDamperError(
            f"file: {p} is a MATLAB v7.3 (HDF5) file; reading it needs h5py: install the "
            "'mat73' extra (pip install 'mrdamper[mat73]')"
        ) from None
    with h5py.File(p, "r") as f:
        group: Any = f
        if struct is not None:
            if struct not in f or not isinstance(f[struct], h5py.Group):
                structs = [k for k in f if isinstance(f[k], h5py.Group) and not k.startswith("#")]
                raise DataValidationError(
                    "struct", f"{p} has no struct variable {struct!r}; structs found: {structs}"
                )
            group = f[struct]
        items: dict[str, Any] = {}
        skipped: list[str] = []
        for key in group:
            if key.startswith("#"):
                continue
            obj = group[key]
            cls = obj.attrs.get("MATLAB_class", b"")
            cls = cls.decode() if isinstance(cls, bytes) else str(cls)
            if isinstance(obj, h5py.Dataset) and cls not in ("char", "cell", "struct", "logical"):
                items[key] = obj[()]
            else:
                skipped.append(key)
    vec, rest = _vectors(items)
    return vec, skipped + rest


def read_mat(
    path: str | os.PathLike[str],
    *,
    struct: str | None = None,
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    nan_policy: NanPolicy = "raise",
    max_gap: int = 5,
    resample_fs: float | None = None,
    fs: float | None = None,
    derive_velocity: bool | float = False,
    name: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    time_tolerance: float = DEFAULT_TIME_TOLERANCE,
    plausible_max: Mapping[str, float] | None = None,
) -> Experiment:
    """Read one record from a MATLAB ``.mat`` file (v5 via SciPy, v7.3 via h5py).

    Parameters
    ----------
    path : path-like
        The file.
    struct : str, optional
        Name of a struct variable whose fields are the channels; default: top-level variables.
    columns, units, nan_policy, max_gap, resample_fs, fs, derive_velocity, name, metadata
        See :func:`~mrdamper.data.readers.read_csv` (``columns`` maps variable names).
    time_tolerance, plausible_max
        See :func:`~mrdamper.data.readers.read_csv` (``columns`` maps variable names).

    Returns
    -------
    Experiment
        The record in SI units; ``metadata["mat_version"]`` says which format was read and
        ``metadata["ignored_columns"]`` lists variables that are not channels.

    Raises
    ------
    FileNotFoundError, DataValidationError, UnitError
        As for :func:`~mrdamper.data.readers.read_csv`.
    MrDamperError
        For a v7.3 file when h5py is not installed (names the ``mat73`` extra).
    """
    p = existing_file(path)
    version = mat_version(p)
    if version == "v7.3":
        raw, skipped = _read_v73(p, struct)
    elif version in ("v4", "v5"):
        raw, skipped = _read_v5(p, struct)
    else:
        raise DataValidationError("file", f"{p}: unsupported MATLAB file version {version}")
    if not raw:
        raise DataValidationError(
            "file",
            f"{p} holds no numeric vector variables (found {skipped}); expected t, x, v, F, i ...",
        )
    meta = {"mat_version": version}
    if struct is not None:
        meta["mat_struct"] = struct
    meta.update(metadata or {})
    exp = build_experiment(
        raw,
        path=p,
        columns=columns,
        units=units,
        nan_policy=nan_policy,
        max_gap=max_gap,
        resample_fs=resample_fs,
        fs=fs,
        derive_velocity=derive_velocity,
        name=name,
        metadata=meta,
        time_tolerance=time_tolerance,
        plausible_max=plausible_max,
    )
    if skipped:
        ignored = list(exp.metadata.get("ignored_columns", [])) + skipped
        exp = exp.replace(metadata={**exp.metadata, "ignored_columns": ignored})
    return exp
