"""C rendering of the static maps SP-1..SP-4 and Bingham (``A(i) tanh(a(i) v + b(i) x) + c(i) v +
d(i) x + f0``, each component a polynomial in the input) and their regularised inverse."""

from __future__ import annotations

from mrdamper.control.export.c_render._common import (
    COMMON,
    INTERVAL_C,
    INV_CONST,
    Context,
    Rendered,
    arr1,
    fmt_base,
    input_note,
    inverse_settings,
    lit,
    quarter_car_defaults,
    solver,
)
from mrdamper.errors import DataValidationError
from mrdamper.models.base import FittedModel

__all__ = ["render_static"]

STATIC = r"""
#define {P}_N_THETA {n_theta}
static const int {P}_COMP[{P}_N_THETA] = {comp};
static const int {P}_POWER[{P}_N_THETA] = {power};
static const double {P}_THETA[{P}_N_THETA] = {theta};
static const double {P}_F0 = {f0};
static const double {P}_LO = {lo}; /* input limits of the inverse */
static const double {P}_HI = {hi};

static double {p}_ipow(double x, int n)
{{
    double r = 1.0;
    int q;
    for (q = 0; q < n; ++q) r *= x;
    return r;
}}

/* A(i) tanh(a(i) v + b(i) x) + c(i) v + d(i) x + f0, each component a polynomial in i */
static double {p}_force(double x, double v, double i)
{{
    double c[5] = {{0.0, 0.0, 0.0, 0.0, 0.0}};
    int q;
    for (q = 0; q < {P}_N_THETA; ++q) c[{P}_COMP[q]] += {P}_THETA[q] * {p}_ipow(i, {P}_POWER[q]);
    return c[0] * tanh(c[1] * v + c[2] * x) + c[3] * v + c[4] * x + {P}_F0;
}}

void {p}_init({p}_state *s)
{{
    s->prev = {P}_LO;
    s->k = 0;
}}

double {p}_step({p}_state *s, double x, double v, double input)
{{
    (void)s;
    return {p}_force(x, v, input); /* the input as given, as the model's step */
}}

double {p}_inverse_step({p}_state *s, double x, double v, double F_desired, double *F_out)
{{
    double a = {P}_LO, b = {P}_HI, prev = s->prev, best;
    {p}_allowed(s->k, -1.0, prev, prev, &a, &b);
    best = {p}_solve(x, v, F_desired, a, b, prev);
    s->prev = best;
    s->k += 1;
    if (F_out) *F_out = {p}_force(x, v, best);
    return best;
}}
"""

#: The map's per-sample step (:mod:`mrdamper.models.sp.kernels`): the state is the map's input.
STATIC_STEP = r"""
void {p}_step_init(double *s, double x0, double v0, double e0)
{{
    (void)x0;
    (void)v0;
    s[0] = e0;
}}

double {p}_step_force(const double *s, double x, double v, double e)
{{
    (void)s;
    return {p}_force(x, v, e);
}}

int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, double v1,
                     double e1, double dt)
{{
    (void)x0;
    (void)v0;
    (void)e0;
    (void)x1;
    (void)v1;
    (void)dt;
    s[0] = e1;
    return 0;
}}
"""

STATIC_DFORCE = r"""
static double {p}_dforce(double x, double v, double i)
{{
    double A = 0.0, a = 0.0, b = 0.0, dA = 0.0, da = 0.0, db = 0.0, dc = 0.0, dd = 0.0, th;
    int q;
    for (q = 0; q < {P}_N_THETA; ++q) {{
        int pw = {P}_POWER[q];
        double term = {P}_THETA[q] * {p}_ipow(i, pw);
        double dterm = pw > 0 ? (double)pw * {P}_THETA[q] * {p}_ipow(i, pw - 1) : 0.0;
        switch ({P}_COMP[q]) {{
        case 0: A += term; dA += dterm; break;
        case 1: a += term; da += dterm; break;
        case 2: b += term; db += dterm; break;
        case 3: dc += dterm; break;
        default: dd += dterm; break;
        }}
    }}
    th = tanh(a * v + b * x);
    return dA * th + A * (1.0 - th * th) * (da * v + db * x) + dc * v + dd * x;
}}
"""


def render_static(model: FittedModel, ctx: Context) -> Rendered:
    """C of a static map and its inverse (any sample rate; ``ctx.dt`` sets the rate bound's and
    the default regularisation's interval, by default the quarter car's control sample)."""
    eta = getattr(model, "eta", None)
    if eta is not None:
        raise DataValidationError(
            "model",
            f"C export of a static {model.kind} map with a drive lag (eta = {eta:g} 1/s) is "
            "not implemented; export the map without the lag or an LPV model with its drive lag",
        )
    p = ctx.p
    if ctx.rate is not None and ctx.dt is None:
        raise DataValidationError(
            "dt", "a rate bound on a static map's inverse needs the sample time dt [s]"
        )
    step_dt = quarter_car_defaults()[0] if ctx.dt is None else float(ctx.dt)
    lam, rate_step = inverse_settings(model, ctx.reg, ctx.v_ref, ctx.rate, step_dt)
    fmt = fmt_base(model, ctx, lam, rate_step)
    form = model.step().form
    fmt.update(
        n_theta=form.theta.size,
        comp="{" + ", ".join(str(int(c)) for c in form.comp) + "}",
        power="{" + ", ".join(str(int(q)) for q in form.power) + "}",
        theta=arr1(form.theta),
        f0=lit(form.f0),
    )
    state = (
        f"typedef struct {{\n    double prev; /* input of the last inverse sample */\n"
        f"    long k; /* inverse samples taken */\n}} {p}_state;\n"
    )
    head, inv = STATIC.split("double {p}_inverse_step", 1)
    body = (
        COMMON.format(**fmt)
        + INV_CONST.format(**fmt)
        + head.format(**fmt)
        + STATIC_STEP.format(**fmt)
        + STATIC_DFORCE.format(**fmt)
    )
    body += solver(
        fmt, "double x, double v", "x, v", f"{p}_force(x, v, {{r}})", f"{p}_dforce(x, v, {{r}})"
    )
    body += INTERVAL_C.format(**fmt) + ("double {p}_inverse_step" + inv).format(**fmt)
    return Rendered(
        state,
        body,
        True,
        [
            input_note(model),
            "Sample rate: any (static map).",
            f"Inverse: regularisation weight {lam!r}, grid {ctx.n_grid}.",
        ],
        step_n=1,
    )
