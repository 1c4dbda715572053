"""The version of mrdamper (its one source: the package metadata reads it from here) and the
commit of the source that runs (:func:`git_commit`, shown by ``mrdamper --version`` and in every
report)."""

from __future__ import annotations

import functools
import subprocess
from pathlib import Path

__all__ = ["__version__", "git_commit", "version_text"]

__version__ = "0.2.0"


@functools.cache
def git_commit() -> str | None:
    """The commit of the mrdamper source this process runs, or None when it is not a git checkout.

    The commit is that of the checkout holding this very package (``<root>/src/mrdamper``), never
    of another repository the installation happens to sit in. ``+dirty`` is appended when tracked
    files differ from the commit.

    Returns
    -------
    str or None
    """
    package = Path(__file__).resolve().parent

    def git(*args: str) -> str | None:
        try:
            proc = subprocess.run(
                ["git", "-C", str(package), *args],
                capture_output=True,
                text=True,
                timeout=10,
                check=False,
            )
        except (OSError, subprocess.SubprocessError):
            return None
        return proc.stdout.strip() if proc.returncode == 0 else None

    top = git("rev-parse", "--show-toplevel")
    if top is None or Path(top).resolve() / "src" / "mrdamper" != package:
        return None
    head = git("rev-parse", "HEAD")
    if not head:
        return None
    dirty = git("status", "--porcelain", "--untracked-files=no")
    return head + ("+dirty" if dirty else "")


def version_text() -> str:
    """``"mrdamper 0.2.0 (commit 0123456789ab)"``, or ``"... (not run from a git checkout)"``."""
    commit = git_commit()
    where = f"commit {commit[:12]}" if commit else "not run from a git checkout"
    dirty = " with uncommitted changes" if commit and commit.endswith("+dirty") else ""
    return f"mrdamper {__version__} ({where}{dirty})"
