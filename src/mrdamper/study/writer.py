"""Writing a :class:`~mrdamper.study.result.StudyResult` to a folder.

:func:`write_study` builds everything in a hidden temporary folder beside the target and renames
it into place at the very end, so an interrupted or failed write never leaves a folder that looks
complete. ``report.html`` is written last inside it. The result object only holds values; this
module and :mod:`mrdamper.study.report` turn them into files.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mrdamper._io import atomic_write_text
from mrdamper.errors import OutputExistsError

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.study.result import StudyResult

__all__ = ["FIGURE_DPI", "FIGURE_FORMATS", "save_figures", "write_study"]

FIGURE_FORMATS: tuple[str, ...] = ("png", "svg")
#: Resolution of the PNG figures [dots per inch]: sharp when printed at their drawn size.
FIGURE_DPI = 150


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "fold"


def write_study(
    res: StudyResult, out_dir: str | os.PathLike[str], *, force: bool = False, figures: bool = True
) -> Path:
    """Write results, summary, models, figures (PNG + SVG) and ``report.html`` to ``out_dir``.

    Parameters
    ----------
    res : StudyResult
        The study.
    out_dir : path
        Target folder. It must not exist or be empty, unless ``force``.
    force : bool
        Replace an existing non-empty folder (only once the new one is complete).
    figures : bool
        Also draw the figures (and embed them in the report).

    Returns
    -------
    Path
        ``out_dir``.

    Raises
    ------
    OutputExistsError
        ``out_dir`` exists, is not an empty folder and ``force`` is false.
    OutputError
        ``out_dir`` is an input, holds one, is the working folder or one of its ancestors, or
        cannot be written (checked before anything is written).
    """
    from mrdamper.study._outputs import naming_output, prepare_out

    out = prepare_out(res, out_dir, force)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        _write_into(res, tmp, figures)
        _swap_into_place(tmp, out, force)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise naming_output(exc, out) from exc
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return Path(out_dir)


def _write_into(res: StudyResult, d: Path, figures: bool) -> None:
    from mrdamper.study import report
    from mrdamper.study._outputs import write_tables
    from mrdamper.study.figures import make_figures

    summary = res.summary
    write_tables(res, d, summary)
    for (fold, label), model in res.models.items():
        model.save(d / "models" / _slug(fold) / f"{_slug(label)}.json")
    for fold, an in res.analyses.items():
        if an.laws is not None and hasattr(an.laws, "to_dict"):
            text = json.dumps(an.laws.to_dict(), indent=1)
            atomic_write_text(d / "analysis" / f"{_slug(fold)}_zone_laws.json", text + "\n")
    saved = save_figures(make_figures(res), d / "figures") if figures else {}
    html = report.render_report(res, summary, saved)
    atomic_write_text(d / "report.html", html)


def save_figures(figs: Mapping[str, Any], folder: Path) -> dict[str, Any]:
    """Save each Figure as PNG and SVG in ``folder``; name -> {format: path} or the skip reason.

    Parameters
    ----------
    figs : mapping
        Name -> matplotlib Figure, or the reason (str) it was not drawn.
    folder : Path
        Target folder (created).

    Returns
    -------
    dict
        Name -> ``{"png": path, "svg": path}``, or the reason text for figures not drawn.
    """
    import matplotlib
    import matplotlib.pyplot as plt

    folder.mkdir(exist_ok=True)
    saved: dict[str, Any] = {}
    with matplotlib.rc_context({"svg.hashsalt": "mrdamper"}):
        for name, fig in figs.items():
            if isinstance(fig, str):
                saved[name] = fig
                continue
            files = {}
            for fmt in FIGURE_FORMATS:
                p = folder / f"{name}.{fmt}"
                fig.savefig(
                    p, format=fmt, dpi=FIGURE_DPI, bbox_inches="tight", metadata=_fig_metadata(fmt)
                )
                files[fmt] = p
            saved[name] = files
            plt.close(fig)
    return saved


def _fig_metadata(fmt: str) -> dict[str, Any]:
    """Fixed metadata so the same figure gives the same bytes (no dates, no software versions)."""
    if fmt == "svg":
        return {"Date": None, "Creator": None}
    if fmt == "png":
        return {"Software": None}
    return {}


def _umask() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except OSError:
        pass
    return 0o022


def _usual_permissions(folder: Path) -> None:
    """Give the finished folder the permissions of an ordinary folder (temporary files are private)."""
    mask = _umask()
    folder.chmod(0o777 & ~mask)
    for p in folder.rglob("*"):
        p.chmod((0o777 if p.is_dir() else 0o666) & ~mask)


def _swap_into_place(tmp: Path, out: Path, force: bool) -> None:
    """Move the finished folder ``tmp`` to ``out`` (replacing an empty one, or any one if ``force``)."""
    _usual_permissions(tmp)
    if not out.exists():
        os.replace(tmp, out)
        return
    if not any(out.iterdir()):
        out.rmdir()
        os.replace(tmp, out)
        return
    if not force:  # re-check: the folder may have been filled meanwhile
        raise OutputExistsError(
            f"{out}: folder filled while writing; pass force=True to replace it"
        )
    trash = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
    os.replace(out, trash / out.name)
    os.replace(tmp, out)
    shutil.rmtree(trash, ignore_errors=True)
