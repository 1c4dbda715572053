"""Every kind of the kind table through the control tools, on a tiny default DoE.

Each kind is fitted once per session (:func:`doe_models`: Table II at scale 0.07 and 200 Hz,
sequences 1 and 6, the conformance suite's short settings) and then, on a short ISO C road:

* drives the quarter car as its own damper with a passive and a semi-active controller
  (:func:`~mrdamper.control.compare_controllers`, the halving check included), its input within
  the rated range of the rig's damper;
* gives the input for a desired force on a record (:func:`~mrdamper.control.inverse_current`);
* controls the rig's reference damper (``--plant rig``);
* is the plant of the SP-1 model's controller.

The outcomes form the table of ``docs/control.md`` ("Every kind through the control tools"): the
test fails when the page differs from them (``MRDAMPER_WRITE_MATRIX=1`` writes it).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrdamper.control import compare_controllers, inverse_current
from mrdamper.control.loop.closed_loop import simulate_closed_loop
from mrdamper.control.loop.quarter_car import iso_road
from mrdamper.kinds import KINDS
from tests.conftest import REPO_ROOT
from tests.control.conftest import LazyFits

#: The tools of the matrix, in table order: column title and what it runs.
TOOLS = ("quarter car", "inverse", "--plant rig", "plant of sp1")
DOC = REPO_ROOT / "docs" / "control.md"
BEGIN = "<!-- kind-matrix: written by tests/control/test_kind_matrix.py -->"
END = "<!-- /kind-matrix -->"
#: The rated range of the rig's default damper (quiroz2022) [A].
RATED = (0.0, 1.0)


def _tiny_doe() -> list[Any]:
    from mrdamper.rig.doe import table_ii

    return list(table_ii(seed=0, scale=0.07, fs=200.0, experiments=[1, 6]))


@pytest.fixture(scope="session")
def doe_models() -> LazyFits:
    """Every kind fitted lazily on the tiny default DoE (see the module docstring)."""
    return LazyFits(_tiny_doe)


def _road() -> Any:
    return iso_road("C", speed=20.0, duration=1.0, fs=1000.0, seed=0)


def _outcome(run: Any) -> str:
    """``ok`` or the one-line reason a tool refused."""
    try:
        run()
    except Exception as exc:  # the matrix records the refusal  # noqa: BLE001
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return f"refused: {text}"
    return "ok"


def _quarter_car(model: Any) -> None:
    cmp = compare_controllers(
        model,
        road_classes=("C",),
        bump=False,
        controllers=("soft", "hard", "skyhook"),
        duration=1.0,
    )
    assert not cmp.refused, cmp.refused
    table = cmp.table()
    assert (table["status"] == "ok").all()
    hard = cmp.results[(cmp.roads[0], "hard")]
    assert RATED[0] <= hard.i.min() and hard.i.max() <= RATED[1]  # the rated range, not beyond
    sky = cmp.results[(cmp.roads[0], "skyhook")]
    assert np.all(np.isfinite(sky.i)) and RATED[0] <= sky.i.min() and sky.i.max() <= RATED[1]


def _inverse(model: Any, record: Any) -> None:
    res = inverse_current(model, record, record.F)
    assert np.all(np.isfinite(res.i))


def _plant_rig(model: Any) -> None:
    r = simulate_closed_loop(model, _road(), "skyhook", plant="rig")
    assert np.all(np.isfinite(r.F))


def _plant_of(controller: Any, plant: Any) -> None:
    r = simulate_closed_loop(controller, _road(), "skyhook", plant=plant)
    assert np.all(np.isfinite(r.F))


def kind_outcomes(models: LazyFits) -> dict[str, dict[str, str]]:
    """Outcome of every tool for every kind of the table."""
    out: dict[str, dict[str, str]] = {}
    for row in KINDS:
        m = models[row.kind]
        record = models.records[0].slice(0, 200)
        out[row.kind] = {
            "quarter car": _outcome(lambda m=m: _quarter_car(m)),
            "inverse": _outcome(lambda m=m, r=record: _inverse(m, r)),
            "--plant rig": _outcome(lambda m=m: _plant_rig(m)),
            "plant of sp1": _outcome(lambda m=m: _plant_of(models["sp1"], m)),
        }
    return out


def matrix_markdown(outcomes: dict[str, dict[str, str]]) -> str:
    """The table of ``docs/control.md`` from the outcomes."""
    lines = ["| kind | " + " | ".join(f"`{t}`" if t.startswith("-") else t for t in TOOLS) + " |"]
    lines.append("|---" * (len(TOOLS) + 1) + "|")
    for kind, cells in outcomes.items():
        lines.append(f"| {kind} | " + " | ".join(cells[t] for t in TOOLS) + " |")
    return "\n".join(lines)


def _doc_block(text: str) -> str:
    m = re.search(re.escape(BEGIN) + r"\n(.*?)\n" + re.escape(END), text, re.DOTALL)
    assert m is not None, f"{DOC.name}: no block between {BEGIN!r} and {END!r}"
    return m.group(1)


@pytest.mark.slow
def test_every_kind_through_the_control_tools(doe_models: LazyFits) -> None:
    outcomes = kind_outcomes(doe_models)
    table = matrix_markdown(outcomes)
    failed = {(k, t): c for k, cells in outcomes.items() for t, c in cells.items() if c != "ok"}
    assert not failed, failed  # every kind through every tool
    text = DOC.read_text(encoding="utf-8")
    if os.environ.get("MRDAMPER_WRITE_MATRIX") == "1":
        DOC.write_text(text.replace(_doc_block(text), table), encoding="utf-8")
        text = DOC.read_text(encoding="utf-8")
    assert _doc_block(text) == table, "docs/control.md: the kind matrix is stale (see docstring)"


def test_the_table_is_the_kind_table() -> None:
    """The page lists every kind of the table, in its order, and every tool."""
    block = _doc_block(Path(DOC).read_text(encoding="utf-8")).splitlines()
    assert [line.split("|")[1].strip() for line in block[2:]] == [row.kind for row in KINDS]
    assert block[:2] == matrix_markdown({}).splitlines()
