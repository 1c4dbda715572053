"""Each model family's C rendering, looked up by kind (the family-to-renderer table).

A renderer takes the fitted model and the export's :class:`Context` and returns a
:class:`Rendered`: the state struct, the constants and functions up to ``<name>_step`` (and
``<name>_inverse_step`` where the family has an inverse), header notes and the sample time the C
step must be called at. :func:`mrdamper.control.export.c_export.c_source` assembles the files and
the
FMU export (:mod:`mrdamper.control.export.fmu`) wraps the same code. Another kind of this package is
added by writing its renderer and adding it to :data:`RENDERERS`; a family of another package (a
plug-in) renders itself: its fitted model's method ``render_c(ctx: Context) -> Rendered``
(:func:`renderer_of` asks the model).

Every rendering has the same C interface: ``<name>_init(<name>_state *)`` and
``double <name>_step(<name>_state *, double x, double v, double input)``, one call per sample.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from mrdamper.control.export.c_render._common import Context, Rendered
from mrdamper.control.export.c_render.hysteresis import render_hysteresis
from mrdamper.control.export.c_render.lpv import render_lpv
from mrdamper.control.export.c_render.narx import render_narx
from mrdamper.control.export.c_render.p15 import render_p15
from mrdamper.control.export.c_render.spencer import render_spencer, render_spencer_form
from mrdamper.control.export.c_render.static import render_static

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.models import FittedModel

__all__ = ["RENDERERS", "Context", "Rendered", "render_spencer_form", "renderer_of"]

#: Model kind -> renderer ``(model, Context) -> Rendered``.
RENDERERS: dict[str, Callable[[Any, Context], Rendered]] = {
    "lpv": render_lpv,
    "lti": render_lpv,
    "sp1": render_static,
    "sp2": render_static,
    "sp3": render_static,
    "sp4": render_static,
    "bingham": render_static,
    "spencer": render_spencer,
    "p15": render_p15,
    "narx": render_narx,
    "tanh": render_hysteresis,
    "boucwen": render_hysteresis,
    "dahl": render_hysteresis,
    "lugre": render_hysteresis,
}


def renderer_of(model: FittedModel) -> Callable[[Context], Rendered] | None:
    """The C rendering of ``model``: its kind's renderer in :data:`RENDERERS`, else the model's own
    ``render_c`` method (a plug-in family's), else None (no C export).

    Parameters
    ----------
    model : FittedModel
        The model to export.
    """
    kind = getattr(model, "kind", type(model).__name__)
    if kind in RENDERERS:
        return functools.partial(RENDERERS[kind], model)
    own = getattr(model, "render_c", None)
    return own if callable(own) else None
