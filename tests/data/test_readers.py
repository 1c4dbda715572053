"""Readers: column aliases, declared units, delimiters, policies, folders, and every documented
error for bad files (the error names the offending field)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrdamper.data import read, read_csv, read_directory
from mrdamper.data.readers import DEFAULT_PATTERN, parse_file_name
from mrdamper.data.readers.csv_reader import sniff_delimiter
from mrdamper.errors import DataValidationError, Note, UnitError

N = 200
FS = 500.0


def _signals(n: int = N) -> dict[str, np.ndarray]:
    t = np.arange(n) / FS
    return {
        "t": t,
        "x": 0.004 * np.sin(2 * np.pi * 2 * t),
        "v": 0.004 * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * t),
        "i": np.full(n, 0.5),
        "F": 800.0 * np.tanh(30 * np.cos(2 * np.pi * 2 * t)),
    }


def _write(path: Path, header: list[str], cols: list[np.ndarray], sep: str = ",") -> Path:
    lines = [sep.join(header)]
    lines += [sep.join(repr(float(c[k])) for c in cols) for k in range(len(cols[0]))]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_aliases_and_provenance(tmp_path: Path) -> None:
    s = _signals()
    p = _write(
        tmp_path / "r.csv",
        ["Time", "Displacement", "velocity", "Current", "FORCE"],
        [s["t"], s["x"], s["v"], s["i"], s["F"]],
    )
    e = read_csv(p)
    np.testing.assert_array_equal(e.F, s["F"])
    np.testing.assert_array_equal(e.x, s["x"])
    assert e.name == "r"
    assert e.metadata["source"] == str(p)
    assert e.metadata["columns"] == {
        "t": "Time",
        "x": "Displacement",
        "v": "velocity",
        "F": "FORCE",
        "i": "Current",
    }
    assert e.metadata["units"] == {"t": "s", "x": "m", "v": "m/s", "F": "N", "i": "A"}


def test_one_letter_aliases_are_case_sensitive(tmp_path: Path) -> None:
    s = _signals()
    p = _write(
        tmp_path / "r.csv", ["t", "x", "v", "V", "F"], [s["t"], s["x"], s["v"], 2 * s["i"], s["F"]]
    )
    e = read_csv(p)
    np.testing.assert_array_equal(e.v, s["v"])
    np.testing.assert_array_equal(e.voltage, 2 * s["i"])
    assert e.i is None


def test_user_mapping_and_declared_units(tmp_path: Path) -> None:
    s = _signals()
    p = _write(
        tmp_path / "r.csv",
        ["time_ms", "pos_mm", "vel", "I_mA", "Force_kN"],
        [s["t"] * 1e3, s["x"] * 1e3, s["v"], s["i"] * 1e3, s["F"] / 1e3],
    )
    e = read_csv(
        p,
        columns={"time_ms": "t", "pos_mm": "x", "I_mA": "i", "Force_kN": "F"},
        units={"t": "ms", "x": "mm", "Force_kN": "kN", "i": "mA"},
    )
    np.testing.assert_allclose(e.t, s["t"], rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(e.x, s["x"], rtol=1e-14)
    np.testing.assert_allclose(e.F, s["F"], rtol=1e-14)
    np.testing.assert_allclose(e.i, s["i"], rtol=1e-14)
    assert e.metadata["units"]["F"] == "kN"
    assert e.metadata["columns"]["F"] == "Force_kN"


def test_units_in_headers_and_paper_units(tmp_path: Path) -> None:
    s = _signals()
    p = _write(
        tmp_path / "r.csv",
        ["t [s]", "x (in)", "v [in/sec]", "i [A]", "F [lbf]"],
        [s["t"], s["x"] / 0.0254, s["v"] / 0.0254, s["i"], s["F"] / 4.4482216152605],
    )
    e = read_csv(p)
    np.testing.assert_allclose(e.x, s["x"], rtol=1e-14)
    np.testing.assert_allclose(e.v, s["v"], rtol=1e-14)
    np.testing.assert_allclose(e.F, s["F"], rtol=1e-14)
    assert e.metadata["units"] == {"t": "s", "x": "in", "v": "in/s", "F": "lbf", "i": "A"}
    # A declared unit that agrees with the header is fine; one that contradicts it is an error.
    read_csv(p, units={"x": "in"})
    with pytest.raises(UnitError, match="header says") as info:
        read_csv(p, units={"x": "mm"})
    assert info.value.field == "x (in)"


@pytest.mark.parametrize("sep", [";", "\t", "|", " "])
def test_delimiters_are_detected(tmp_path: Path, sep: str) -> None:
    s = _signals()
    p = _write(tmp_path / "r.txt", list(s), list(s.values()), sep=sep)
    e = read(p)
    np.testing.assert_array_equal(e.F, s["F"])


def test_blank_separated_with_runs_of_spaces() -> None:
    assert sniff_delimiter("t    x   v\n0   1   2\n1   2   3\n") == r"\s+"


def test_decimal_comma(tmp_path: Path) -> None:
    s = _signals()
    text = "t;x;v;i;F\n" + "\n".join(
        ";".join(f"{s[c][k]:.10f}".replace(".", ",") for c in s) for k in range(N)
    )
    p = tmp_path / "r.csv"
    p.write_text(text)
    with pytest.raises(DataValidationError, match="decimal"):
        read_csv(p)
    e = read_csv(p, decimal=",")
    np.testing.assert_allclose(e.F, s["F"], atol=1e-9)


def test_nan_policy_and_resample_pass_through(tmp_path: Path) -> None:
    s = _signals()
    F = s["F"].copy()
    F[[0, 50, 51]] = np.nan
    p = _write(tmp_path / "r.csv", list(s), [s["t"], s["x"], s["v"], s["i"], F])
    with pytest.raises(DataValidationError, match="non-finite") as info:
        read_csv(p)
    assert info.value.field == "F"
    e = read_csv(p, nan_policy="interpolate")
    assert e.n == N - 1
    assert any("interpolated 2" in r for r in e.metadata["repairs"])
    e2 = read_csv(p, nan_policy="interpolate", resample_fs=250.0)
    assert e2.fs == pytest.approx(250.0)


def test_declared_rate_regenerates_rounded_time(tmp_path: Path) -> None:
    s = _signals()
    fs = 3004.8
    t = np.arange(N) / fs
    t_rounded = np.array([float(f"{v:.4g}") for v in t])  # few printed digits: jittered intervals
    p = _write(tmp_path / "r.csv", list(s), [t_rounded, s["x"], s["v"], s["i"], s["F"]])
    # Without fs= the rate is estimated from the rounded column, with a note saying so.
    with pytest.warns(Note, match="rate estimated as 3004.8 Hz"):
        est = read_csv(p)
    np.testing.assert_allclose(est.t, t, rtol=0, atol=1e-12)
    assert "rate estimated" in est.metadata["repairs"][0]
    e = read_csv(p, fs=fs)
    np.testing.assert_allclose(e.t, t, rtol=0, atol=1e-15)
    assert "time regenerated" in e.metadata["repairs"][0]
    # A missing sample is not hidden by fs=: the time column departs by a whole interval.
    keep = np.r_[0:100, 101:N]
    p2 = _write(
        tmp_path / "gap.csv",
        list(s),
        [t[keep], s["x"][keep], s["v"][keep], s["i"][keep], s["F"][keep]],
    )
    with pytest.raises(DataValidationError, match="missing") as info:
        read_csv(p2, fs=fs)
    assert info.value.field == "t"
    # ... nor by the estimate: one missing sample is a whole interval off any straight line.
    with pytest.raises(DataValidationError, match="fs=") as info:
        read_csv(p2)
    assert info.value.field == "t"
    with pytest.raises(DataValidationError, match="not both"):
        read_csv(p, fs=fs, resample_fs=1000.0)


def test_no_time_column_with_declared_rate(tmp_path: Path) -> None:
    s = _signals()
    p = _write(tmp_path / "r.csv", ["x", "v", "i", "F"], [s["x"], s["v"], s["i"], s["F"]])
    with pytest.raises(DataValidationError, match="fs=") as info:
        read_csv(p)
    assert info.value.field == "t"
    e = read_csv(p, fs=FS)
    np.testing.assert_allclose(e.t, s["t"], atol=1e-15)


def test_missing_velocity_can_be_derived(tmp_path: Path) -> None:
    s = _signals(2000)  # 4 s: 8 cycles of 2 Hz
    p = _write(tmp_path / "r.csv", ["t", "x", "i", "F"], [s["t"], s["x"], s["i"], s["F"]])
    with pytest.raises(DataValidationError, match="velocity_from_displacement") as info:
        read_csv(p)
    assert info.value.field == "v"
    e = read_csv(p, derive_velocity=True, metadata={"frequency": 2.0})
    assert e.metadata["velocity_cutoff"] == pytest.approx(20.0)
    inner = slice(100, -100)  # away from the filter's start-up at both ends
    np.testing.assert_allclose(e.v[inner], s["v"][inner], atol=0.002 * np.abs(s["v"]).max())
    e2 = read_csv(p, derive_velocity=25.0)
    assert e2.metadata["velocity_cutoff"] == 25.0
    with pytest.raises(DataValidationError, match="derive_velocity"):
        read_csv(p, derive_velocity=-1.0)
    p2 = _write(tmp_path / "rv.csv", list(s), list(s.values()))
    with pytest.raises(DataValidationError, match="has a velocity column"):
        read_csv(p2, derive_velocity=True)


# ----------------------------------------------------------------------------- bad files
@pytest.mark.parametrize(
    ("header", "field", "text"),
    [
        (["t", "x", "v", "i", "Load_kN"], "F", "no force column"),
        (["t", "x", "v", "F", "temperature"], "i", "no electrical input"),
        (["t", "pos", "x", "v", "i"], "x", "all look like 'x'"),
        (["t", "x", "v", "x", "F"], "x", "more than once"),
    ],
)
def test_bad_headers(tmp_path: Path, header: list[str], field: str, text: str) -> None:
    s = _signals()
    p = _write(tmp_path / "r.csv", header, list(s.values()))
    with pytest.raises(DataValidationError, match=text) as info:
        read_csv(p)
    assert info.value.field == field


def test_duplicated_column_mapping(tmp_path: Path) -> None:
    s = _signals()
    p = _write(tmp_path / "r.csv", ["t", "x", "v", "i", "F1", "F2"], [*s.values(), s["F"]])
    with pytest.raises(DataValidationError, match="both 'F1' and 'F2'") as info:
        read_csv(p, columns={"F1": "F", "F2": "F"})
    assert info.value.field == "columns"
    with pytest.raises(DataValidationError, match="not found") as info:
        read_csv(p, columns={"Force": "F"})
    assert info.value.field == "columns"
    with pytest.raises(DataValidationError, match="expected one of") as info:
        read_csv(p, columns={"F1": "force"})
    assert info.value.field == "columns"


def test_unit_errors_name_the_column(tmp_path: Path) -> None:
    s = _signals()
    p = _write(tmp_path / "r.csv", list(s), list(s.values()))
    with pytest.raises(UnitError, match="unknown unit 'stone'") as info:
        read_csv(p, units={"F": "stone"})
    assert info.value.field == "F"
    with pytest.raises(UnitError, match="measures length") as info:
        read_csv(p, units={"F": "mm"})
    assert info.value.field == "F"
    with pytest.raises(UnitError, match="no such channel") as info:
        read_csv(p, units={"voltage": "V"})
    assert info.value.field == "voltage"


def test_non_numeric_value(tmp_path: Path) -> None:
    s = _signals()
    p = _write(tmp_path / "r.csv", list(s), list(s.values()))
    lines = p.read_text().splitlines()
    parts = lines[7].split(",")
    parts[4] = "overload"
    lines[7] = ",".join(parts)
    p.write_text("\n".join(lines))
    with pytest.raises(
        DataValidationError, match="non-numeric value 'overload' at data row 6"
    ) as info:
        read_csv(p)
    assert info.value.field == "F"


@pytest.mark.parametrize(
    ("content", "text"), [("", "is empty"), ("\n\n", "is empty"), ("t,x,v,i,F\n", "no data rows")]
)
def test_empty_files(tmp_path: Path, content: str, text: str) -> None:
    p = tmp_path / "r.csv"
    p.write_text(content)
    with pytest.raises(DataValidationError, match=text) as info:
        read_csv(p)
    assert info.value.field == "file"


def test_non_uniform_time_in_file(tmp_path: Path) -> None:
    s = _signals()
    t = s["t"].copy()
    t[100:] += 0.5 / FS
    p = _write(tmp_path / "r.csv", list(s), [t, s["x"], s["v"], s["i"], s["F"]])
    with pytest.raises(DataValidationError, match="not uniform") as info:
        read_csv(p)
    assert info.value.field == "t"
    assert str(p) in str(info.value)


def test_missing_file_and_unknown_type(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        read(tmp_path / "nope.csv")
    (tmp_path / "r.xlsx").write_text("x")
    with pytest.raises(DataValidationError, match="unknown file type") as info:
        read(tmp_path / "r.xlsx")
    assert info.value.field == "path"


# ----------------------------------------------------------------------------- folders
def test_parse_file_name_units_and_numbers() -> None:
    assert parse_file_name("sine_25mm_0.25Hz_0.75A.csv", DEFAULT_PATTERN) == {
        "condition": "25mm_0.25Hz",
        "amplitude": 0.025,
        "frequency": 0.25,
        "current": 0.75,
    }
    assert parse_file_name("README.md", DEFAULT_PATTERN) is None
    meta = parse_file_name(
        "run_3_12.5mm_per_s.csv", r"run_(?P<replicate>\d+)_(?P<speed_mm_per_s>[\d.]+)mm_per_s\.csv"
    )
    assert meta == {"replicate": 3.0, "speed": pytest.approx(0.0125)}
    with pytest.raises(DataValidationError) as info:
        parse_file_name("a_x.csv", r"a_(?P<gap_mm>\w+)\.csv")
    assert info.value.field == "gap"


def test_read_directory(tmp_path: Path) -> None:
    s = _signals()
    for amp, f, i in [(10, 1, 0.5), (2, 5, 0.0), (2, 5, 1), (2, 5, 0.25)]:
        _write(
            tmp_path / f"sine_{amp}mm_{f}Hz_{i:g}A.csv",
            list(s),
            [s["t"], s["x"], s["v"], s["i"] * 0 + i, s["F"]],
        )
    (tmp_path / "README.md").write_text("not a record")
    rs = read_directory(tmp_path)
    assert rs.names == [
        "sine_2mm_5Hz_0A",
        "sine_2mm_5Hz_0.25A",
        "sine_2mm_5Hz_1A",
        "sine_10mm_1Hz_0.5A",
    ]
    assert rs.name == tmp_path.name
    e = rs["sine_10mm_1Hz_0.5A"]
    assert e.metadata["amplitude"] == pytest.approx(0.010)
    assert e.metadata["current"] == 0.5 and e.metadata["frequency"] == 1.0
    assert e.metadata["condition"] == "10mm_1Hz"
    assert e.metadata["source"].endswith("sine_10mm_1Hz_0.5A.csv")
    assert rs.filter(current=0.25).names == ["sine_2mm_5Hz_0.25A"]
    assert read(tmp_path).names == rs.names
    # Reader options reach every file.
    rs_mm = read_directory(tmp_path, units={"x": "mm"})
    np.testing.assert_allclose(rs_mm[0].x, s["x"] * 1e-3)
    with pytest.raises(DataValidationError, match="no file") as info:
        read_directory(tmp_path, r"step_.*\.csv")
    assert info.value.field == "pattern"
    with pytest.raises(DataValidationError, match="regular expression") as info:
        read_directory(tmp_path, r"sine_(")
    assert info.value.field == "pattern"
    with pytest.raises(FileNotFoundError):
        read_directory(tmp_path / "missing")
