"""Round trips for every file format: write, read back, compare (SI and converted units)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from mrdamper.data import (
    Experiment,
    read,
    read_csv,
    read_mat,
    read_parquet,
    write_csv,
    write_parquet,
)
from mrdamper.data.readers import read_directory
from mrdamper.errors import DataValidationError, OutputExistsError, UnitError


def _record(n: int = 500, electrical: str = "i", seed: int = 0) -> Experiment:
    rng = np.random.default_rng(seed)
    t = 0.25 + np.arange(n) / 1000.0
    x = 0.003 * np.sin(2 * np.pi * 3 * t) + 1e-5 * rng.standard_normal(n)
    v = np.gradient(x, t)
    F = 900 * np.tanh(v / 0.01) + 50 * rng.standard_normal(n)
    el = {electrical: np.round(rng.uniform(0, 2, n), 3)}
    return Experiment(
        t=t, x=x, v=v, F=F, **el, name="rec", metadata={"current": 1.0, "pattern": "sine"}
    )


def _assert_same(a: Experiment, b: Experiment, rtol: float = 0.0) -> None:
    assert a.channel_names == b.channel_names
    for ch in a.channel_names:
        if rtol == 0.0:
            np.testing.assert_array_equal(getattr(a, ch), getattr(b, ch), err_msg=ch)
        else:
            np.testing.assert_allclose(
                getattr(a, ch), getattr(b, ch), rtol=rtol, atol=0, err_msg=ch
            )


@pytest.mark.parametrize("electrical", ["i", "voltage"])
def test_csv_si_round_trip_is_exact(tmp_path: Path, electrical: str) -> None:
    e = _record(electrical=electrical)
    p = write_csv(e, tmp_path / "out" / "rec.csv")
    assert p.read_text().splitlines()[0] == ",".join(e.channel_names)
    back = read_csv(p)
    _assert_same(e, back)
    assert back.metadata["source"] == str(p)


def test_csv_unit_round_trip(tmp_path: Path) -> None:
    e = _record()
    units = {"t": "ms", "x": "mm", "v": "in/s", "F": "kN", "i": "mA"}
    p = write_csv(e, tmp_path / "rec.csv", units=units, sep=";")
    header = p.read_text().splitlines()[0].split(";")
    assert header == ["t [ms]", "x [mm]", "v [in/s]", "i [mA]", "F [kN]"]
    row = p.read_text().splitlines()[1].split(";")
    assert float(row[4]) == pytest.approx(e.F[0] / 1000.0, rel=1e-15)
    back = read_csv(p)  # units come from the headers
    _assert_same(e, back, rtol=1e-14)
    assert back.metadata["units"] == {"t": "ms", "x": "mm", "v": "in/s", "F": "kN", "i": "mA"}


def test_writer_unit_errors(tmp_path: Path) -> None:
    e = _record()
    with pytest.raises(UnitError, match="measures force") as info:
        write_csv(e, tmp_path / "a.csv", units={"x": "kN"})
    assert info.value.field == "x"
    with pytest.raises(UnitError, match="not a channel") as info:
        write_csv(e, tmp_path / "a.csv", units={"voltage": "V"})
    assert info.value.field == "voltage"
    assert not (tmp_path / "a.csv").exists()


@pytest.mark.parametrize("writer", [write_csv, write_parquet])
def test_writers_never_overwrite_without_force(tmp_path: Path, writer) -> None:
    e = _record()
    p = tmp_path / "rec.out"
    writer(e, p)
    before = p.read_bytes()
    with pytest.raises(OutputExistsError, match="force"):
        writer(e.replace(F=e.F + 1.0), p)
    assert p.read_bytes() == before
    writer(e.replace(F=e.F + 1.0), p, force=True)
    assert p.read_bytes() != before
    assert [f for f in os.listdir(tmp_path) if f.endswith(".part")] == []


def test_parquet_round_trip_with_metadata(tmp_path: Path) -> None:
    e = _record()
    p = write_parquet(e, tmp_path / "rec.parquet")
    back = read_parquet(p)
    _assert_same(e, back)
    assert back.name == "rec"
    assert back.metadata["current"] == 1.0 and back.metadata["pattern"] == "sine"
    assert back.metadata["source"] == str(p)
    assert read(p).name == "rec"
    assert read_parquet(p, name="other", metadata={"current": 0.5}).metadata["current"] == 0.5
    from mrdamper.data.preprocessing import trim

    q = write_parquet(trim(e, 0.3, 0.5), tmp_path / "trimmed.parquet")
    assert read_parquet(q).metadata["processing"] == ("trimmed to [0.3, 0.5] s",)


def test_parquet_unit_round_trip(tmp_path: Path) -> None:
    e = _record(electrical="voltage")
    p = write_parquet(e, tmp_path / "rec.pq", units={"x": "cm", "F": "lbf"})
    back = read(p)
    _assert_same(e, back, rtol=1e-14)
    assert back.metadata["units"]["F"] == "lbf"


def test_parquet_rejects_non_parquet(tmp_path: Path) -> None:
    p = tmp_path / "bad.parquet"
    p.write_text("t,x\n1,2\n")
    with pytest.raises(DataValidationError, match="Parquet") as info:
        read_parquet(p)
    assert info.value.field == "file"


def test_mat_v5_round_trip(tmp_path: Path) -> None:
    e = _record()
    p = tmp_path / "rec.mat"
    scipy.io.savemat(
        p, {c: getattr(e, c) for c in e.channel_names} | {"fs": 1000.0, "note": "rig A"}
    )
    back = read_mat(p)
    _assert_same(e, back)
    assert back.metadata["mat_version"] == "v5"
    assert set(back.metadata["ignored_columns"]) == {"fs", "note"}
    # Column vectors, a struct, and declared units.
    p2 = tmp_path / "struct.mat"
    rec = {"time": e.t, "disp_mm": e.x * 1e3, "vel": e.v, "curr": e.i, "Force_kN": e.F / 1e3}
    scipy.io.savemat(p2, {"rec": rec}, oned_as="column")
    back2 = read(
        p2, struct="rec", columns={"disp_mm": "x", "Force_kN": "F"}, units={"x": "mm", "F": "kN"}
    )
    _assert_same(e, back2, rtol=1e-14)
    with pytest.raises(DataValidationError, match="no struct variable 'data'") as info:
        read_mat(p2, struct="data")
    assert info.value.field == "struct"


def _write_mat73(path: Path, variables: dict[str, np.ndarray], group: str | None = None) -> None:
    """Write a MATLAB v7.3 file: HDF5 with a 512-byte MATLAB header, vectors stored as 1-by-n."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as f:
        target = f.create_group(group) if group else f
        if group:
            target.attrs["MATLAB_class"] = np.bytes_("struct")
        for name, arr in variables.items():
            ds = target.create_dataset(name, data=np.asarray(arr, dtype=np.float64)[None, :])
            ds.attrs["MATLAB_class"] = np.bytes_("double")
        txt = f.create_dataset(
            "label", data=np.frombuffer(b"rig A", dtype=np.uint8).astype(np.uint16)[:, None]
        )
        txt.attrs["MATLAB_class"] = np.bytes_("char")
    header = (
        b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 "
        b"HDF5 schema 1.00 ."
    )
    header = header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
    with open(path, "r+b") as fh:
        fh.write(header)


def test_mat_v73_round_trip(tmp_path: Path) -> None:
    e = _record(electrical="voltage")
    p = tmp_path / "rec73.mat"
    _write_mat73(p, {c: getattr(e, c) for c in e.channel_names})
    back = read_mat(p)
    _assert_same(e, back)
    assert back.metadata["mat_version"] == "v7.3"
    assert "label" in back.metadata["ignored_columns"]
    p2 = tmp_path / "grp73.mat"
    _write_mat73(p2, {"t": e.t, "x": e.x * 1e2, "v": e.v, "V": e.voltage, "F": e.F}, group="data")
    back2 = read(p2, struct="data", units={"x": "cm"})
    _assert_same(e, back2, rtol=1e-14)


def test_mat_bad_files(tmp_path: Path) -> None:
    p = tmp_path / "empty.mat"
    p.write_bytes(b"")
    with pytest.raises(DataValidationError, match="empty") as info:
        read_mat(p)
    assert info.value.field == "file"
    p.write_text("t,x,v\n1,2,3\n" * 20)
    with pytest.raises(DataValidationError, match="not a MATLAB") as info:
        read_mat(p)
    assert info.value.field == "file"
    p2 = tmp_path / "nothing.mat"
    scipy.io.savemat(p2, {"note": "no vectors", "fs": 1000.0})
    with pytest.raises(DataValidationError, match="no numeric vector") as info:
        read_mat(p2)
    assert info.value.field == "file"


def test_directory_of_mixed_formats(tmp_path: Path) -> None:
    base = _record()
    for k, (fmt, cur) in enumerate([("csv", 0.0), ("parquet", 0.5), ("mat", 1.0)]):
        e = base.replace(i=np.full(base.n, cur), name=f"step_{cur:g}A")
        p = tmp_path / f"step_{cur:g}A.{fmt}"
        if fmt == "csv":
            write_csv(e, p)
        elif fmt == "parquet":
            write_parquet(e, p)
        else:
            scipy.io.savemat(p, {c: getattr(e, c) for c in e.channel_names})
    s = read_directory(tmp_path, r"step_(?P<current>[\d.]+)A\.(csv|parquet|mat)")
    assert s.names == ["step_0A", "step_0.5A", "step_1A"]
    assert [e.metadata["current"] for e in s] == [0.0, 0.5, 1.0]
    for e in s:
        np.testing.assert_array_equal(e.F, base.F)
        assert np.all(e.i == e.metadata["current"])


def test_missing_optional_libraries_name_the_extra(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sys

    from mrdamper.errors import MrDamperError

    e = _record()
    p73 = tmp_path / "rec73.mat"
    _write_mat73(p73, {c: getattr(e, c) for c in e.channel_names})
    pq = write_parquet(e, tmp_path / "rec.parquet")
    monkeypatch.setitem(sys.modules, "h5py", None)  # import h5py now raises ImportError
    with pytest.raises(MrDamperError, match=r"mrdamper\[mat73\]"):
        read_mat(p73)
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    with pytest.raises(MrDamperError, match=r"mrdamper\[parquet\]"):
        read_parquet(pq)
    with pytest.raises(MrDamperError, match=r"mrdamper\[parquet\]"):
        write_parquet(e, tmp_path / "other.parquet")
