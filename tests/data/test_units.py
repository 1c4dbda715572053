"""The unit table: known conversion factors, wrong-quantity and unknown-unit errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mrdamper.data.units import (
    CHANNEL_QUANTITY,
    UNITS,
    canonical_unit,
    from_si,
    parse_unit_assignments,
    si_factor,
    to_si,
)
from mrdamper.errors import UnitError


@pytest.mark.parametrize(
    ("channel", "unit", "factor"),
    [
        # Definitions: 1 in = 25.4 mm exactly; 1 lbf = 0.45359237 kg * 9.80665 m/s^2 exactly.
        ("x", "in", 0.0254),
        ("v", "in/s", 0.0254),
        ("v", "in/sec", 0.0254),
        ("F", "lbf", 0.45359237 * 9.80665),
        ("F", "kN", 1000.0),
        ("x", "cm", 0.01),
        ("x", "mm", 0.001),
        ("v", "mm/s", 0.001),
        ("v", "cm/s", 0.01),
        ("i", "mA", 0.001),
        ("t", "ms", 0.001),
        ("voltage", "V", 1.0),
    ],
)
def test_known_factors(channel: str, unit: str, factor: float) -> None:
    assert si_factor(channel, unit) == pytest.approx(factor, rel=1e-15)


def test_every_channel_has_its_si_unit_with_factor_one() -> None:
    for ch, q in CHANNEL_QUANTITY.items():
        si = [u for u, f in UNITS[q].items() if f == 1.0]
        assert len(si) == 1, ch


def test_to_si_copies_and_converts() -> None:
    a = np.array([1.0, -2.5])
    out = to_si(a, "mm", channel="x")
    np.testing.assert_array_equal(out, [0.001, -0.0025])
    out[0] = 5.0
    assert a[0] == 1.0
    assert to_si(a, "m", channel="x") is not a


def test_wrong_quantity_names_column() -> None:
    with pytest.raises(UnitError, match="measures force") as info:
        si_factor("x", "kN", column="Disp")
    assert info.value.field == "Disp"


def test_unknown_unit_names_column() -> None:
    with pytest.raises(UnitError, match="unknown unit 'furlong'") as info:
        to_si([1.0], "furlong", channel="x", column="pos")
    assert info.value.field == "pos"
    with pytest.raises(UnitError, match="string"):
        canonical_unit(3)  # type: ignore[arg-type]
    with pytest.raises(UnitError, match="case|unknown"):
        canonical_unit("MA")  # units are case sensitive: mega-ampere is not milli-ampere


def test_parse_unit_assignments() -> None:
    assert parse_unit_assignments(["x=mm", " F = kN "]) == {"x": "mm", "F": "kN"}
    assert parse_unit_assignments({"v": "in/sec"}) == {"v": "in/s"}
    assert parse_unit_assignments(None) == {}
    with pytest.raises(UnitError, match="column=unit"):
        parse_unit_assignments(["xmm"])
    with pytest.raises(UnitError, match="unknown unit"):
        parse_unit_assignments(["x=parsec"])


@given(
    st.sampled_from([(ch, u) for ch, q in CHANNEL_QUANTITY.items() for u in UNITS[q]]),
    st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=20),
)
def test_round_trip_through_si(pair: tuple[str, str], values: list[float]) -> None:
    ch, unit = pair
    back = from_si(to_si(values, unit, channel=ch), unit, channel=ch)
    np.testing.assert_allclose(back, values, rtol=4e-16 * 4, atol=1e-300)
