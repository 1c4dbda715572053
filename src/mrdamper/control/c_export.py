"""C99 code of an identified damper model and of its regularised inverse.

:func:`export_c` writes a self-contained pair ``<name>.h`` / ``<name>.c`` (only ``<math.h>``; no
dynamic allocation, no globals that change: all state lives in a caller-owned struct) with

* ``<name>_init(<name>_state *s)``: reset to rest;
* ``double <name>_step(<name>_state *s, double x, double v, double input)``: forward model, one
  sample: the damper force [N] for displacement ``x`` [m], velocity ``v`` [m/s] and the electrical
  input [A] or [V] at this sample (clipped to the identified input range);
* ``double <name>_inverse_step(<name>_state *s, double x, double v, double F_desired,
  double *F_out)``: the regularised inverse (:func:`mrdamper.control.inverse_current`, method
  ``"regularised"``), one sample: returns the input (for an LPV model with a drive lag, the
  scheduling value ``rho``; the driver command is the lead filter of
  :func:`mrdamper.control.driver_command`) and writes the force the model gives with it to
  ``*F_out`` (may be NULL);
* ``void <name>_run(...)`` / ``<name>_inverse_run(...)``: the step functions over arrays.

Model kinds with C export: ``lpv`` and ``lti`` (the input-output recursion of eq. 9 with the zone
laws, the optional drive lag and, for the hysteretic input, the Dahl state ``z`` carried in the
state struct and stepped with the model's exact update from the velocity passed to each call,
from rest ``z = 0``; an LTI model has no inverse: its force does not depend on the
present input) and the static maps ``sp1``..``sp4`` and ``bingham``. Spencer (a stiff ODE whose
integration scheme would also have to be fixed in C), P-15 and NARX are not exported.

All constants are written as C99 hexadecimal floating literals, so the C code uses exactly the
model's ``float64`` values. The arithmetic follows the compiled Python kernels operation by
operation (the forward LPV recursion sums in another order than the record kernel), so the two
agree to rounding: a test compiles the pair with ``gcc -std=c99 -Wall -Werror`` and compares it with
the Python simulation on a real record.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from mrdamper._io import atomic_write_text, check_writable
from mrdamper.control import _inverse_kernels as K
from mrdamper.control.export import warn_if_unstable
from mrdamper.control.inverse import (
    DEFAULT_REG_FRACTION,
    default_reg,
    force_authority,
    horizon_samples,
    lpv_hysteresis,
    lpv_law_arrays,
    model_input_limits,
    static_map_arrays,
)
from mrdamper.errors import DataValidationError

__all__ = ["C_KINDS", "c_source", "export_c"]

#: Model kinds :func:`export_c` handles.
C_KINDS = ("lpv", "lti", "sp1", "sp2", "sp3", "sp4", "bingham")


def _f(x: float) -> str:
    x = float(x)
    if math.isinf(x):
        return "HUGE_VAL" if x > 0 else "(-HUGE_VAL)"
    if math.isnan(x):
        raise DataValidationError("model", "a NaN constant cannot be exported")
    return x.hex() if x != 0.0 else "0.0"


def _arr1(a: Any) -> str:
    return "{" + ", ".join(_f(v) for v in np.ravel(a)) + "}"


def _arr2(a: Any) -> str:
    return "{" + ", ".join(_arr1(row) for row in np.asarray(a)) + "}"


# C templates for str.format ({{ and }} are literal braces). A line longer than 100 columns is
# split into adjacent raw strings, which join into the one C line.
_COMMON = r"""
static double {p}_dmax(double a, double b) {{ return a > b ? a : b; }}
static double {p}_dmin(double a, double b) {{ return a < b ? a : b; }}
"""

_INV_CONST = r"""
static const double {P}_LAM2 = {lam2}; /* squared regularisation weight [N^2 per input unit^2] */
static const double {P}_RATE_STEP = {rate_step}; /* largest input change per sample */
static const int {P}_N_GRID = {n_grid};
"""

_LPV = (
    r"""
#define {P}_N_M {n_m}
#define {P}_N_P {n_p}
#define {P}_N_D {n_d}
static const double {P}_ALPHA[{P}_N_M][{P}_N_P] = {alpha};
static const double {P}_BETA[{P}_N_M][{P}_N_P] = {beta};
static const double {P}_OFFSET = {offset};
static const double {P}_IN_LO = {in_lo}; /* identified input range: the forward step clips to it */
static const double {P}_IN_HI = {in_hi};
static const double {P}_LO = {lo}; /* lower input limit of the inverse, rest state */
static const double {P}_LAG = {lag}; /* exp(-eta / fs), or -1: no drive lag */
static const int {P}_MODE = {mode}; /* 0: u = v; 1: continuous, 2: literal reading of eq. 22 */
static const double {P}_GM[3][{P}_N_D] = {gm};
static const double {P}_GC[3][{P}_N_D] = {gc};
static const double {P}_MU_HIGH[2] = {mu_high};
static const double {P}_MU_LOW[2] = {mu_low};
static const double {P}_BLEND = {blend}; /* share of the Dahl state in u; 0: static input */
static const double {P}_STROKE = {stroke}; /* stroke scale x_y of the Dahl state [m] */
static const double {P}_DT = {dt}; /* model sample time [s] */

static double {p}_poly(const double *c, int n, double r)
{{
    double acc = 0.0;
    int q;
    for (q = n - 1; q >= 0; --q) acc = acc * r + c[q];
    return acc;
}}

/* LPV input; with BLEND != 0 the hysteretic input with the Dahl state z */
static double {p}_u_of(double v, double r, double z)
{{
    double hi, lo, m1, m2, m3;
    if ({P}_MODE == 0) return v;
    hi = {P}_MU_HIGH[0] * r + {P}_MU_HIGH[1];
    lo = {P}_MU_LOW[0] * r + {P}_MU_LOW[1];
    m1 = {p}_poly({P}_GM[0], {P}_N_D, r);
    m2 = {p}_poly({P}_GM[1], {P}_N_D, r);
    m3 = {p}_poly({P}_GM[2], {P}_N_D, r);
    if ({P}_BLEND != 0.0) {{
        double ratio = (v >= 0.0 ? m3 : m1) / m2, level = z >= 0.0 ? hi : -lo;
        double pre = (1.0 - {P}_BLEND) * {p}_dmin({p}_dmax(v, lo), hi) + {P}_BLEND * level * z;
        return (1.0 - ratio) * pre + ratio * v;
    }}
    if (v < lo) {{
        if ({P}_MODE == 1) return lo + m1 / m2 * (v - lo);
        return (m1 * v + {p}_poly({P}_GC[0], {P}_N_D, r)) / m2;
    }}
    if (v > hi) {{
        if ({P}_MODE == 1) return hi + m3 / m2 * (v - hi);
        return (m3 * v + {p}_poly({P}_GC[2], {P}_N_D, r)) / m2;
    }}
    return v;
}}

/* coefficients in rho of the force at this sample, from the stored past */
static void {p}_coefficients(const {p}_state *s, double *cf)
{{
    int p, j;
    for (p = 0; p < {P}_N_P; ++p) {{
        double acc = 0.0;
        for (j = 0; j < {P}_N_M && j < s->k; ++j) acc += {P}_BETA[j][p] * s->u[j]"""
    r""" - {P}_ALPHA[j][p] * s->y[j];
        cf[p] = acc;
    }}
    cf[0] += {P}_OFFSET;
}}

static void {p}_commit({p}_state *s, double F, double v, double r)
{{
    int j;
    for (j = {P}_N_M - 1; j > 0; --j) {{
        s->y[j] = s->y[j - 1];
        s->u[j] = s->u[j - 1];
    }}
    s->y[0] = F - {P}_OFFSET;
    s->u[0] = {p}_u_of(v, r, s->z);
    s->rho = r;
    s->k += 1;
}}

/* Dahl state at this sample: exact step over the trapezoidal displacement (from rest, z = 0) */
static void {p}_advance({p}_state *s, double v)
{{
    if ({P}_BLEND != 0.0 && s->k > 0) {{
        double dx = 0.5 * (s->v_prev + v) * {P}_DT;
        if (dx > 0.0) s->z = 1.0 + (s->z - 1.0) * exp(-dx / {P}_STROKE);
        else if (dx < 0.0) s->z = -1.0 + (s->z + 1.0) * exp(dx / {P}_STROKE);
    }}
    s->v_prev = v;
}}

void {p}_init({p}_state *s)
{{
    int j;
    for (j = 0; j < {P}_N_M; ++j) {{
        s->y[j] = 0.0;
        s->u[j] = 0.0;
    }}
    s->rho = {P}_LO;
    s->w = {P}_LO;
    s->z = 0.0;
    s->v_prev = 0.0;
    s->k = 0;
}}

double {p}_step({p}_state *s, double x, double v, double input)
{{
    double cf[{P}_N_P];
    double w = {p}_dmin({p}_dmax(input, {P}_IN_LO), {P}_IN_HI);
    double r = w, F;
    (void)x;
    if ({P}_LAG >= 0.0 && s->k > 0) r = {P}_LAG * s->rho + (1.0 - {P}_LAG) * s->w;
    s->w = w;
    {p}_advance(s, v);
    {p}_coefficients(s, cf);
    F = {p}_poly(cf, {P}_N_P, r);
    {p}_commit(s, F, v, r);
    return F;
}}
"""
)

_LPV_DPOLY = r"""
static const double {P}_HI = {hi}; /* upper input limit of the inverse */
static double {p}_dpoly(const double *c, int n, double r)
{{
    double acc = 0.0;
    int q;
    for (q = n - 1; q > 0; --q) acc = acc * r + q * c[q];
    return acc;
}}
"""

_LPV_HORIZON = (
    r"""
static const int {P}_HORIZON = {horizon}; /* lead horizon [samples] of the drive-lag inverse */
static const double {P}_GOLDEN = {golden};

/* mean squared force error over the horizon: this sample at r, then the model run on with the
   command w held, the velocity v and the Dahl state held and the same target */
static double {p}_hcost(const {p}_state *s, const double *cf, double r, double w, double v,"""
    r""" double target)
{{
    double ys[{P}_N_M], us[{P}_N_M], c2[{P}_N_P], F, e, acc, rr;
    int j, q, h, nv = s->k < {P}_N_M ? (int)s->k : {P}_N_M;
    for (j = 0; j < {P}_N_M; ++j) {{
        ys[j] = s->y[j];
        us[j] = s->u[j];
    }}
    F = {p}_poly(cf, {P}_N_P, r);
    e = F - target;
    acc = e * e;
    rr = r;
    for (h = 1; h < {P}_HORIZON; ++h) {{
        for (j = {P}_N_M - 1; j > 0; --j) {{
            ys[j] = ys[j - 1];
            us[j] = us[j - 1];
        }}
        ys[0] = F - {P}_OFFSET;
        us[0] = {p}_u_of(v, rr, s->z);
        if (nv < {P}_N_M) nv += 1;
        rr = {P}_LAG * rr + (1.0 - {P}_LAG) * w;
        for (q = 0; q < {P}_N_P; ++q) {{
            double a2 = 0.0;
            for (j = 0; j < nv; ++j) a2 += {P}_BETA[j][q] * us[j] - {P}_ALPHA[j][q] * ys[j];
            c2[q] = a2;
        }}
        c2[0] += {P}_OFFSET;
        F = {p}_poly(c2, {P}_N_P, rr);
        e = F - target;
        acc += e * e;
    }}
    return acc / {P}_HORIZON;
}}

static double {p}_hj(const {p}_state *s, const double *cf, double r, double prev,"""
    r""" double hold, double v,
                     double target)
{{
    double w = (r - {P}_LAG * prev) / (1.0 - {P}_LAG), d = r - hold;
    return {p}_hcost(s, cf, r, w, v, target) + {P}_LAM2 * d * d;
}}

/* rho on [a, b] minimising the horizon cost of the command it implies: grid scan, then golden
   section on the grid intervals either side of the best point */
static double {p}_hstep(const {p}_state *s, const double *cf, double a, double b,"""
    r""" double prev, double hold,
                        double v, double target)
{{
    double best = {p}_dmin({p}_dmax(hold, a), b), best_j, h, lo, hi, m, jm;
    int q, it;
    best_j = {p}_hj(s, cf, best, prev, hold, v, target);
    if (b <= a) return best;
    h = (b - a) / {P}_N_GRID;
    for (q = 0; q <= {P}_N_GRID; ++q) {{
        double r = (q == {P}_N_GRID) ? b : a + q * h, j = {p}_hj(s, cf, r, prev, hold, v, target);
        if (j < best_j) {{
            best = r;
            best_j = j;
        }}
    }}
    lo = {p}_dmax(a, best - h);
    hi = {p}_dmin(b, best + h);
    for (it = 0; it < {n_golden}; ++it) {{
        double c1 = hi - {P}_GOLDEN * (hi - lo), c3 = lo + {P}_GOLDEN * (hi - lo);
        if ({p}_hj(s, cf, c1, prev, hold, v, target)"""
    r""" <= {p}_hj(s, cf, c3, prev, hold, v, target)) hi = c3;
        else lo = c1;
    }}
    m = 0.5 * (lo + hi);
    jm = {p}_hj(s, cf, m, prev, hold, v, target);
    if (jm < best_j) best = m;
    return best;
}}
"""
)

_LPV_INVERSE = (
    r"""double {p}_inverse_step({p}_state *s, double x, double v, double F_desired, double *F_out)
{{
    double cf[{P}_N_P];
    double a = {P}_LO, b = {P}_HI, prev = s->rho, hold, r, F;
    (void)x;
    {p}_advance(s, v);
    {p}_coefficients(s, cf);
    if ({P}_LAG >= 0.0 && s->k >= 1) {{
        if (s->k == 1) {{
            a = s->rho;
            b = s->rho;
        }} else {{
            a = {p}_dmax({P}_LAG * s->rho + (1.0 - {P}_LAG) * {P}_LO, {P}_LO);
            b = {p}_dmin({P}_LAG * s->rho + (1.0 - {P}_LAG) * {P}_HI, {P}_HI);
        }}
    }}
    if (s->k >= 1) {{
        a = {p}_dmax(a, prev - {P}_RATE_STEP);
        b = {p}_dmin(b, prev + {P}_RATE_STEP);
        if (b < a) {{
            a = {p}_dmin({p}_dmax(prev, a), b);
            b = a;
        }}
    }}
    hold = prev;
    if ({P}_LAG >= 0.0 && s->k >= 2) hold ="""
    r""" {p}_dmin({p}_dmax({P}_LAG * prev + (1.0 - {P}_LAG) * s->w, a), b);
    if ({P}_LAG >= 0.0 && s->k >= 2 && {P}_HORIZON > 1)"""
    r""" r = {p}_hstep(s, cf, a, b, prev, hold, v, F_desired);
    else r = {p}_solve(cf, F_desired, a, b, hold);
    if ({P}_LAG >= 0.0) {{ /* command of the previous sample (the lead of the lag) */
        s->w = s->k <= 1 ? r :"""
    r""" {p}_dmin({p}_dmax((r - {P}_LAG * prev) / (1.0 - {P}_LAG), {P}_LO), {P}_HI);
    }}
    F = {p}_poly(cf, {P}_N_P, r);
    {p}_commit(s, F, v, r);
    if (F_out) *F_out = F;
    return r;
}}
"""
)

_STATIC = r"""
#define {P}_N_THETA {n_theta}
static const int {P}_COMP[{P}_N_THETA] = {comp};
static const int {P}_POWER[{P}_N_THETA] = {power};
static const double {P}_THETA[{P}_N_THETA] = {theta};
static const double {P}_F0 = {f0};
static const double {P}_IN_LO = {in_lo}; /* identified input range: the forward step clips to it */
static const double {P}_IN_HI = {in_hi};
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
    return {p}_force(x, v, {p}_dmin({p}_dmax(input, {P}_IN_LO), {P}_IN_HI));
}}

double {p}_inverse_step({p}_state *s, double x, double v, double F_desired, double *F_out)
{{
    double a = {P}_LO, b = {P}_HI, prev = s->prev, best;
    if (s->k >= 1) {{
        a = {p}_dmax(a, prev - {P}_RATE_STEP);
        b = {p}_dmin(b, prev + {P}_RATE_STEP);
    }}
    best = {p}_solve(x, v, F_desired, a, b, prev);
    s->prev = best;
    s->k += 1;
    if (F_out) *F_out = {p}_force(x, v, best);
    return best;
}}
"""

_STATIC_DFORCE = r"""
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

_SOLVE = (
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

_BISECT = r"""
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


_RUN = r"""
void {p}_run(long n, const double *x, const double *v, const double *input, double *F)
{{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < n; ++k) F[k] = {p}_step(&s, x[k], v[k], input[k]);
}}
"""

_INVERSE_RUN = (
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


def _solver(fmt: dict[str, Any], args: str, call: str, f_expr: str, df_expr: str) -> str:
    """Slope, bisection and solver functions of the regularised inverse for one force expression."""
    sub = dict(
        fmt,
        args=args,
        call=call,
        F_r=f_expr.format(r="r"),
        dF_r=df_expr.format(r="r"),
        F_best=f_expr.format(r="best"),
    )
    slope, solve = _SOLVE.split("/* minimiser", 1)
    return slope.format(**sub) + _BISECT.format(**sub) + ("/* minimiser" + solve).format(**sub)


def _settings(
    model: Any,
    reg: float | None,
    v_ref: float,
    rate: float | None,
    dt: float,
    dt_known: bool = True,
) -> tuple[float, float]:
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


def c_source(
    model: Any,
    name: str = "mrd_damper",
    *,
    reg: float | None = None,
    v_ref: float = 0.3,
    rate: float | None = None,
    n_grid: int = 32,
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
        ``dt`` (without ``dt``: ``DEFAULT_REG_FRACTION * force_authority(model, v_ref)``, the 200 Hz
        value); fixed into the code.
    v_ref : float
        Velocity setting the default ``reg`` [m/s].
    rate : float, optional
        Input rate bound of the inverse [input unit/s]; needs the sample time (``dt`` or an LPV
        model's rate).
    n_grid : int
        Search grid of the inverse.
    dt : float, optional
        Sample time [s] of a static map's inverse (only used with ``rate``).
    """
    from mrdamper.models.lpv import TransferFunctionModel
    from mrdamper.models.protocols import InvertibleModel

    kind = getattr(model, "kind", type(model).__name__)
    if kind not in C_KINDS:
        raise DataValidationError("model", f"C export handles kinds {list(C_KINDS)}, got {kind!r}")
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise DataValidationError("name", f"expected a C identifier, got {name!r}")
    if isinstance(n_grid, bool) or not isinstance(n_grid, int) or n_grid < 1:
        raise DataValidationError("n_grid", f"expected a positive integer, got {n_grid!r}")
    if not isinstance(model, TransferFunctionModel) and getattr(model, "eta", None) is not None:
        raise DataValidationError(
            "model",
            f"C export of a static {kind} map with a drive lag (eta = {model.eta:g} 1/s) is not "
            "implemented; export the map without the lag or an LPV model with its drive lag",
        )
    warn_if_unstable(model)
    p, P = name, name.upper()
    lo, hi = model_input_limits(model)
    has_inverse = isinstance(model, InvertibleModel)
    is_lpv = isinstance(model, TransferFunctionModel)
    if is_lpv:
        step_dt = 1.0 / model.fs
    else:
        step_dt = 1.0 if dt is None else float(dt)
        if rate is not None and dt is None:
            raise DataValidationError(
                "dt", "a rate bound on a static map's inverse needs the sample time dt [s]"
            )
    dt_known = is_lpv or dt is not None
    lam, rate_step = (
        _settings(model, reg, v_ref, rate, step_dt, dt_known) if has_inverse else (0.0, math.inf)
    )
    fmt: dict[str, Any] = {
        "p": p,
        "P": P,
        "lo": _f(lo),
        "hi": _f(hi),
        "in_lo": _f(model.input_range[0]),
        "in_hi": _f(model.input_range[1]),
        "lam2": _f(lam * lam),
        "rate_step": _f(rate_step),
        "n_grid": n_grid,
        "n_bisect": K._N_BISECT,
    }
    if is_lpv:
        mode, gm, gc, mu_h, mu_l = lpv_law_arrays(model)
        blend, stroke = lpv_hysteresis(model)
        lag = -1.0 if model.eta is None else float(np.exp(-model.eta / model.fs))
        fmt.update(
            n_m=model.n_m,
            n_p=model.n_rho + 1,
            n_d=gm.shape[1],
            alpha=_arr2(model.alpha),
            beta=_arr2(model.beta),
            offset=_f(model.offset),
            lag=_f(lag),
            mode=mode,
            gm=_arr2(gm),
            gc=_arr2(gc),
            mu_high=_arr1(mu_h),
            mu_low=_arr1(mu_l),
            blend=_f(blend),
            stroke=_f(stroke),
            dt=_f(1.0 / model.fs),
            horizon=horizon_samples(model.eta, 1.0 / model.fs),
            golden=_f(K.GOLDEN),
            n_golden=K.N_GOLDEN,
        )
        state = (
            f"typedef struct {{\n    double y[{model.n_m}]; "
            "/* past outputs y[k-1-j] (force minus offset) [N] */\n"
            f"    double u[{model.n_m}]; /* past LPV inputs u[k-1-j] [m/s] */\n"
            "    double rho; /* scheduling value of the last sample */\n"
            "    double w; "
            "/* forward: input of the last sample; inverse: last command (drive lag) */\n"
            "    double z; /* Dahl state of the hysteretic input [-] */\n"
            "    double v_prev; /* velocity of the last sample [m/s] */\n"
            f"    long k; /* samples taken */\n}} {p}_state;\n"
        )
        body = _LPV.format(**fmt)
        if has_inverse:
            body += _LPV_DPOLY.format(**fmt) + _solver(
                fmt,
                "const double *cf",
                "cf",
                f"{p}_poly(cf, {P}_N_P, {{r}})",
                f"{p}_dpoly(cf, {P}_N_P, {{r}})",
            )
            body += _LPV_HORIZON.format(**fmt) + _LPV_INVERSE.format(**fmt)
        rate_note = f"{model.fs!r} Hz (one call per model sample)"
    else:
        comp, power, theta, f0 = static_map_arrays(model)
        fmt.update(
            n_theta=theta.size,
            comp="{" + ", ".join(str(int(c)) for c in comp) + "}",
            power="{" + ", ".join(str(int(q)) for q in power) + "}",
            theta=_arr1(theta),
            f0=_f(f0),
        )
        state = (
            f"typedef struct {{\n    double prev; /* input of the last inverse sample */\n"
            f"    long k; /* inverse samples taken */\n}} {p}_state;\n"
        )
        head, inv = _STATIC.split("double {p}_inverse_step", 1)
        body = head.format(**fmt) + _STATIC_DFORCE.format(**fmt)
        body += _solver(
            fmt, "double x, double v", "x, v", f"{p}_force(x, v, {{r}})", f"{p}_dforce(x, v, {{r}})"
        )
        body += ("double {p}_inverse_step" + inv).format(**fmt)
        rate_note = "any (static map)"
    unit = "A" if model.input == "i" else "V"
    guard = f"{P}_H"
    protos = [
        f"void {p}_init({p}_state *s);",
        f"double {p}_step({p}_state *s, double x, double v, double input);",
        f"void {p}_run(long n, const double *x, const double *v, const double *input, double *F);",
    ]
    if has_inverse:
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
    header = (
        f"/* {name}.h: {kind} damper model exported by mrdamper (C99, no dynamic allocation).\n"
        f" * Units: x [m], v [m/s], input [{unit}] clipped to "
        f"[{model.input_range[0]!r}, {model.input_range[1]!r}] "
        f"(inverse: [{lo!r}, {hi!r}]), force [N].\n * Sample rate: {rate_note}.\n"
        f" * Inverse: regularisation weight {lam!r} N/{unit}, grid {n_grid}. */\n"
        f"#ifndef {guard}\n#define {guard}\n\n{state}\n"
        + "\n".join(protos)
        + f"\n\n#endif /* {guard} */\n"
    )
    src = f'/* {name}.c: see {name}.h. */\n#include <math.h>\n#include "{name}.h"\n'
    src += _COMMON.format(**fmt) + (_INV_CONST.format(**fmt) if has_inverse else "") + body
    src += _RUN.format(**fmt)
    if has_inverse:
        src += _INVERSE_RUN.format(**fmt)
    return header, src


def export_c(
    model: Any, out_dir: str | Path, *, name: str = "mrd_damper", force: bool = False, **kwargs: Any
) -> tuple[Path, Path]:
    """Write ``<out_dir>/<name>.h`` and ``<name>.c`` atomically (see :func:`c_source` for the
    options).

    Parameters
    ----------
    model : FittedModel
        LPV, LTI, SP-1..SP-4 or Bingham model.
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
    h_path, c_path = check_writable(d / f"{name}.h", force), check_writable(d / f"{name}.c", force)
    d.mkdir(parents=True, exist_ok=True)
    return atomic_write_text(h_path, header, force=force), atomic_write_text(
        c_path, src, force=force
    )
