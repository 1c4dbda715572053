"""Long records: readers stream Parquet row groups and build records without extra copies."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from mrdamper.data import read_parquet
from mrdamper.data.experiment import Experiment
from mrdamper.data.readers import read_csv
from mrdamper.errors import DataValidationError

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")

FS = 1000.0


def _columns(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    x = 0.01 * np.sin(2 * np.pi * 1.5 * t)
    return {
        "t": t,
        "x": x,
        "v": np.gradient(x, t),
        "i": rng.uniform(0.0, 1.0, n),
        "F": rng.normal(0.0, 100.0, n),
    }


def _write(path: Path, table: object, row_group_size: int) -> Path:
    pq.write_table(table, path, row_group_size=row_group_size)
    return path


def test_row_groups_are_read_exactly(tmp_path: Path) -> None:
    cols = _columns(10_007)
    path = _write(tmp_path / "r.parquet", pa.table(cols), row_group_size=1000)
    assert pq.ParquetFile(path).num_row_groups == 11
    rec = read_parquet(path)
    for ch, values in cols.items():
        np.testing.assert_array_equal(getattr(rec, ch), values)
        assert not getattr(rec, ch).flags.writeable


def test_units_integers_and_unused_columns(tmp_path: Path) -> None:
    cols = _columns(3000)
    table = pa.table(
        {
            "time": cols["t"],
            "disp_mm": cols["x"] * 1e3,
            "v": cols["v"],
            "current_mA": np.round(cols["i"] * 1e3).astype(np.int32),
            "force_kN": cols["F"] / 1e3,
            "note": ["a"] * 3000,  # not a channel: never read
        }
    )
    path = _write(tmp_path / "u.parquet", table, row_group_size=700)
    rec = read_parquet(
        path,
        columns={"disp_mm": "x", "current_mA": "i", "force_kN": "F"},
        units={"x": "mm", "i": "mA", "F": "kN"},
    )
    np.testing.assert_allclose(rec.x, cols["x"], rtol=1e-15, atol=0)
    np.testing.assert_allclose(rec.F, cols["F"], rtol=1e-15, atol=0)
    np.testing.assert_allclose(rec.i, np.round(cols["i"] * 1e3) / 1e3, rtol=1e-15, atol=0)
    assert rec.metadata["ignored_columns"] == ["note"]


def test_nulls_follow_the_nan_policy(tmp_path: Path) -> None:
    cols = _columns(2000)
    force = pa.array([None if k in (5, 1500) else v for k, v in enumerate(cols["F"])])
    table = pa.table({**{k: v for k, v in cols.items() if k != "F"}, "F": force})
    path = _write(tmp_path / "n.parquet", table, row_group_size=512)
    with pytest.raises(DataValidationError) as err:
        read_parquet(path)
    assert err.value.field == "F" and "first at sample 5" in str(err.value)
    rec = read_parquet(path, nan_policy="interpolate")
    assert rec.n == 2000
    assert rec.F[5] == pytest.approx(0.5 * (cols["F"][4] + cols["F"][6]))


def test_text_channel_is_refused_naming_the_column(tmp_path: Path) -> None:
    cols = _columns(100)
    table = pa.table({**{k: v for k, v in cols.items() if k != "F"}, "F": ["1.0"] * 99 + ["x"]})
    path = _write(tmp_path / "s.parquet", table, row_group_size=30)
    with pytest.raises(DataValidationError) as err:
        read_parquet(path)
    assert err.value.field == "F" and "'x'" in str(err.value)


def _peak_bytes(read: object) -> tuple[Experiment, int]:
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        rec = read()  # type: ignore[operator]
        return rec, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("reader", ["parquet", "csv"])
@pytest.mark.slow
def test_reading_costs_about_the_record_itself(tmp_path: Path, reader: str) -> None:
    """NumPy memory (traced) while reading: the record's channels plus a small margin.

    Each channel used to be copied three times on its way in (float64 conversion, SI scaling,
    the record's own copy) and the time check made several temporaries as long as the record;
    the whole table and its concatenated columns came on top for Parquet.
    """
    n = 400_000
    cols = _columns(n)
    if reader == "parquet":
        path = _write(tmp_path / "big.parquet", pa.table(cols), row_group_size=50_000)
        rec, peak = _peak_bytes(lambda: read_parquet(path))
        limit = 1.9  # before streaming row groups and dropping the copies: 2.8
    else:
        path = tmp_path / "big.csv"
        import pandas as pd

        pd.DataFrame(cols).to_csv(path, index=False)
        rec, peak = _peak_bytes(lambda: read_csv(path))
        limit = 3.0  # pandas' parsed frame is one more copy of the record; before: 3.8
    record_bytes = 5 * n * 8
    assert rec.n == n
    assert peak < limit * record_bytes, (peak / record_bytes, limit)


def test_time_base_check_in_blocks_finds_the_sample(monkeypatch: pytest.MonkeyPatch) -> None:
    """The block-wise time check reports the same sample as a check on the whole record."""
    from mrdamper.data import experiment

    monkeypatch.setattr(experiment, "_TIME_BLOCK", 64)
    n = 1000
    t = np.arange(n) / FS
    z = np.zeros(n)
    bad = t.copy()
    bad[700:] += 0.5e-3  # one interval of 1.5 ms before sample 700
    with pytest.raises(DataValidationError, match="interval before sample 700 is 0.0015 s"):
        Experiment(t=bad, x=z, v=z, F=z, i=z)
    back = t.copy()
    back[129] = back[128]
    with pytest.raises(DataValidationError, match="sample 129 .* does not exceed sample 128"):
        Experiment(t=back, x=z, v=z, F=z, i=z)
    assert Experiment(t=t, x=z, v=z, F=z, i=z).n == n
