"""The outcome of a study and how it is written to disk.

:meth:`StudyResult.write` builds everything in a hidden temporary folder beside the target and
renames it into place at the very end, so an interrupted or failed write never leaves a folder
that looks complete. ``report.html`` is written last inside it.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from mrdamper._io import atomic_write_text
from mrdamper.data import Experiment
from mrdamper.errors import OutputExistsError
from mrdamper.study.analysis_step import AnalysisOutcome
from mrdamper.study.protocol import ModelSpec, Protocol
from mrdamper.study.tables import headline, summarize

__all__ = ["FIGURE_FORMATS", "Showcase", "StudyResult"]

FIGURE_FORMATS: tuple[str, ...] = ("png", "svg")


@dataclass(frozen=True, eq=False)
class Showcase:
    """One record with every model's free-run prediction, for the time-domain figures.

    Attributes
    ----------
    fold : str
        Fold whose models made the predictions.
    record : Experiment
        The record (scored in that fold).
    predictions : dict
        Model label -> predicted force [N] (ndarray) or the error text when it failed.
    kinds : dict
        Model label -> registry kind.
    """

    fold: str
    record: Experiment
    predictions: Mapping[str, Any]
    kinds: Mapping[str, str] = field(default_factory=dict)

    def ok(self) -> dict[str, Any]:
        """Only the successful predictions."""
        return {k: v for k, v in self.predictions.items() if not isinstance(v, str)}


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "fold"


@dataclass(frozen=True, eq=False)
class StudyResult:
    """Everything a study produced.

    Attributes
    ----------
    protocol : Protocol
        The protocol run (with the models actually used in ``specs``).
    specs : tuple of ModelSpec
        Models run, in display order.
    results : DataFrame
        One row per fold x model x scored record (see ``docs/study.md`` for the columns).
    fits : DataFrame
        One row per fold x model: fit status, time, training size, error.
    roles : DataFrame
        Which record had which role (analysis, train, score) in which fold.
    models : dict
        ``(fold, label) -> FittedModel`` for every successful fit.
    analyses : dict
        ``fold -> AnalysisOutcome`` of the force-velocity analysis.
    showcase, hysteresis : Showcase or None
        Records and predictions drawn in Figs. 6, 9, 10 and Fig. 4.
    info : dict
        Seed, executor, wall time, platform.
    """

    protocol: Protocol
    specs: tuple[ModelSpec, ...]
    results: pd.DataFrame
    fits: pd.DataFrame
    roles: pd.DataFrame
    models: Mapping[tuple[str, str], Any]
    analyses: Mapping[str, AnalysisOutcome]
    showcase: Showcase | None = None
    hysteresis: Showcase | None = None
    info: Mapping[str, Any] = field(default_factory=dict)

    @property
    def labels(self) -> list[str]:
        """Model labels in display order."""
        return [s.label for s in self.specs]

    @property
    def summary(self) -> pd.DataFrame:
        """Per-model statistics (see :func:`~mrdamper.study.tables.summarize`)."""
        return summarize(self.results, self.labels)

    def headline(self, model: str = "lpv") -> dict[str, Any]:
        """``model`` against the best of the paper's classical models (P-15, SP-1..SP-4)."""
        return headline(self.summary, model)

    def to_frame(self) -> pd.DataFrame:
        """The per-record results table."""
        return self.results

    def overlap(self) -> pd.DataFrame:
        """Scored records that also trained a model or the analysis in the same fold (empty when none)."""
        r = self.roles
        sc = r[r["role"] == "score"][["fold", "record"]]
        tr = r[r["role"] != "score"][["fold", "record", "role"]]
        return sc.merge(tr, on=["fold", "record"], how="inner")

    def figures(self) -> dict[str, Any]:
        """Build every figure: name -> matplotlib Figure (or the reason it was skipped, a str)."""
        from mrdamper.study.figures import make_figures

        return make_figures(self)

    def plot(self, index: str = "esr", ax: Any = None) -> Any:
        """Box plot of an index per model (Figs. 7 and 8); returns the Axes."""
        from mrdamper.plotting import plot_index_boxes

        return plot_index_boxes(self.results, index=index, order=self.labels, ax=ax)

    # ------------------------------------------------------------------ writing
    def write(self, out_dir: str | os.PathLike[str], *, force: bool = False, figures: bool = True) -> Path:
        """Write results, summary, models, figures (PNG + SVG) and ``report.html`` to ``out_dir``.

        Parameters
        ----------
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
        """
        from mrdamper.study._outputs import naming_output, prepare_out

        out = prepare_out(self, out_dir, force)
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
        try:
            self._write_into(tmp, figures)
            _swap_into_place(tmp, out, force)
        except OSError as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            raise naming_output(exc, out) from exc
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return Path(out_dir)

    def _write_into(self, d: Path, figures: bool) -> None:
        from mrdamper.study._outputs import write_tables
        from mrdamper.study.report import render_report

        summary = self.summary
        write_tables(self, d, summary)
        for (fold, label), model in self.models.items():
            model.save(d / "models" / _slug(fold) / f"{_slug(label)}.json")
        for fold, an in self.analyses.items():
            if an.laws is not None and hasattr(an.laws, "to_dict"):
                text = json.dumps(an.laws.to_dict(), indent=1)
                atomic_write_text(d / "analysis" / f"{_slug(fold)}_zone_laws.json", text + "\n")
        saved = _save_figures(self.figures(), d / "figures") if figures else {}
        html = render_report(self, summary, saved)
        atomic_write_text(d / "report.html", html)


def _save_figures(figs: Mapping[str, Any], folder: Path) -> dict[str, Any]:
    """Save each Figure as PNG and SVG in ``folder``; name -> {format: path} or the skip reason."""
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
                fig.savefig(p, format=fmt, dpi=110, bbox_inches="tight", metadata=_fig_metadata(fmt))
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
        raise OutputExistsError(f"{out}: folder filled while writing; pass force=True to replace it")
    trash = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
    os.replace(out, trash / out.name)
    os.replace(tmp, out)
    shutil.rmtree(trash, ignore_errors=True)
