"""Table II design of experiments: structure, metadata, seeding, signals, files."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from mrdamper._io import MARK_NAME
from mrdamper.data.readers.manifest import OPTIONAL_COLUMNS
from mrdamper.errors import DataValidationError, OutputExistsError
from mrdamper.rig import VirtualRig
from mrdamper.rig.doe import TABLE_II, constant_current_sweep, make_record, table_ii
from mrdamper.rig.doe_io import MANIFEST_COLUMNS, read_doe, write_doe, write_records
from mrdamper.signals.aprbs import run_starts

SCALE = 0.1


@pytest.fixture(scope="module")
def doe(damper_cls):  # type: ignore[no-untyped-def]
    return table_ii(seed=0, scale=SCALE, damper=damper_cls(input="i", input_range=(0.0, 1.0)))


def test_table_ii_rows_match_the_paper() -> None:
    rows = [
        (s.experiment, s.displacement, s.pattern, s.duration, s.replicates, s.max_frequency)
        for s in TABLE_II
    ]
    assert rows == [
        (1, "Road Profile", "ICPS", 30.0, 11, 5.5),
        (2, "Road Profile", "APRBS", 30.0, 11, 4.5),
        (3, "Road Profile", "PRBS", 30.0, 11, 4.2),
        (4, "Long Road Profile", "APRBS", 600.0, 3, 4.5),
        (5, "Long Road Profile", "ICPS", 600.0, 4, 5.5),
        (6, "Road Profile", "SC", 30.0, 7, 5.5),
        (7, "Road Profile", "SC", 30.0, 7, 4.5),
        (8, "Road Profile", "SC", 30.0, 7, 4.5),
    ]
    assert sum(s.replicates for s in TABLE_II) == 61
    assert sum(s.replicates * s.duration for s in TABLE_II) == 5820.0


def test_records_names_and_metadata(doe) -> None:
    assert len(doe) == 61
    assert doe[0].name == "exp1_rep01" and doe[-1].name == "exp8_rep07"
    assert Counter(e.metadata["experiment"] for e in doe) == {
        s.experiment: s.replicates for s in TABLE_II
    }
    for e in doe:
        spec = TABLE_II[e.metadata["experiment"] - 1]
        m = e.metadata
        assert m["pattern"] == spec.pattern and m["max_frequency"] == spec.max_frequency
        assert m["duration"] == pytest.approx(spec.duration * SCALE)
        assert e.n == round(spec.duration * SCALE * 1000)
        assert m["source"] == "virtual rig"
        assert isinstance(m["seed"], int) and 0 <= m["seed"] < 2**63
        assert e.name == f"exp{spec.experiment}_rep{m['replicate']:02d}"
        assert np.max(np.abs(e.x)) < 0.02  # inside +-stroke/2
    assert len({e.metadata["seed"] for e in doe}) == 61
    assert sum(e.n for e in doe) == 582_000


def test_current_patterns_are_recognisable(doe) -> None:
    # the measured current is noisy: look at its levels rounded to the transducer's noise scale
    def levels(e):  # type: ignore[no-untyped-def]
        return np.unique(np.round(e.i[e.i.size // 10 :: 50], 1))

    sc = doe.filter(experiment=6)[0]
    i_up = np.round(sc.i, 2)
    firsts = i_up[run_starts(np.round(sc.i[::100], 1)) * 100]
    assert set(levels(sc).tolist()) <= {0.0, 0.2, 0.3, 0.5, 0.7, 0.8, 1.0}
    assert np.all(np.diff(np.round(sc.i[::300], 1)) >= -0.05)  # upward staircase
    assert firsts[0] == pytest.approx(0.0, abs=0.02)
    down = doe.filter(experiment=7)[0].i
    assert np.all(np.diff(np.round(down[::300], 1)) <= 0.05)
    updown = doe.filter(experiment=8)[0].i
    assert updown[updown.size // 2] == pytest.approx(1.0, abs=0.02) and updown[-1] < 0.05
    prbs_rec = doe.filter(experiment=3)[0]
    assert set(levels(prbs_rec).tolist()) == {0.0, 1.0}
    aprbs_rec = doe.filter(experiment=2)[0]
    assert len(levels(aprbs_rec)) > 3
    assert np.all((doe.filter(experiment=4)[0].i > -0.01) & (doe.filter(experiment=4)[0].i < 1.02))


def test_same_seed_same_bytes_and_subsets_keep_seeds(doe, damper_cls) -> None:
    d = damper_cls(input="i", input_range=(0.0, 1.0))
    again = table_ii(seed=0, scale=SCALE, damper=d, experiments=[3])
    for e in again:
        ref = doe[e.name]
        assert e.metadata["seed"] == ref.metadata["seed"]
        for ch in ("x", "v", "i", "F"):
            assert getattr(e, ch).tobytes() == getattr(ref, ch).tobytes()
    other = table_ii(seed=1, scale=SCALE, damper=d, experiments=[3])
    assert other[0].F.tobytes() != doe["exp3_rep01"].F.tobytes()
    # one record rebuilt from its metadata seed alone
    rec = doe["exp5_rep02"]
    rebuilt = make_record(TABLE_II[4], 2, rec.metadata["seed"], VirtualRig(damper=d), SCALE)
    assert rebuilt.F.tobytes() == rec.F.tobytes()


def test_worker_processes_give_the_same_bytes(doe, damper_cls) -> None:
    d = damper_cls(input="i", input_range=(0.0, 1.0))
    par = table_ii(seed=0, scale=SCALE, damper=d, experiments=[4, 8], workers=2)
    assert par.names == [e.name for e in doe if e.metadata["experiment"] in (4, 8)]
    for e in par:
        ref = doe[e.name]
        assert dict(e.metadata) == dict(ref.metadata)
        for ch in ("t", "x", "v", "i", "F"):
            assert getattr(e, ch).tobytes() == getattr(ref, ch).tobytes()
    with pytest.raises(DataValidationError, match="workers"):
        table_ii(seed=0, scale=SCALE, damper=d, experiments=[8], workers=0)


def test_bad_arguments(damper_cls) -> None:
    d = damper_cls(input="i", input_range=(0.0, 1.0))
    with pytest.raises(DataValidationError, match="scale"):
        table_ii(scale=0.01, damper=d)
    with pytest.raises(DataValidationError, match="experiments"):
        table_ii(scale=SCALE, damper=d, experiments=[9])
    with pytest.raises(DataValidationError, match="damper"):
        table_ii(scale=SCALE, damper=damper_cls(input="i", input_range=(0.0, 0.0)), experiments=[1])


def test_constant_current_sweep(damper) -> None:
    s = constant_current_sweep(seed=2, duration=3.0, damper=damper, replicates=2)
    assert len(s) == 10
    assert [e.metadata["current"] for e in s][::2] == [0.0, 0.25, 0.5, 0.75, 1.0]
    assert s[0].name == "cc_0A_rep01" and s[3].name == "cc_0.25A_rep02"
    for e in s:
        assert abs(np.median(e.i) - e.metadata["current"]) < 0.005
        assert e.metadata["pattern"] == "constant"


def test_write_records_byte_identical_and_no_overwrite(doe, tmp_path: Path) -> None:
    sub = doe.filter(experiment=[3, 6])
    a, b = tmp_path / "a", tmp_path / "b"
    write_records(sub, a)
    write_records(sub, b)
    files = sorted(p.name for p in a.iterdir())
    assert files == sorted([f"{e.name}.csv" for e in sub] + ["manifest.csv", MARK_NAME])
    for name in files:  # the mark names the folder it was written for: its entries are equal
        if name != MARK_NAME:
            assert (a / name).read_bytes() == (b / name).read_bytes()
    marks = [json.loads((d / MARK_NAME).read_text()) for d in (a, b)]
    assert marks[0]["entries"] == marks[1]["entries"] and marks[0]["path"] == str(a.resolve())
    lines = (a / "manifest.csv").read_text().splitlines()
    columns = [*MANIFEST_COLUMNS, *OPTIONAL_COLUMNS]
    assert lines[0].split(",") == columns
    assert len(lines) == 1 + len(sub)
    first = dict(zip(columns, lines[1].split(",")))
    assert first["file"] == "exp3_rep01.csv" and int(first["seed"]) == sub[0].metadata["seed"]
    # the damper behind the records: its kind, and "custom" for a damper that is not shipped
    assert (first["damper"], first["reference_damper"]) == (sub[0].metadata["damper"], "custom")
    back = read_doe(a)
    assert back.names == sub.names
    for e, ref in zip(back, sub):
        for ch in ("t", "x", "v", "i", "F"):
            np.testing.assert_array_equal(
                getattr(e, ch), getattr(ref, ch)
            )  # exact float round trip
        for key in (
            "experiment",
            "replicate",
            "pattern",
            "displacement",
            "seed",
            "source",
            *OPTIONAL_COLUMNS,
        ):
            assert e.metadata[key] == ref.metadata[key]
    with pytest.raises(OutputExistsError, match="not empty"):
        write_records(sub, a)
    write_records(sub, a, force=True)
    assert (a / "manifest.csv").read_bytes() == (b / "manifest.csv").read_bytes()


@pytest.mark.slow
def test_write_doe_writes_every_record_and_refuses_to_overwrite(damper, tmp_path: Path) -> None:
    import pandas as pd

    from mrdamper.rig.doe import record_seeds

    out = tmp_path / "doe"
    manifest = write_doe(out, seed=4, scale=0.07, damper=damper)
    table = pd.read_csv(manifest)
    assert len(table) == 61 and sorted(p.name for p in out.iterdir()) == sorted(
        [*table["file"], "manifest.csv", MARK_NAME]
    )
    assert table["seed"].tolist() == record_seeds(4, 61)
    # a written record equals the record rebuilt from its manifest seed (full float precision)
    row = table.iloc[40]
    spec = TABLE_II[int(row["experiment"]) - 1]
    rebuilt = make_record(
        spec, int(row["replicate"]), int(row["seed"]), VirtualRig(damper=damper), 0.07
    )
    frame = pd.read_csv(out / row["file"])
    assert list(frame.columns) == ["t", "x", "v", "i", "F"]
    np.testing.assert_array_equal(frame["F"].to_numpy(), rebuilt.F)
    with pytest.raises(OutputExistsError):
        write_doe(out, seed=4, scale=0.07, damper=damper)


def test_read_doe_reports_problems(doe, tmp_path: Path) -> None:
    sub = doe.filter(experiment=3)[:2]
    write_records(sub, tmp_path / "d")
    with pytest.raises(FileNotFoundError, match="manifest"):
        read_doe(tmp_path)
    (tmp_path / "d" / "exp3_rep02.csv").unlink()
    with pytest.raises(FileNotFoundError, match="exp3_rep02"):
        read_doe(tmp_path / "d")


def test_a_manifest_without_the_damper_columns_still_reads(doe, tmp_path: Path) -> None:
    sub = doe.filter(experiment=3)[:2]
    write_records(sub, tmp_path / "d")
    manifest = tmp_path / "d" / "manifest.csv"
    rows = [line.split(",") for line in manifest.read_text().splitlines()]
    keep = len(MANIFEST_COLUMNS)
    manifest.write_text("\n".join(",".join(r[:keep]) for r in rows) + "\n")
    back = read_doe(tmp_path / "d")
    assert back.names == sub.names
    assert all("reference_damper" not in e.metadata for e in back)
