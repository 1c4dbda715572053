"""C99 code of an identified damper model and of its regularised inverse.

:func:`export_c` writes a self-contained pair ``<name>.h`` / ``<name>.c`` (only ``<math.h>``; no
dynamic allocation, no globals that change: all state lives in a caller-owned struct) with

* ``<name>_init(<name>_state *s)``: reset to rest;
* ``double <name>_step(<name>_state *s, double x, double v, double input)``: forward model, one
  sample: the damper force [N] for displacement ``x`` [m], velocity ``v`` [m/s] and the electrical
  input [A] or [V] at this sample (as given, as the model's step: not clipped);
* ``double <name>_inverse_step(<name>_state *s, double x, double v, double F_desired,
  double *F_out)``: the regularised inverse (:func:`mrdamper.control.inverse_current`, method
  ``"regularised"``), one sample: returns the input (for a model with a drive lag, the lagged
  input ``rho``; the driver command is the lead filter of
  :func:`mrdamper.control.driver_command`) and writes the force the model gives with it to
  ``*F_out`` (may be NULL);
* ``void <name>_run(...)`` / ``<name>_inverse_run(...)``: the step functions over arrays;
* ``long <name>_state_size(void)`` (``sizeof(<name>_state)``) and ``const char *<name>_kind(void)``
  (the model kind), with which :class:`mrdamper.control.export.c_inverse.CInverse` checks a compiled
  library and owns its state, to run ``<name>_inverse_step`` inside the quarter-car loop.

Model kinds with C export (:data:`C_KINDS`, each rendered by its family's renderer in
:mod:`mrdamper.control.export.c_render`): ``lpv`` and ``lti`` (the input-output recursion of eq. 9
with
the zone laws, the optional drive lag and, for the hysteretic input, the Dahl state ``z`` carried
in the state struct; an LTI model has no inverse: its force does not depend on the present
input), the static maps ``sp1``..``sp4`` and ``bingham``, and ``spencer`` (its per-sample step,
:meth:`~mrdamper.models.spencer.SpencerModel.step`, at the fixed sample time ``dt`` given with
the export; no inverse), ``p15`` (its step at ``dt``; no inverse), ``narx`` (at its own rate;
no inverse) and the one-state hysteresis families ``tanh``, ``boucwen``, ``dahl``, ``lugre``
(their step at ``dt``, :mod:`mrdamper.control.export.c_render.hysteresis`, and their closed-form
inverse). Every
rendering also defines the family's per-sample step as ``<name>_step_init`` /
``<name>_step_force`` / ``<name>_step_advance`` on a ``double`` state of ``<name>_step_size()``
entries laid out as the Python step's (:mod:`mrdamper.models.step`), which
:class:`mrdamper.control.export.fmu_plant.FMUPlant` runs from the quarter car. The defaults of the
inverse are the quarter car's (grid, reference velocity, regularisation at its control sample).

All constants are written as C99 hexadecimal floating literals, so the C code uses exactly the
model's ``float64`` values. The arithmetic follows the compiled Python kernels operation by
operation (the forward LPV recursion sums in another order than the record kernel), so the two
agree to rounding: tests compile the pair with ``gcc -std=c99 -Wall -Wextra -pedantic -Werror``
and compare it with ``predict`` for every kind (``tests/control/test_export_parity.py``).

A family of another package (a plug-in, :mod:`mrdamper.kinds`) is exported when its fitted model
renders itself (a method ``render_c``, :func:`mrdamper.control.export.c_render.renderer_of`);
without
its own rate (an attribute ``fs``) it takes the sample time ``dt`` as the families of
:data:`NEEDS_DT` do.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mrdamper._io import c_code_kind, check_output, write_files
from mrdamper.control.export.c_render import RENDERERS, Context, Rendered, renderer_of
from mrdamper.control.export.c_render._common import (
    IDENTITY,
    INVERSE_RUN,
    RUN,
    STEP_SIZE,
    quarter_car_defaults,
)
from mrdamper.control.export.matrices import warn_if_unstable
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel

if TYPE_CHECKING:  # pragma: no cover
    from mrdamper.models import FittedModel

__all__ = ["C_KINDS", "NEEDS_DT", "assemble", "c_source", "export_c", "needs_dt", "render"]

#: Model kinds :func:`export_c` handles.
C_KINDS = tuple(RENDERERS)
#: Kinds whose C step needs the sample time ``dt`` given at export (no rate of their own).
NEEDS_DT = ("spencer", "p15", "tanh", "boucwen", "dahl", "lugre")


def needs_dt(model: FittedModel) -> bool:
    """Whether the C step of ``model`` needs the sample time ``dt`` given at export: a kind of
    :data:`NEEDS_DT`, or a plug-in's model without a rate ``fs`` of its own."""
    return model.kind in NEEDS_DT or (model.kind not in RENDERERS and not hasattr(model, "fs"))


def render(
    model: FittedModel,
    name: str = "mrd_damper",
    *,
    reg: float | None = None,
    v_ref: float = 0.3,
    rate: float | None = None,
    n_grid: int | None = None,
    dt: float | None = None,
) -> Rendered:
    """The family's C rendering of ``model`` (see :func:`c_source` for the parameters).

    Raises
    ------
    DataValidationError
        A kind without a C rendering, a name that is not a C identifier, or a bad option.
    """
    kind = getattr(model, "kind", type(model).__name__)
    own = renderer_of(model)
    if own is None:
        raise DataValidationError(
            "model",
            f"C export handles kinds {list(C_KINDS)} and plug-in models with a render_c method, "
            f"got {kind!r}",
        )
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise DataValidationError("name", f"expected a C identifier, got {name!r}")
    if n_grid is None:
        n_grid = quarter_car_defaults()[1]
    if isinstance(n_grid, bool) or not isinstance(n_grid, int) or n_grid < 1:
        raise DataValidationError("n_grid", f"expected a positive integer, got {n_grid!r}")
    ctx = Context(name, reg=reg, v_ref=v_ref, rate=rate, n_grid=n_grid, dt=dt)
    return own(ctx)


def c_source(
    model: FittedModel,
    name: str = "mrd_damper",
    *,
    reg: float | None = None,
    v_ref: float = 0.3,
    rate: float | None = None,
    n_grid: int | None = None,
    dt: float | None = None,
) -> tuple[str, str]:
    """Header and source text of the C export (see the module docstring).

    Parameters
    ----------
    model : FittedModel
        Kind in :data:`C_KINDS`.
    name : str
        C identifier prefix and file stem.
    reg : float, optional
        Regularisation weight of the inverse [N per input unit]; default
        ``default_reg(model, v_ref, dt)`` at the LPV model's sample time or, for a static map, at
        ``dt`` (without ``dt``: the quarter car's control sample, 1 ms), the quarter car's
        default; fixed into the code.
    v_ref : float
        Velocity setting the default ``reg`` [m/s].
    rate : float, optional
        Input rate bound of the inverse [input unit/s]; needs the sample time (``dt`` or an LPV
        model's rate).
    n_grid : int, optional
        Search grid of the inverse (default the quarter car's, 16).
    dt : float, optional
        Sample time [s]: required for a Spencer, P-15, tanh, Bouc-Wen, Dahl or LuGre model (the
        interval ``<name>_step`` integrates);
        for a static map, the interval of the inverse's rate bound (only used with ``rate``) and
        of the default ``reg``; an LPV model runs at its own rate.
    """
    warn_if_unstable(model)
    return assemble(
        model, name, render(model, name, reg=reg, v_ref=v_ref, rate=rate, n_grid=n_grid, dt=dt)
    )


def assemble(model: FittedModel, name: str, r: Rendered) -> tuple[str, str]:
    """Header and source text of a rendering ``r`` of ``model`` with the prefix ``name``."""
    p = name
    unit = "A" if model.input == "i" else "V"
    guard = f"{name.upper()}_H"
    protos = [
        f"void {p}_init({p}_state *s);",
        f"double {p}_step({p}_state *s, double x, double v, double input);",
        f"void {p}_run(long n, const double *x, const double *v, const double *input, double *F);",
    ]
    step_protos = [
        f"#define {name.upper()}_STEP_N {r.step_n} /* length of the step state */",
        f"void {p}_step_init(double *s, double x0, double v0, double e0);",
        f"double {p}_step_force(const double *s, double x, double v, double e);",
        (
            f"int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, "
            "double v1, double e1, double dt);"
        ),
        f"long {p}_step_size(void);",
        f"long {p}_state_size(void); /* sizeof({p}_state) [bytes] */",
        f"const char *{p}_kind(void); /* the model kind, {model.kind!r} */",
    ]
    protos += step_protos
    if r.has_inverse:
        protos += [
            (
                f"double {p}_inverse_step({p}_state *s, double x, double v, double F_desired, "
                "double *F_out);"
            ),
            (
                f"void {p}_inverse_run(long n, const double *x, const double *v, "
                "const double *F_desired, double *input, double *F);"
            ),
        ]
    lo, hi = model.input_range
    notes = [
        f"Units: x [m], v [m/s], input [{unit}] (identified on [{lo!r}, {hi!r}]), force [N].",
        *r.notes,
    ]
    header = (
        f"/* {name}.h: {model.kind} damper model exported by mrdamper (C99, no dynamic "
        "allocation).\n"
        + "".join(f" * {line}\n" for line in notes)
        + f" */\n#ifndef {guard}\n#define {guard}\n\n{r.state}\n"
        + "\n".join(protos)
        + f"\n\n#endif /* {guard} */\n"
    )
    src = f'/* {name}.c: see {name}.h. */\n#include <math.h>\n#include "{name}.h"\n'
    src += r.body + RUN.format(p=p) + STEP_SIZE.format(p=p, P=name.upper())
    src += IDENTITY.format(p=p, kind=model.kind)
    if r.has_inverse:
        src += INVERSE_RUN.format(p=p)
    return header, src


def export_c(
    model: FittedModel,
    out_dir: str | Path,
    *,
    name: str = "mrd_damper",
    force: bool = False,
    **kwargs: Any,
) -> tuple[Path, Path]:
    """Write ``<out_dir>/<name>.h`` and ``<name>.c`` atomically (see :func:`c_source` for the
    options).

    Parameters
    ----------
    model : FittedModel
        A model of a kind in :data:`C_KINDS`.
    out_dir : str or Path
        Folder of the two files (created if missing).
    name : str
        C identifier used as file stem and prefix of every symbol.
    force : bool
        Overwrite existing files.
    **kwargs
        Options of :func:`c_source` (``n_grid``, ``reg``, ...).

    Returns
    -------
    (Path, Path)
        Header and source files.

    Raises
    ------
    DataValidationError
        Unsupported model kind or bad option.
    OutputExistsError
        A file exists and ``force`` is False (nothing is written then).
    """
    header, src = c_source(model, name, **kwargs)
    d = Path(out_dir)
    if d.exists() and not d.is_dir():
        raise DataValidationError("out_dir", f"{d} exists and is not a folder")
    check_output(d, force=force, folder=True, mode="add")
    kind = c_code_kind()
    write_files(
        d,
        {
            f"{name}.h": (kind, lambda p: p.write_text(header, encoding="utf-8")),
            f"{name}.c": (kind, lambda p: p.write_text(src, encoding="utf-8")),
        },
        force=force,
    )
    return d / f"{name}.h", d / f"{name}.c"
