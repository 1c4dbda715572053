"""Pieces every family's C rendering shares (private to :mod:`mrdamper.control.export.c_render`).

Literal formatting (C99 hexadecimal floating constants, so the C code uses exactly the model's
``float64`` values), the render context and result, the min/max helpers, the regularised inverse's
solver (grid scan, then bisection of the slope) and the ``_run`` loops over arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mrdamper.control.inverse.current import (
    DEFAULT_REG_FRACTION,
    default_reg,
    force_authority,
    model_input_limits,
)
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel
from mrdamper.models.kernels import INVERSE_N_BISECT

__all__ = [
    "BISECT",
    "COMMON",
    "IDENTITY",
    "INTERVAL_C",
    "INVERSE_RUN",
    "INV_CONST",
    "RUN",
    "SOLVE",
    "STEP_SIZE",
    "STEP_WRAPPER",
    "Context",
    "Rendered",
    "arr1",
    "arr2",
    "fmt_base",
    "input_note",
    "inverse_settings",
    "lit",
    "quarter_car_defaults",
    "rates_hint",
    "require_dt",
    "sampled_step",
    "solver",
    "step_state",
]


def quarter_car_defaults() -> tuple[float, int]:
    """The quarter car's control sample [s] (the period of its roads' default rate) and inverse
    search grid: the C export's defaults, so that the exported controller is the evaluated one."""
    import inspect

    from mrdamper.control.loop.quarter_car import iso_road, simulate_quarter_car

    fs = inspect.signature(iso_road).parameters["fs"].default
    n_grid = inspect.signature(simulate_quarter_car).parameters["n_grid"].default
    return 1.0 / float(fs), int(n_grid)


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
        Search grid of the inverse (default the quarter car's).
    dt : float or None
        Sample time [s] given with the export (the fixed step of a continuous-time family, the
        inverse rate bound's interval of a static map).
    """

    name: str
    reg: float | None = None
    v_ref: float = 0.3
    rate: float | None = None
    n_grid: int = field(default_factory=lambda: quarter_car_defaults()[1])
    dt: float | None = None

    @property
    def p(self) -> str:
        return self.name

    @property
    def P(self) -> str:
        return self.name.upper()


@dataclass(frozen=True)
class Rendered:
    """One family's C rendering: what :func:`mrdamper.control.export.c_export.c_source` assembles.

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
    step_n : int
        Length of the step's state vector: the body defines the model's per-sample step as
        ``<name>_step_init``, ``<name>_step_force`` and ``<name>_step_advance`` over a
        ``double[step_n]`` state laid out as the Python step's (:mod:`mrdamper.models.step`).
    step_dt : bool
        Whether the step runs at its own sample time (``Step.dt`` set: LPV, LTI, NARX).
    """

    state: str
    body: str
    has_inverse: bool
    notes: list[str] = field(default_factory=list)
    sample_time: float | None = None
    step_n: int = 0
    step_dt: bool = False


def fmt_base(
    model: FittedModel, ctx: Context, lam: float = 0.0, rate_step: float = math.inf
) -> dict[str, Any]:
    """Format fields every template uses: prefixes, input limits, inverse settings."""
    lo, hi = model_input_limits(model)
    return {
        "p": ctx.p,
        "P": ctx.P,
        "lo": lit(lo),
        "hi": lit(hi),
        "lam2": lit(lam * lam),
        "rate_step": lit(rate_step),
        "n_grid": ctx.n_grid,
        "n_bisect": INVERSE_N_BISECT,
    }


def input_note(model: FittedModel) -> str:
    """Header line of a family with an inverse: the forward step takes the input as given (as
    the model's step: no range policy), the inverse is limited."""
    lo, hi = model_input_limits(model)
    return f"The forward step takes the input as given (not clipped); inverse on [{lo!r}, {hi!r}]."


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

#: The inverse's allowed interval in C99, the same rule as
#: :func:`mrdamper.models.kernels.allowed_interval` (it reads ``P_LO``, ``P_HI``, ``P_RATE_STEP``
#: and the ``p_dmin`` / ``p_dmax`` helpers of :data:`COMMON`); every renderer's inverse calls it.
INTERVAL_C = r"""
/* the admissible [a, b] of rho[k]: input limits, the drive lag's reach (lag >= 0; rho[1] = rho[0]),
   the rate bound around prev */
static void {p}_allowed(long k, double lag, double rho_prev, double prev, double *a, double *b)
{{
    *a = {P}_LO;
    *b = {P}_HI;
    if (lag >= 0.0 && k >= 1) {{
        if (k == 1) {{
            *a = rho_prev;
            *b = rho_prev;
        }} else {{
            *a = {p}_dmax(lag * rho_prev + (1.0 - lag) * {P}_LO, {P}_LO);
            *b = {p}_dmin(lag * rho_prev + (1.0 - lag) * {P}_HI, {P}_HI);
        }}
    }}
    if (k >= 1) {{
        *a = {p}_dmax(*a, prev - {P}_RATE_STEP);
        *b = {p}_dmin(*b, prev + {P}_RATE_STEP);
        if (*b < *a) {{
            *a = {p}_dmin({p}_dmax(prev, *a), *b);
            *b = *a;
        }}
    }}
}}
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

STEP_SIZE = r"""
long {p}_step_size(void) {{ return {P}_STEP_N; }}
"""

#: What a caller loading the compiled library needs to check it and to own a state: the size of
#: ``<name>_state`` [bytes] and the model kind.
IDENTITY = r"""
long {p}_state_size(void) {{ return (long)sizeof({p}_state); }}
const char *{p}_kind(void) {{ return "{kind}"; }}
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


#: ``<name>_init`` / ``<name>_step`` over a model's step functions: the first call sets the rest
#: state, every later call advances it over the interval from the previous call's inputs (one
#: sample time ``{P}_DT``), then returns the force; after a failed advance the status is kept and
#: the step returns NaN from then on (:func:`mrdamper.models.step.run`, one sample a call).
STEP_WRAPPER = r"""
void {p}_init({p}_state *s)
{{
    int j;
    for (j = 0; j < {n}; ++j) s->s[j] = 0.0;
    s->x = 0.0;
    s->v = 0.0;
    s->e = 0.0;
    s->k = 0;
    s->status = 0;
}}

double {p}_step({p}_state *s, double x, double v, double input)
{{
    if (s->status != 0) return NAN;
    if (s->k == 0) {{
        {p}_step_init(s->s, x, v, input);
    }} else {{
        s->status = {p}_step_advance(s->s, s->x, s->v, s->e, x, v, input, {P}_DT);
        if (s->status != 0) return NAN;
    }}
    s->x = x;
    s->v = v;
    s->e = input;
    s->k += 1;
    return {p}_step_force(s->s, x, v, input);
}}
"""


def require_dt(model: FittedModel, ctx: Context) -> float:
    """The export's sample time ``ctx.dt`` [s], required by a family without its own rate."""
    if ctx.dt is None:
        raise DataValidationError(
            "dt",
            f"the {model.kind} C step integrates fixed intervals and the model records no sample "
            f"time it was fitted at{rates_hint(model)}: give its sample time dt [s] (--dt)",
        )
    if not (ctx.dt > 0 and ctx.dt < math.inf):
        raise DataValidationError("dt", f"expected a positive sample time [s], got {ctx.dt!r}")
    return float(ctx.dt)


def rates_hint(model: FittedModel) -> str:
    """`` (training records at 1000, 200 Hz)`` when the model's provenance lists several training
    intervals (``record_dt``), else ``""``."""
    values = model.provenance.get("record_dt") if hasattr(model, "provenance") else None
    if not isinstance(values, (list, tuple)) or len(values) < 2:
        return ""
    return " (training records at " + ", ".join(f"{1.0 / float(d):g}" for d in values) + " Hz)"


def sampled_step(model: FittedModel, ctx: Context) -> tuple[Any, float]:
    """The model's step at the export's sample time (:func:`require_dt`) and the time [s].

    The step's default velocity bound (:meth:`~mrdamper.models.base.FittedModel.step_vmax`):
    the sub-steps of ``predict`` on every record at that rate within it, and the step the
    quarter car runs, so the exported damper is the validated one.
    """
    dt = require_dt(model, ctx)
    return model.step(dt=dt), dt


def step_state(p: str, n: int, what: str) -> str:
    """The ``<p>_state`` struct of :data:`STEP_WRAPPER` for a step state of ``n`` entries."""
    return (
        "typedef struct {\n"
        f"    double s[{n}]; /* step state: {what} */\n"
        "    double x, v, e; /* inputs of the last sample */\n"
        "    long k; /* samples taken */\n"
        "    int status; /* 0 ok, else the failed advance's status (the step returns NaN) */\n"
        f"}} {p}_state;\n"
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
    model: FittedModel,
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
