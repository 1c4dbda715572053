"""Help text as written: units in brackets kept, readable value types.

The terminal help formatter (rich) reads ``[...]`` as markup, so ``Vehicle speed [m/s].`` would
show as ``Vehicle speed .``; :func:`readable_help` escapes the brackets of every help text when the
app renders rich markup. It also replaces the type labels of flags (``<bool>``: a flag takes no
value, none is shown) and of repeatable values (``<list[Path]>`` becomes ``<path> ...`` for an
argument, ``<str> (repeatable)`` for an option).
"""

from __future__ import annotations

import re
from typing import Any

__all__ = ["kinds_text", "readable_help"]


def kinds_text() -> str:
    """The model kinds of the kind table (:mod:`mrdamper.kinds`), comma-separated, for help texts
    that list them (``"lpv, p15, sp1, ..."``)."""
    from mrdamper import kinds

    return ", ".join(row.kind for row in kinds.rows())


#: Click type name -> the label shown (as the other options show theirs).
_LABELS = {"text": "str", "integer": "int", "float": "float", "path": "path", "boolean": "bool"}


def _label(param: Any) -> Any:
    """A ``display_type_rich`` for ``param`` (None: keep the formatter's own): nothing for a
    flag; the element type, then ``...`` or ``(repeatable)``, for a list."""
    flag = bool(getattr(param, "is_flag", False))
    many = getattr(param, "multiple", False) or getattr(param, "nargs", 1) == -1
    if not (flag or many):
        return None
    original = param.display_type_rich

    def display_type_rich(ctx: Any = None) -> str | None:
        if flag:
            return None
        shown = str(original(ctx=ctx) or "").removesuffix("...")
        m = re.fullmatch(r"<list\[(.+)\]>", shown)
        if m is None:
            return shown or None
        name = m.group(1).lower()
        elem = f"<{_LABELS.get(name, name)}>"
        return f"{elem} (repeatable)" if getattr(param, "multiple", False) else f"{elem} ..."

    return display_type_rich


def readable_help(command: Any, markup: str | None) -> Any:
    """Make the help of ``command`` and all its subcommands readable (see the module docstring).

    Parameters
    ----------
    command : click.Command
        The command built from the Typer app (changed in place).
    markup : {"rich", "markdown"} or None
        The app's ``rich_markup_mode``: brackets are escaped only when it is ``"rich"``.

    Returns
    -------
    click.Command
        ``command``.
    """
    from rich.markup import escape

    def esc(text: str | None) -> str | None:
        return escape(text) if (text and markup == "rich") else text

    def readable(param: Any) -> Any:
        if param is None or getattr(param, "_readable", False):
            return param
        if hasattr(param, "help"):
            param.help = esc(param.help)
        shown = _label(param)
        if shown is not None:
            param.display_type_rich = shown
        param._readable = True
        return param

    command.help = esc(command.help)
    for param in command.params:
        readable(param)
    help_option = command.get_help_option  # --help is made when the help is asked for
    command.get_help_option = lambda ctx: readable(help_option(ctx))
    for sub in getattr(command, "commands", {}).values():
        readable_help(sub, markup)
    return command
