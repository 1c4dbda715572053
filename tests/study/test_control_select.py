"""``select --for control``'s split: whole loop runs held out, every other record trains."""

from __future__ import annotations

import types

import pytest

from mrdamper.errors import DataValidationError
from mrdamper.study.control_select import split_loop_records


def _rec(name: str, displacement: str, pattern: str = "APRBS") -> types.SimpleNamespace:
    return types.SimpleNamespace(
        name=name, metadata={"displacement": displacement, "pattern": pattern}
    )


def test_every_second_loop_run_is_held_out_with_both_its_records() -> None:
    runs = [f"quarter car (skyhook, sp1 model), ISO {r} @ 20 m/s" for r in "BCD"]
    loop = [
        _rec(f"ctrl{k + 1:02d}", runs[k // 2], ("loop current", "APRBS")[k % 2]) for k in range(6)
    ]
    table_ii = [_rec("exp2_rep01", "Road Profile"), _rec("stroke01", "sine 18.0 mm @ 0.5 Hz")]
    train, held = split_loop_records([*table_ii, *reversed(loop)])
    assert [e.name for e in held] == ["ctrl03", "ctrl04"]  # run C, both currents
    assert {e.name for e in train} == {
        "exp2_rep01",
        "stroke01",
        "ctrl01",
        "ctrl02",
        "ctrl05",
        "ctrl06",
    }
    # Table II's APRBS records are not loop-like: their displacement is not a quarter car's
    assert all(e.name.startswith("ctrl") for e in held)


def test_records_without_two_loop_runs_are_refused_in_one_line() -> None:
    one = [_rec("ctrl01", "quarter car (soft, sp1 model), ISO B @ 25 m/s"), _rec("e", "sine")]
    with pytest.raises(DataValidationError, match="at least two loop runs"):
        split_loop_records(one)  # type: ignore[arg-type]
