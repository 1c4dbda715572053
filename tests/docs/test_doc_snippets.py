"""Every ```bash and ```python block of README.md and docs/**/*.md runs as written.

How the blocks run:

* one test per page, or per folder of a page: a line ``<!-- doc-test: folder NAME -->`` between
  blocks puts the blocks after it (up to the next such line) in folder NAME; the blocks before
  the first such line are in folder ``main``. The blocks of one folder use no file that a block
  of another folder wrote, and each folder runs as its own test (so the test workers share a
  long page). A folder's blocks run in page order, then once more in the same folder every
  block that wrote or changed a file there on its first run and took at most
  :data:`RERUN_MAX_S` (a second run finds the first one's outputs, as a user who runs a
  documented command twice does; a block that wrote nothing meets on its second run the folder
  it met on its first, so it is not run again; the few slower blocks, such as the demo, the
  studies on the shared data, ``select`` and the benchmarks, run once: ``tests/cli/
  test_study_cli.py`` runs a short ``demo`` again over its own outputs with ``--force``, and the
  faster ``study``, ``fit`` and ``quartercar`` blocks of the pages run twice), all in one fresh
  temporary folder that has
  ``../shared`` (a link to the shared folder holding ``data/``) beside it and a link
  ``benchmarks/`` to the repository's benchmarks, so commands are written as a user at the
  repository root would write them (``../shared/data/...``);
* ``bash`` blocks run with ``bash -e`` (the first failing command fails the block); ``python``
  blocks run as a script with this interpreter. Both see this checkout's ``src`` first on
  ``PYTHONPATH``, matplotlib's ``Agg`` backend and single-threaded BLAS;
* a ``text`` block preceded, on the line just before its fence, by ``<!-- doc-test: output -->``
  is the output of the block before it: each of its lines must appear in what that block prints
  (spaces collapsed), so the numbers a page shows are the ones that come out;
* a block preceded, on the line just before its fence, by ``<!-- doc-test: skip "reason" -->`` is
  not run (the reason is reported); such blocks are the ones that take minutes, and the page
  then shows their quick form in a block that does run;
* the package is already installed where this test runs, so a ``pip install ... && COMMAND``
  line runs only ``COMMAND`` (the part after ``&&``), and a line that only installs is left out.

Pages that use ``../shared`` skip, with the reason, when the shared data are absent. Every file
the README's and the tutorial's blocks write is in ``.gitignore`` (:data:`CLEAN_PAGES`), and each
command of the README prints at most :data:`MAX_WARNING_LINES` distinct warning or note lines,
each once. With the
environment variable ``MRDAMPER_DOC_TIMES`` set to a file, every block run appends one line
``page<TAB>line<TAB>run<TAB>seconds`` to it (where the suite's time goes).
"""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.conftest import REPO_ROOT, SHARED_DATA

#: Longest time one block may run [s] (the convention asks for seconds to about a minute).
BLOCK_TIMEOUT_S = 600
#: A block that wrote a file runs a second time only when its first run took at most this [s].
RERUN_MAX_S = 25.0
_FENCE = re.compile(r"^\s*```\s*([A-Za-z0-9_+-]*)\s*$")
_OUTPUT = re.compile(r"^\s*<!--\s*doc-test:\s*output\s*-->\s*$")
_SKIP = re.compile(r'^\s*<!--\s*doc-test:\s*skip\s+"([^"]+)"\s*-->\s*$')
_FOLDER = re.compile(r"^\s*<!--\s*doc-test:\s*folder\s+([A-Za-z0-9_.-]+)\s*-->\s*$")
_PIP = re.compile(r"^\s*(?:python3?\s+-m\s+)?pip3?\s+install\b[^&]*?(?:&&\s*(?P<rest>.*))?$")


@dataclass(frozen=True)
class Block:
    """One fenced block of a page."""

    page: str
    line: int
    lang: str
    code: str
    skip: str | None
    #: The output the page shows for this block (a marked ``text`` block after it), or None.
    expected: str | None = None
    #: The folder of the page the block runs in (named by the last ``folder`` line before it).
    folder: str = "main"


def doc_pages() -> list[Path]:
    """README.md and every Markdown page under docs/, in a stable order."""
    pages = [REPO_ROOT / "README.md"] if (REPO_ROOT / "README.md").is_file() else []
    return pages + sorted((REPO_ROOT / "docs").rglob("*.md"))


def blocks_of(page: Path) -> list[Block]:
    """The ``bash`` and ``python`` blocks of a page, with their skip reasons."""
    lines = page.read_text(encoding="utf-8").splitlines()
    out: list[Block] = []
    k = 0
    folder = "main"
    rel = str(page.relative_to(REPO_ROOT)) if page.is_relative_to(REPO_ROOT) else page.name
    while k < len(lines):
        m = _FENCE.match(lines[k])
        if not m:
            named = _FOLDER.match(lines[k])
            folder = named.group(1) if named else folder
            k += 1
            continue
        start, lang = k, m.group(1).lower()
        k += 1
        body: list[str] = []
        while k < len(lines) and not lines[k].lstrip().startswith("```"):
            body.append(lines[k])
            k += 1
        k += 1  # closing fence
        if lang == "text" and out and start > 0 and _OUTPUT.match(lines[start - 1]):
            out[-1] = dataclasses.replace(out[-1], expected="\n".join(body))
        if lang in ("bash", "python"):
            prev = _SKIP.match(lines[start - 1]) if start > 0 else None
            code = textwrap.dedent("\n".join(body)) + "\n"  # blocks indented inside list items
            skip = prev.group(1) if prev else None
            out.append(Block(rel, start + 1, lang, code, skip, folder=folder))
    return out


def folders_of(page: Path) -> dict[str, list[Block]]:
    """The page's blocks by folder, each list in page order (folders without blocks left out)."""
    groups: dict[str, list[Block]] = {}
    for b in blocks_of(page):
        groups.setdefault(b.folder, []).append(b)
    return groups


def as_run(block: Block) -> str:
    """The code that runs: install lines reduced to what follows their ``&&``."""
    if block.lang != "bash":
        return block.code
    kept = []
    for ln in block.code.splitlines():
        m = _PIP.match(ln)
        if m:
            if m.group("rest"):
                kept.append(m.group("rest"))
            continue
        kept.append(ln)
    return "\n".join(kept) + "\n"


def _env() -> dict[str, str]:
    env = dict(os.environ)
    src = str(REPO_ROOT / "src")
    env["PYTHONPATH"] = src + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env.update(MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    return env


#: Pages with at least one bash or python block (the API reference pages have none).
PAGES = [p for p in doc_pages() if blocks_of(p)]
#: (page, blocks) of every folder of every page.
PARTS = [(p, blocks) for p in PAGES for blocks in folders_of(p).values()]
#: Test ids: the page, followed by the folder's name on pages with several folders.
PART_IDS = [
    blocks[0].page if len(folders_of(p)) == 1 else f"{blocks[0].page}:{blocks[0].folder}"
    for p, blocks in PARTS
]


def test_the_convention_is_parsed() -> None:
    page = REPO_ROOT / "README.md"
    assert any(b.lang == "python" for b in blocks_of(page))
    demo = Block(
        "x",
        1,
        "bash",
        'python3 -m pip install -e ".[dev]" && python3 -m pytest\npip install x\nls\n',
        None,
    )
    assert as_run(demo) == "python3 -m pytest\nls\n"


@pytest.mark.slow
@pytest.mark.parametrize(("page", "blocks"), PARTS, ids=PART_IDS)
def test_page_blocks_run(page: Path, blocks: list[Block], tmp_path: Path) -> None:
    runnable = [b for b in blocks if b.skip is None]
    if not runnable:
        pytest.skip("; ".join(f"line {b.line}: {b.skip}" for b in blocks))
    if "../shared" in "".join(b.code for b in runnable) and not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA} (set MRDAMPER_SHARED_DATA)")
    work = tmp_path / "repo"
    work.mkdir()
    (tmp_path / "shared").symlink_to(SHARED_DATA.parent, target_is_directory=True)
    (work / "benchmarks").symlink_to(REPO_ROOT / "benchmarks", target_is_directory=True)
    _run_folder(runnable, work, _env())
    if blocks[0].page in CLEAN_PAGES:
        _check_ignored(work)


#: Pages whose commands, run from the repository root, must leave ``git status`` clean: what
#: they write is in ``.gitignore``.
CLEAN_PAGES = ("README.md", "docs/tutorial.md")
#: Most distinct warning and note lines one command of the README may print.
MAX_WARNING_LINES = 5
#: The trace prefix that marks where each command of a README ``bash`` block starts on stderr.
_TRACE = "+mrdamper-doc-test> "


def _check_ignored(work: Path) -> None:
    """Every file the blocks wrote in ``work`` is ignored by the repository's ``.gitignore`` (a
    user who runs them at the repository root keeps a clean ``git status``)."""
    if not (REPO_ROOT / ".git").exists():
        return
    written = sorted(_snapshot(work))
    proc = subprocess.run(
        ["git", "-C", str(REPO_ROOT), "check-ignore", "--no-index", "--stdin"],
        input="\n".join(written) + "\n",
        capture_output=True,
        text=True,
        check=False,
    )
    ignored = set(proc.stdout.splitlines())
    left = [f for f in written if f not in ignored]
    assert not left, f"written by the page's commands but not in .gitignore: {left[:10]}"


def _check_warning_lines(b: Block, stderr: str) -> None:
    """Each command of a README block prints at most :data:`MAX_WARNING_LINES` distinct warning
    or note lines, each once."""
    commands = stderr.split(_TRACE) if b.lang == "bash" else [stderr]
    for text in commands:
        said = [
            ln
            for ln in text.splitlines()
            if ln.startswith(("warning: ", "note: ")) or re.match(r"^\S+:\d+: \w+: ", ln)
        ]
        command = text.splitlines()[0] if b.lang == "bash" and text else b.page
        assert len(said) == len(set(said)), f"{b.page}:{b.line} repeats a line: {command}"
        assert len(said) <= MAX_WARNING_LINES, (
            f"{b.page}:{b.line}: {len(said)} warning lines from {command}: {said}"
        )


def _run_folder(blocks: list[Block], work: Path, env: dict[str, str]) -> list[tuple[int, int]]:
    """Run ``blocks`` in page order in ``work``, then again each one that wrote a file and took at
    most :data:`RERUN_MAX_S`; return the ``(line, run)`` of every run."""
    ran: list[tuple[int, int]] = []
    again = []
    for b in blocks:
        t0 = time.perf_counter()
        wrote = _run_block(b, 1, work, env)
        ran.append((b.line, 1))
        if wrote and time.perf_counter() - t0 <= RERUN_MAX_S:
            again.append(b)
    for b in again:
        _run_block(b, 2, work, env)
        ran.append((b.line, 2))
    return ran


def _run_block(b: Block, run: int, work: Path, env: dict[str, str]) -> bool:
    """Run one block in ``work`` (failing the test if it fails); True if it wrote a file there."""
    code = as_run(b)
    if b.page == "README.md" and b.lang == "bash":  # mark each command's start on stderr
        code = f"PS4='{_TRACE}'\nset -x\n{code}"
    before = _snapshot(work)
    t0 = time.perf_counter()
    cmd = ["bash", "-e", "-c", code] if b.lang == "bash" else [sys.executable, "-c", code]
    try:
        proc = subprocess.run(
            cmd,
            cwd=work,
            env=env,
            capture_output=True,
            text=True,
            timeout=BLOCK_TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"{b.page}:{b.line} ({b.lang}, run {run}) ran longer than {BLOCK_TIMEOUT_S} s")
    times = os.environ.get("MRDAMPER_DOC_TIMES")
    if times:
        with open(times, "a", encoding="utf-8") as fh:
            fh.write(f"{b.page}\t{b.line}\t{run}\t{time.perf_counter() - t0:.1f}\n")
    if proc.returncode != 0:
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-15:])
        pytest.fail(
            f"{b.page}:{b.line} ({b.lang}, run {run} of 2) exited {proc.returncode}:\n"
            f"{code}\n"
            f"--- output ---\n{tail}"
        )
    if b.expected is not None:
        _check_output(b, proc.stdout, run)
    if b.page == "README.md":
        _check_warning_lines(b, proc.stderr)
    return _snapshot(work) != before


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    """Every file under ``folder`` (links not followed) with its modification time and size."""
    out: dict[str, tuple[int, int]] = {}
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if not (Path(root) / d).is_symlink()]
        for name in files:
            st = (Path(root) / name).lstat()
            out[os.path.relpath(Path(root) / name, folder)] = (st.st_mtime_ns, st.st_size)
    return out


def _squeeze(text: str) -> str:
    return " ".join(text.split())


def _check_output(b: Block, stdout: str, run: int) -> None:
    """Every line of the output a page shows for ``b`` appears in what ``b`` printed."""
    got = _squeeze(stdout)
    missing = [ln for ln in (b.expected or "").splitlines() if _squeeze(ln) not in got]
    if missing:
        pytest.fail(
            f"{b.page}:{b.line} ({b.lang}, run {run} of 2): the page shows output that does not "
            f"come out: {missing[:3]}\n--- printed ---\n{stdout[-2000:]}"
        )


def test_shown_output_must_come_out() -> None:
    b = Block("x.md", 1, "python", "print('ESR 0.0170')\n", None, expected="ESR   0.0170")
    _check_output(b, "ESR 0.0170\n", 1)  # spaces collapsed
    with pytest.raises(pytest.fail.Exception, match="does not come out"):
        _check_output(b, "ESR 0.0206\n", 1)
    page = REPO_ROOT / "docs" / "tutorial.md"
    assert any(blk.expected for blk in blocks_of(page))


def test_a_block_that_writes_runs_again(tmp_path: Path) -> None:
    env = _env()
    reader = Block("x.md", 1, "bash", "ls\n", None)
    writer = Block("x.md", 2, "bash", "set -o noclobber; echo 1 > out.txt\n", None)
    assert not _run_block(reader, 1, tmp_path, env)
    assert _run_block(writer, 1, tmp_path, env)
    with pytest.raises(pytest.fail.Exception, match="run 2 of 2"):
        _run_block(writer, 2, tmp_path, env)  # refuses to overwrite its own output


def test_a_slow_writer_runs_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    env = _env()
    blocks = [
        Block("x.md", 1, "bash", "ls\n", None),
        Block("x.md", 2, "bash", "echo 1 > a.txt\n", None),
        Block("x.md", 3, "bash", "sleep 0.3; echo 1 > b.txt\n", None),
    ]
    monkeypatch.setattr(sys.modules[__name__], "RERUN_MAX_S", 0.2)
    assert _run_folder(blocks, tmp_path, env) == [(1, 1), (2, 1), (3, 1), (2, 2)]


def test_a_page_splits_into_folders(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    fence = "```"
    page.write_text(
        f"{fence}bash\nls\n{fence}\n<!-- doc-test: folder b -->\n"
        f"{fence}python\nprint(1)\n{fence}\n<!-- doc-test: folder main -->\n"
        f"{fence}bash\npwd\n{fence}\n",
        encoding="utf-8",
    )
    got = {name: [b.line for b in blocks] for name, blocks in folders_of(page).items()}
    assert got == {"main": [1, 9], "b": [5]}
    assert len(PARTS) > len(PAGES)  # the long pages are split


def test_outputs_must_be_ignored_and_warnings_counted(tmp_path: Path) -> None:
    if not (REPO_ROOT / ".git").exists():
        pytest.skip("not a git checkout: .gitignore is not checked")
    (tmp_path / "my-rig").mkdir()
    (tmp_path / "my-rig" / "run.csv").write_text("t\n")
    (tmp_path / "m.json").write_text("{}")
    _check_ignored(tmp_path)  # the README's and the tutorial's outputs
    (tmp_path / "stray.txt").write_text("")
    with pytest.raises(AssertionError, match="stray.txt"):
        _check_ignored(tmp_path)
    readme = Block("README.md", 1, "bash", "ls\n", None)
    once = f"{_TRACE}mrdamper score m.json\nnote: a\n{_TRACE}mrdamper inverse m.json\nnote: a\n"
    _check_warning_lines(readme, once)  # the same note from two commands
    with pytest.raises(AssertionError, match="repeats a line"):
        _check_warning_lines(readme, f"{_TRACE}mrdamper score m.json\nnote: a\nnote: a\n")
    many = "".join(f"note: n{k}\n" for k in range(MAX_WARNING_LINES + 1))
    with pytest.raises(AssertionError, match="warning lines from mrdamper score"):
        _check_warning_lines(readme, f"{_TRACE}mrdamper score m.json\n{many}")
