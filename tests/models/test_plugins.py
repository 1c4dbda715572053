"""A family installed as a plug-in (an entry point of the group ``mrdamper.kinds``) is a kind like
the built-in ones, in every process.

The toy plug-in ``mrd_viscous`` (a linear viscous damper) lives in ``tests/plugin_site``, a folder
laid out as an installed distribution (package and ``.dist-info`` with its entry point); a test
puts it on the path. Checked: the kind table lists it without importing its module, it passes
:func:`mrdamper.check_family`, its C and FMU exports equal its step, study workers started by
spawn fit it, and broken plug-ins are left out with one warning line each (in the command line
too) while the other kinds work.
"""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from mrdamper import check_family, kinds
from mrdamper.conformance import CHECKS, probe_record
from mrdamper.errors import PluginError, SchemaError
from mrdamper.models import get_estimator, known_kinds, registry
from tests.conftest import REPO_ROOT

PLUGIN_SITE = Path(__file__).resolve().parents[1] / "plugin_site"


def _fresh_table(monkeypatch: pytest.MonkeyPatch, *site: Path) -> None:
    """Put ``site`` on the path and make the kind table read the entry points again (all undone
    after the test)."""
    for folder in site:
        monkeypatch.syspath_prepend(str(folder))
    monkeypatch.setattr(kinds, "_PLUGINS", None)
    monkeypatch.setattr(kinds, "_BROKEN", {})
    monkeypatch.setattr(registry, "_ESTIMATORS", dict(registry._ESTIMATORS))
    monkeypatch.setattr(registry, "_FITTED", dict(registry._FITTED))


@pytest.fixture
def plugin(monkeypatch: pytest.MonkeyPatch) -> None:
    _fresh_table(monkeypatch, PLUGIN_SITE)


def _env(*site: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO_ROOT / "src"), *map(str, site)])
    return env


def test_the_kind_table_reads_the_row_without_importing_the_family() -> None:
    code = (
        "import sys; from mrdamper import kinds; row = kinds.spec('viscous'); "
        "print(row.module, row.default, 'mrd_viscous.family' in sys.modules, "
        "'numpy' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        env=_env(PLUGIN_SITE),
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["mrd_viscous.family", "False", "False", "False"]
    assert out.stderr == ""


def test_plugin_family_conforms(plugin: None) -> None:
    assert "viscous" in known_kinds() and known_kinds()[: len(kinds.KINDS)] == [
        row.kind for row in kinds.KINDS
    ]
    assert "viscous" not in kinds.default_kinds()
    report = check_family(get_estimator("viscous"))
    assert report.passed == tuple(CHECKS) and report.skipped == ()


def _broken_site(root: Path) -> Path:
    """An installed distribution whose entry points are broken in five ways, and one whose row
    is fine but names a module that is missing."""
    site = root / "site"
    (site / "mrd_bad").mkdir(parents=True)
    (site / "mrd_bad" / "__init__.py").write_text(
        "from mrdamper.kinds import KindSpec\n"
        "NOT_A_ROW = 3\n"
        "OTHER = KindSpec('other', 'mrd_bad.x', 'E', 'M', 'x', '0.4')\n"
        "MISSING = KindSpec('gone', 'mrd_bad.nowhere', 'E', 'M', 'x', '0.4')\n",
        encoding="utf-8",
    )
    (site / "mrd_crash.py").write_text("raise RuntimeError('boom')\n", encoding="utf-8")
    info = site / "mrd_bad-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: mrd-bad\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[mrdamper.kinds]\n"
        "crash = mrd_crash:KIND\n"
        "number = mrd_bad:NOT_A_ROW\n"
        "misnamed = mrd_bad:OTHER\n"
        "lpv = mrd_bad:OTHER\n"
        "absent = mrd_bad:NO_SUCH_NAME\n"
        "gone = mrd_bad:MISSING\n",
        encoding="utf-8",
    )
    return site


BROKEN = ("absent", "crash", "lpv", "misnamed", "number")


def test_broken_plugins_are_left_out_in_one_line_each(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    site = _broken_site(tmp_path)
    _fresh_table(monkeypatch, site, PLUGIN_SITE)
    with pytest.warns(UserWarning) as record:
        names = known_kinds()
    lines = [str(w.message) for w in record]
    assert len(lines) == len(BROKEN) and all("\n" not in t for t in lines)
    for kind, text in zip(BROKEN, sorted(lines), strict=True):
        assert text.startswith(f"plug-in entry point '{kind} = mrd_") and "mrd-bad 0.1" in text
    assert "RuntimeError: boom" in kinds.plugin_errors()["crash"]
    assert "expected a mrdamper.kinds.KindSpec" in kinds.plugin_errors()["number"]
    assert "cannot be replaced" in kinds.plugin_errors()["lpv"]
    # the other kinds, the good plug-in's included, are all there; the built-in lpv is intact
    assert names[: len(kinds.KINDS)] == [row.kind for row in kinds.KINDS]
    assert "viscous" in names and "gone" in names
    assert kinds.spec("lpv") is kinds.KINDS[0]
    with pytest.raises(SchemaError, match=r"kind 'crash': plug-in entry point 'crash = mrd_crash"):
        get_estimator("crash")
    with pytest.raises(PluginError, match=r"kind 'gone': .*mrd_bad\.nowhere.*ModuleNotFoundError"):
        get_estimator("gone")
    assert "gone" not in registry.available_models()


@pytest.mark.slow
def test_the_command_line_warns_once_per_broken_plugin(tmp_path: Path) -> None:
    site = _broken_site(tmp_path)
    out = subprocess.run(
        [sys.executable, "-m", "mrdamper", "--version"],
        env=_env(site),
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("mrdamper ")
    lines = out.stderr.splitlines()
    assert len(lines) == len(BROKEN), out.stderr
    assert all(ln.startswith("warning: plug-in entry point '") for ln in lines)


@pytest.mark.slow
def test_plugin_c_and_fmu_equal_its_step(plugin: None, tmp_path: Path) -> None:
    from mrdamper.conformance import fit_quietly, training_records
    from mrdamper.models.step import run_step
    from tests.control.test_c_export import GCC, _forward, _rel, _step_lib

    if GCC is None:
        pytest.skip("gcc not found")
    model = fit_quietly(get_estimator("viscous"), training_records())
    rec = probe_record().slice(0, 300)
    e = np.ascontiguousarray(model.electrical_input(rec))
    F_py, status, _ = run_step(model.step(dt=rec.dt), rec.x, rec.v, e, rec.dt)
    assert status == 0
    lib = _step_lib(model, tmp_path, "visc", rec.dt)
    assert _rel(_forward(lib, "visc", rec.x, rec.v, e), F_py) < 1e-9
    pytest.importorskip("fmpy")
    from fmpy.validation import validate_fmu

    from mrdamper.control.export.fmu import export_fmu, run_fmu

    fmu = export_fmu(model, tmp_path / "visc.fmu", name="visc_fmu", dt=rec.dt)
    assert validate_fmu(str(fmu)) == []
    assert _rel(run_fmu(fmu, rec.x, rec.v, e)[:, 0], F_py) < 1e-9


@pytest.mark.slow
def test_spawned_study_workers_fit_the_plugin(
    plugin: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    # workers started by spawn import everything afresh: they find the plug-in through its
    # entry point (as Dask workers do) and are handed the rows that register() added here (the
    # toy kinds of the study tests); they score both as forked workers do
    from mrdamper.study import ModelSpec, doe_protocol, run_study
    from tests.study.conftest import small_doe

    doe = small_doe(reps=2)
    models = [ModelSpec("viscous"), ModelSpec("toy")]
    kw = {"workers": 2, "seed": 0, "progress": False, "control": None}
    forked = run_study(doe, doe_protocol(), models, **kw)
    monkeypatch.setattr(multiprocessing, "get_all_start_methods", lambda: ["spawn"])
    spawned = run_study(doe, doe_protocol(), models, **kw)
    assert list(spawned.fits["error"]) == ["", ""]
    cols = ["model", "record", "esr"]
    assert set(spawned.results["model"]) == {"viscous", "toy"}
    assert spawned.results[cols].equals(forked.results[cols])


def _page_file(page: str, path: str) -> str:
    """The text a bash block of ``page`` writes to ``path`` with ``cat > path <<'EOF'``."""
    text = (REPO_ROOT / page).read_text(encoding="utf-8")
    start = text.index(f"cat > {path} <<'EOF'\n") + len(f"cat > {path} <<'EOF'\n")
    return text[start : text.index("\nEOF\n", start) + 1]


def test_the_documented_package_is_the_tested_one() -> None:
    # docs/adding-a-model.md installs the package that these tests put on the path
    page = "docs/adding-a-model.md"
    for name in ("__init__.py", "family.py"):
        documented = _page_file(page, f"mrd-viscous/mrd_viscous/{name}")
        tested = (PLUGIN_SITE / "mrd_viscous" / name).read_text(encoding="utf-8")
        if name == "__init__.py":  # the tests' copy says where it is installed from
            documented, tested = documented.split('"""')[-1], tested.split('"""')[-1]
        assert documented == tested, name
    entry = (PLUGIN_SITE / "mrd_viscous-0.1.dist-info" / "entry_points.txt").read_text()
    name, value = entry.splitlines()[1].split(" = ")
    assert f'{name} = "{value}"' in _page_file(page, "mrd-viscous/pyproject.toml")


def test_unreadable_entry_points_leave_the_built_in_kinds(monkeypatch: pytest.MonkeyPatch) -> None:
    import importlib.metadata

    def unreadable(**_: object) -> None:
        raise OSError("metadata of some distribution cannot be read")

    _fresh_table(monkeypatch)
    monkeypatch.setattr(importlib.metadata, "entry_points", unreadable)
    with pytest.warns(UserWarning, match=r"^plug-ins: .* \(OSError: metadata of some") as record:
        assert kinds.rows() == kinds.KINDS + kinds.added()
    assert len(record) == 1
    with warnings.catch_warnings():  # read once: no second warning
        warnings.simplefilter("error")
        assert kinds.rows() == kinds.KINDS + kinds.added()
