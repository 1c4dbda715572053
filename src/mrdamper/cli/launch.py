"""Entry point of the ``mrdamper`` console script and ``python -m mrdamper``.

It looks at the command line before anything heavy is imported: for ``mrdamper demo`` it starts
the background compilation of the numerical kernels at once (:func:`mrdamper.compiled.start_early`),
so that on a fresh installation the second core compiles while this process imports its libraries
and the command line is parsed. Everything else is :func:`mrdamper.cli.main.main`.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

__all__ = ["demo_kinds", "main"]


def demo_kinds(args: Sequence[str]) -> list[str] | None:
    """Model kinds whose kernels ``mrdamper demo`` will need, from its arguments ``args``
    (without the program name); None when ``args`` is not a demo that runs (another command,
    ``--help``). Without ``--models``: every kind with compiled kernels (the demo's default)."""
    from mrdamper.compiled import KERNELS

    words = [a for a in args if a not in ("--debug",)]
    if not words or words[0] != "demo" or any(a in ("-h", "--help") for a in words):
        return None
    kinds: list[str] = list(KERNELS)
    for k, a in enumerate(words):
        if a == "--models" and k + 1 < len(words):
            kinds = words[k + 1].split(",")
        elif a.startswith("--models="):
            kinds = a.split("=", 1)[1].split(",")
    return [k.strip() for k in kinds if k.strip()]


def main(argv: Sequence[str] | None = None) -> None:
    """Run the ``mrdamper`` command line with ``argv`` (default: ``sys.argv[1:]``)."""
    args = list(sys.argv[1:] if argv is None else argv)
    kinds = demo_kinds(args)
    if kinds:
        from mrdamper import compiled

        compiled.start_early(kinds)
    from mrdamper.cli.main import main as run

    try:
        run(args)
    finally:
        if kinds:
            from mrdamper import compiled

            compiled.finish_ahead(cancel=True)  # no-op after a demo that ran to its end
