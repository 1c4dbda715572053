"""``mrdamper quartercar`` on a small static model: table, figures, refusals."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from mrdamper.cli.main import main
from mrdamper.models.semiphenomenological import SP3Model

SP3 = SP3Model(S=(800.0, 200.0, 60.0, 0.0, 900.0, 0.0), f0=10.0, input_range=(0.0, 2.0))


def test_quartercar_writes_table_and_figures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = SP3.save(tmp_path / "sp3.json")
    out = tmp_path / "qc"
    main(
        [
            "quartercar",
            str(model),
            "--out",
            str(out),
            "--roads",
            "B,D",
            "--duration",
            "4",
            "--car",
            "m_s=350",
            "--c-sky",
            "2500",
        ]
    )
    printed = capsys.readouterr().out
    assert "skyhook" in printed and "wrote quartercar.csv" in printed
    table = pd.read_csv(out / "quartercar.csv")
    assert len(table) == 3 * 5  # two ISO roads and the bump, five controllers
    assert set(table["controller"]) == {"soft", "hard", "skyhook", "groundhook", "hybrid"}
    assert (table.loc[table["controller"] == "soft", "acc_wk_vs_soft"] == 1.0).all()
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == [
        "spectra_iso_b_20_m_s.png",
        "time_bump_5_cm_x_2_m_20_m_s.png",
        "time_iso_b_20_m_s.png",
    ]
    with pytest.raises(SystemExit) as info:
        main(["quartercar", str(model), "--out", str(out), "--roads", "B", "--duration", "4"])
    assert info.value.code == 2
    assert "already exists" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["--car", "mass=3"], "--car"),
        (["--controllers", "fuzzy"], "controller"),
        (["--roads", "Z"], "road_classes"),
    ],
)
def test_quartercar_bad_options(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], field: str
) -> None:
    model = SP3.save(tmp_path / "sp3.json")
    with pytest.raises(SystemExit) as info:
        main(["quartercar", str(model), "--out", str(tmp_path / "qc"), "--duration", "2", *args])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and field in err
