"""Pieces every family's C rendering shares (private to :mod:`mrdamper.control.c_render`).

Literal formatting (C99 hexadecimal floating constants, so the C code uses exactly the model's
``float64`` values), the render context and result, the min/max helpers, the regularised inverse's
solver (grid scan, then bisection of the slope) and the ``_run`` loops over arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mrdamper.control import _solve_kernels as K
from mrdamper.control.inverse import (
    DEFAULT_REG_FRACTION,
    default_reg,
    force_authority,
    model_input_limits,
)
from mrdamper.errors import DataValidationError

__all__ = [
    "BISECT",
    "COMMON",
    "INVERSE_RUN",
    "INV_CONST",
    "RUN",
    "SOLVE",
    "Context",
    "Rendered",
    "arr1",
    "arr2",
    "clip_note",
    "fmt_base",
    "inverse_settings",
    "lit",
    "solver",
]


@dataclass(frozen=True)
class Context:
    """Options of one C export.

    Attributes
    ----------
    name : str
        C identifier prefix (``p``; ``P`` is its upper case).
    reg : float or None
        Regularisation weight of the inverse [N per input unit] (None: the model's default).
    v_ref : float
        Velocity setting the default ``reg`` [m/s].
    rate : float or None
        Input rate bound of the inverse [input unit/s].
    n_grid : int
        Search grid of the inverse.
    dt : float or None
        Sample time [s] given with the export (the fixed step of a continuous-time family, the
        inverse rate bound's interval of a static map).
    """

    name: str
    reg: float | None = None
    v_ref: float = 0.3
    rate: float | None = None
    n_grid: int = 32
    dt: float | None = None

    @property
    def p(self) -> str:
        return self.name

    @property
    def P(self) -> str:
        return self.name.upper()


@dataclass(frozen=True)
class Rendered:
    """One family's C rendering: what :func:`mrdamper.control.c_export.c_source` assembles.

    Attributes
    ----------
    state : str
        The ``typedef struct {...} <name>_state;`` text of the header.
    body : str
        Source text after the shared min/max helpers: constants and functions up to
        ``<name>_step`` (and ``<name>_inverse_step`` when ``has_inverse``).
    has_inverse : bool
        Whether ``<name>_inverse_step`` is defined.
    notes : list of str
        Lines of the header comment (units, input range, sample rate, inverse settings).
    sample_time : float or None
        The sample time [s] the C step must be called at, None where any is allowed.
    """

    state: str
    body: str
    has_inverse: bool
    notes: list[str] = field(default_factory=list)
    sample_time: float | None = None


def fmt_base(
    model: Any, ctx: Context, lam: float = 0.0, rate_step: float = math.inf
) -> dict[str, Any]:
    """Format fields every template uses: prefixes, input limits, inverse settings."""
    lo, hi = model_input_limits(model)
    return {
        "p": ctx.p,
        "P": ctx.P,
        "lo": lit(lo),
        "hi": lit(hi),
        "in_lo": lit(model.input_range[0]),
        "in_hi": lit(model.input_range[1]),
        "lam2": lit(lam * lam),
        "rate_step": lit(rate_step),
        "n_grid": ctx.n_grid,
        "n_bisect": K._N_BISECT,
    }


def clip_note(model: Any) -> str:
    """Header line of a family whose forward step clips the input and whose inverse is limited."""
    lo, hi = model_input_limits(model)
    return f"The forward step clips the input to the identified range; inverse on [{lo!r}, {hi!r}]."


def lit(x: float) -> str:
    """``x`` as a C99 hexadecimal floating literal (``HUGE_VAL`` for infinities; NaN refused)."""
    x = float(x)
    if math.isinf(x):
        return "HUGE_VAL" if x > 0 else "(-HUGE_VAL)"
    if math.isnan(x):
        raise DataValidationError("model", "a NaN constant cannot be exported")
    return x.hex() if x != 0.0 else "0.0"


def arr1(a: Any) -> str:
    """A C initialiser ``{...}`` of the values of ``a`` (flattened)."""
    return "{" + ", ".join(lit(v) for v in np.ravel(a)) + "}"


def arr2(a: Any) -> str:
    """A C initialiser ``{{...}, ...}`` of the rows of the 2-D array ``a``."""
    return "{" + ", ".join(arr1(row) for row in np.asarray(a)) + "}"


# C templates for str.format ({{ and }} are literal braces). A line longer than 100 columns is
# split into adjacent raw strings, which join into the one C line.
COMMON = r"""
static double {p}_dmax(double a, double b) {{ return a > b ? a : b; }}
static double {p}_dmin(double a, double b) {{ return a < b ? a : b; }}
"""

INV_CONST = r"""
static const double {P}_LAM2 = {lam2}; /* squared regularisation weight [N^2 per input unit^2] */
static const double {P}_RATE_STEP = {rate_step}; /* largest input change per sample */
static const int {P}_N_GRID = {n_grid};
"""

SOLVE = (
    r"""
/* slope of the regularised objective (half its derivative) */
static double {p}_slope({args}, double target, double r, double prev)
{{
    return ({F_r} - target) * {dF_r} + {P}_LAM2 * (r - prev);
}}

/* minimiser of (F(r) - target)^2 + lam^2 (r - prev)^2 on [a, b]: grid scan, then the zero of the
   slope next to the best grid point, bisected to machine precision */
static double {p}_solve({args}, double target, double a, double b, double prev)
{{
    double best = {p}_dmin({p}_dmax(prev, a), b), best_j, h, f, g, r;
    int q;
    f = {F_best};
    best_j = (f - target) * (f - target) + {P}_LAM2 * (best - prev) * (best - prev);
    if (b <= a) return best;
    h = (b - a) / {P}_N_GRID;
    for (q = 0; q <= {P}_N_GRID; ++q) {{
        double j;
        r = (q == {P}_N_GRID) ? b : a + q * h;
        f = {F_r};
        j = (f - target) * (f - target) + {P}_LAM2 * (r - prev) * (r - prev);
        if (j < best_j) {{
            best = r;
            best_j = j;
        }}
    }}
    g = {p}_slope({call}, target, best, prev);
    if (g > 0.0 && best > a) {{
        double lo = {p}_dmax(a, best - h);
        if ({p}_slope({call}, target, lo, prev) < 0.0)"""
    r""" best = {p}_bisect({call}, target, prev, lo, best);
    }} else if (g < 0.0 && best < b) {{
        double hi = {p}_dmin(b, best + h);
        if ({p}_slope({call}, target, hi, prev) > 0.0)"""
    r""" best = {p}_bisect({call}, target, prev, best, hi);
    }}
    return best;
}}
"""
)

BISECT = r"""
static double {p}_bisect({args}, double target, double prev, double a, double b)
{{
    int it;
    for (it = 0; it < {n_bisect}; ++it) {{
        double m = 0.5 * (a + b), g;
        if (m <= a || m >= b) break;
        g = {p}_slope({call}, target, m, prev);
        if (g == 0.0) return m;
        if (g < 0.0) a = m;
        else b = m;
    }}
    return 0.5 * (a + b);
}}
"""


RUN = r"""
void {p}_run(long n, const double *x, const double *v, const double *input, double *F)
{{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < n; ++k) F[k] = {p}_step(&s, x[k], v[k], input[k]);
}}
"""

INVERSE_RUN = (
    r"""
void {p}_inverse_run(long n, const double *x, const double *v, const double *F_desired,"""
    r""" double *input, double *F)
{{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < n; ++k) input[k] = {p}_inverse_step(&s, x[k], v[k], F_desired[k], &F[k]);
}}
"""
)


def solver(fmt: dict[str, Any], args: str, call: str, f_expr: str, df_expr: str) -> str:
    """Slope, bisection and solver functions of the regularised inverse for one force expression."""
    sub = dict(
        fmt,
        args=args,
        call=call,
        F_r=f_expr.format(r="r"),
        dF_r=df_expr.format(r="r"),
        F_best=f_expr.format(r="best"),
    )
    slope, solve = SOLVE.split("/* minimiser", 1)
    return slope.format(**sub) + BISECT.format(**sub) + ("/* minimiser" + solve).format(**sub)


def inverse_settings(
    model: Any,
    reg: float | None,
    v_ref: float,
    rate: float | None,
    dt: float,
    dt_known: bool = True,
) -> tuple[float, float]:
    """Regularisation weight [N per input unit] and largest input change per sample of the inverse.

    ``reg`` None: the model's default at ``v_ref`` [m/s] and the sample time ``dt`` [s] (without
    ``dt_known``, the 200 Hz value); ``rate`` [input unit/s] times ``dt`` bounds the change per
    sample (None: unbounded).
    """
    lo, hi = model_input_limits(model)
    if reg is None and not hi > lo:
        lam = 0.0
    elif reg is None:
        lam = (
            default_reg(model, v_ref, dt)
            if dt_known
            else DEFAULT_REG_FRACTION * force_authority(model, v_ref)
        )
    elif not (np.isfinite(reg) and reg >= 0):
        raise DataValidationError("reg", f"expected a regularisation weight >= 0, got {reg!r}")
    else:
        lam = float(reg)
    if rate is None:
        step = math.inf
    elif not (np.isfinite(rate) and rate > 0):
        raise DataValidationError("rate", f"expected a positive input rate bound, got {rate!r}")
    else:
        step = float(rate) * dt
    return lam, step
