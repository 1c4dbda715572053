"""Exception types raised by mrdamper.

Every error names the offending field, the value found and what was expected, so that a
user can fix the input without reading the source.
"""

from __future__ import annotations

__all__ = [
    "ConformanceError",
    "DataValidationError",
    "IdentificationError",
    "MrDamperError",
    "Note",
    "OutOfRangeError",
    "OutputError",
    "OutputExistsError",
    "PlausibilityWarning",
    "PluginError",
    "SchemaError",
    "SimulationDivergedError",
    "UnitError",
    "interrupt_in_chain",
]


class MrDamperError(Exception):
    """Base class of every error raised on purpose by mrdamper."""


class DataValidationError(MrDamperError, ValueError):
    """Input data are malformed: wrong length, NaN, non-uniform time, missing column, ...

    Parameters
    ----------
    field : str
        Name of the offending field or column (e.g. ``"t"``, ``"F"``).
    message : str
        What was found and what was expected.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        super().__init__(f"{field}: {message}")


class UnitError(DataValidationError):
    """A unit string is unknown or does not fit the quantity of its column."""


class SchemaError(MrDamperError, ValueError):
    """A saved file does not follow the expected schema or schema version."""


class PluginError(MrDamperError, RuntimeError):
    """A model family of another package (a plug-in) cannot be loaded: its module or classes are
    missing or are not what its kind-table row says."""


class ConformanceError(MrDamperError, AssertionError):
    """A model family fails the conformance checks (:func:`mrdamper.check_family`)."""


class OutOfRangeError(MrDamperError, ValueError):
    """A scheduling signal leaves the range a model was identified on."""


class IdentificationError(MrDamperError, RuntimeError):
    """Identification failed: singular regression, no convergence, too few samples, ..."""


class SimulationDivergedError(MrDamperError, RuntimeError):
    """A free-run simulation diverged or became non-finite.

    Parameters
    ----------
    model : str
        Model kind, e.g. ``"p15"``.
    sample : int
        Index of the first sample where the state was non-finite or exceeded the bound.
    message : str
        Details.
    """

    def __init__(self, model: str, sample: int, message: str) -> None:
        self.model = model
        self.sample = sample
        super().__init__(f"{model}: simulation diverged at sample {sample}: {message}")


class OutputError(MrDamperError, ValueError):
    """An output location is unsafe or unusable: it is an input, contains one, is the working
    folder or an ancestor, is not a regular file, or cannot be written."""


class OutputExistsError(MrDamperError, FileExistsError):
    """An output file already exists and overwriting was not requested (use ``force``)."""


class Note(UserWarning):
    """Information about a decision taken on the user's behalf (a rate chosen, a time base
    regenerated, a setting renamed). Issued with :func:`warnings.warn`; the command line prints it
    as one ``note: ...`` line."""


def interrupt_in_chain(exc: BaseException) -> bool:
    """True if ``exc`` is, or was caused by, a :class:`KeyboardInterrupt`.

    A compiled kernel interrupted by Ctrl-C can surface as ``SystemError`` whose cause or context
    is the ``KeyboardInterrupt``; such an error is an interruption, not a failure of the model.

    Parameters
    ----------
    exc : BaseException
        The exception to inspect (with its ``__cause__`` / ``__context__`` chain).
    """
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, KeyboardInterrupt):
            return True
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__
    return False


class PlausibilityWarning(UserWarning):
    """A record holds values no MR damper test produces (a stroke of metres, a current of
    hundreds of amperes): usually wrong declared units. See :mod:`mrdamper.data.plausibility`."""
