"""Which options of a command have no meaning in which of its modes: the one table.

A command with modes (``quartercar`` with ``--plant``, ``--tune`` or ``--c-inverse``, ``export``
with its ``--format``, ``info --example``, ``inverse --method exact``, ``study`` / ``demo`` with
``--no-control``, ``rig doe`` without the control extension) honours every option in every mode
except those this table lists for the mode, which are refused in one line
(:func:`refuse_unused`) when given on the command line: an option is never silently dropped.
Every other command has one mode and honours all its options. ``tests/cli/test_option_modes.py``
walks every command's options against this table.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mrdamper.cli._records import READER_OPTIONS
from mrdamper.errors import DataValidationError

__all__ = ["MODES", "Mode", "refuse_unused"]


@dataclass(frozen=True)
class Mode:
    """A mode of a command and the options it refuses.

    Parameters
    ----------
    name : str
        How the mode is entered, as the user types it (``"--plant"``, ``"--format mat"``).
    refused : tuple of str
        Options (their first flag) that have no meaning in this mode.
    why : str
        The reason, ending the one-line error.
    """

    name: str
    refused: tuple[str, ...]
    why: str


_BUMP = ("--bump", "--bump-height", "--bump-length")
_CONTROL = ("--control-roads", "--control-duration")
#: The reader options (:data:`mrdamper.cli._records.READER_OPTIONS`) as typed.
_READER = tuple("--" + name.replace("_", "-") for name in READER_OPTIONS)

#: Command (as typed: ``"rig doe"``) -> its modes; commands not listed have one mode.
MODES: dict[str, tuple[Mode, ...]] = {
    "info": (
        Mode(
            "--example",
            ("--pattern", *_READER),
            "the built-in example is generated on the virtual rig, not read from files",
        ),
    ),
    "quartercar": (
        Mode(
            "--c-inverse",
            ("--plant", "--reg", "--rate", "--tune"),
            "the C inverse drives the model as its own damper with the settings of its export",
        ),
        Mode(
            "--plant",
            _BUMP,
            "the predicted-against-achieved comparison runs the ISO roads only (drop --plant "
            "for the bump)",
        ),
        Mode(
            "--plant",
            ("--i-range",),
            "model and plant run within the damper's rated range (the identified range within the "
            "rig damper's, a note says which)",
        ),
        Mode(
            "--tune",
            (
                *_BUMP,
                "--controllers",
                "--c-sky",
                "--c-ground",
                "--alpha",
                "--reg",
                "--rate",
                "--i-range",
            ),
            "the sweep covers every controller over its own grid of gains on the ISO roads, with "
            "the inverse's default settings",
        ),
    ),
    "export": (
        Mode(
            "--format mat",
            ("--name", "--reg", "--dt", "--inverse"),
            "the .mat file holds the state-space matrices only (C code and FMUs take them)",
        ),
        Mode(
            "--format json",
            ("--name", "--reg", "--dt", "--inverse"),
            "the JSON file holds the state-space matrices only (C code and FMUs take them)",
        ),
        Mode("--format c", ("--inverse",), "the C export always holds the model and its inverse"),
        Mode(
            "--format fmu",
            ("--reg",),
            "the FMU of the model has no inverse to regularise (the inverse's FMU: add --inverse)",
        ),
    ),
    "inverse": (
        Mode(
            "--method exact",
            ("--reg", "--rate", "--horizon"),
            "the exact inverse has no regularisation, rate bound or lead horizon",
        ),
    ),
    "study": (
        Mode("--no-control", (*_CONTROL, "--control-plant"), "the control step is skipped"),
        Mode("--scheduler", ("--workers",), "the Dask cluster's workers run the study"),
    ),
    "demo": (Mode("--no-control", _CONTROL, "the control step is skipped"),),
    "select": (
        Mode(
            "--for control",
            ("--folds", "--n-folds", "--inside-only", "--workers", "--no-halving", "--time-budget"),
            "each kind is fitted once, on the records less the held-out loop-like ones",
        ),
        Mode(
            "--for fit",
            ("--loop-roads", "--loop-speeds", "--loop-duration"),
            "the loop's roads are those of the closed-loop check (--for control)",
        ),
    ),
    "rig doe": (
        Mode(
            "--extension none",
            ("--loop-model",),
            "the loop model drives the control extension only (--extension control)",
        ),
        Mode("--plan-only", ("--format",), "a test plan is written as CSV commands"),
    ),
}


def _given(ctx: Any, flag: str) -> bool:
    """Whether the option ``flag`` of the running command was given (command line, environment)."""
    for p in ctx.command.params:
        if flag in (*p.opts, *getattr(p, "secondary_opts", ())):
            source = ctx.get_parameter_source(p.name)
            return source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")
    raise KeyError(f"{ctx.command.name}: no option {flag}")  # the table names a stale option


def refuse_unused(ctx: Any, command: str, active: set[str] | tuple[str, ...]) -> None:
    """Refuse, in one line, an option given that one of the ``active`` modes of ``command`` has no
    use for.

    Parameters
    ----------
    ctx : typer.Context or None
        The running command's context (None when the command function is called from Python:
        nothing is checked).
    command : str
        Key of :data:`MODES`.
    active : set of str
        The names of the modes the options given put the command in.

    Raises
    ------
    DataValidationError
        Naming the option, the mode and why: ``--bump-height: not with --plant: ...``.
    """
    if ctx is None:
        return
    for mode in MODES[command]:
        if mode.name not in active:
            continue
        for flag in mode.refused:
            if _given(ctx, flag):
                raise DataValidationError(flag, f"not with {mode.name}: {mode.why}")
