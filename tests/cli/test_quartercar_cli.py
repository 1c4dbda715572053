"""``mrdamper quartercar`` on a small static model: table, figures, refusals."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import click
import pandas as pd
import pytest
import typer

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
    header = printed.splitlines()[0]  # every column with its unit
    for col in ("rms_acc [m/s²]", "rms_tyre_load [N]", "rms_travel [m]", "mean_input [A]"):
        assert col in header, header
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
        (["--i-range", "1,0"], "--i-range"),
        (["--i-range", "0"], "--i-range"),
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


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not found")
def test_quartercar_with_the_exported_c_inverse(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--c-inverse``: the library compiled from the model's C export (every default) drives the
    car and the table is the Python inverse's, to the last printed digit; with ``--plant`` or
    ``--reg`` it is refused in one line."""
    model = SP3.save(tmp_path / "sp3.json")
    main(["export", str(model), "--format", "c", "--out", str(tmp_path / "c"), "--name", "sp3"])
    lib = tmp_path / "c" / "libsp3.so"
    cc = [str(shutil.which("gcc")), "-std=c99", "-O2", "-shared", "-fPIC"]
    subprocess.run([*cc, str(tmp_path / "c" / "sp3.c"), "-o", str(lib), "-lm"], check=True)
    run = ["--roads", "C", "--no-bump", "--duration", "3", "--controllers", "soft,skyhook"]
    main(["quartercar", str(model), "--out", str(tmp_path / "py"), *run])
    main(
        ["quartercar", str(model), "--out", str(tmp_path / "c_run"), "--c-inverse", str(lib), *run]
    )
    assert "(inverse: libsp3.so)" in capsys.readouterr().out
    py = (tmp_path / "py" / "quartercar.csv").read_text(encoding="utf-8")
    assert (tmp_path / "c_run" / "quartercar.csv").read_text(encoding="utf-8") == py
    for extra in (["--plant", "rig"], ["--reg", "100"]):
        with pytest.raises(SystemExit) as info:
            main(
                ["quartercar", str(model), "--out", str(tmp_path / "x"), "--c-inverse", str(lib)]
                + run
                + extra
            )
        assert info.value.code == 2
        err = capsys.readouterr().err
        assert f"{extra[0]}: not with --c-inverse" in err and len(err.strip().splitlines()) == 1


def test_controllers_help_lists_the_registry_without_loading_the_loops() -> None:
    # the option's help and default name exactly the registered controllers, in their order
    from mrdamper.cli.main import app
    from mrdamper.control.loop.controllers import LAWS

    cmd = typer.main.get_command(app)
    ctx = click.Context(cmd)
    option = next(p for p in cmd.get_command(ctx, "quartercar").params if p.name == "controllers")
    assert option.help == f"Comma-separated: {', '.join(LAWS)}."
    assert option.default.split(",") == list(LAWS)
    # the command line reads the names without importing the compiled loops
    probe = (
        "import sys, mrdamper.cli.main; "
        "print(sorted(m for m in sys.modules if m.split('.')[:2] == ['mrdamper', 'control']))"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert loaded == "[]"
