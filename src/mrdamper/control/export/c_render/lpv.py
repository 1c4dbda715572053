"""C rendering of the LPV and LTI models (input-output recursion of eq. 9) and their inverse.

The zone laws, the optional drive lag and, for the hysteretic input, the Dahl state ``z`` carried
in the state struct and stepped with the model's exact update from the velocity passed to each
call, from rest ``z = 0``. An LTI model has no inverse: its force does not depend on the present
input. The arithmetic follows the compiled Python kernels operation by operation.
"""

from __future__ import annotations

import numpy as np

from mrdamper.control.export.c_render._common import (
    COMMON,
    INTERVAL_C,
    INV_CONST,
    Context,
    Rendered,
    arr1,
    arr2,
    fmt_base,
    input_note,
    inverse_settings,
    lit,
    solver,
)
from mrdamper.control.inverse import _inverse_kernels as K
from mrdamper.control.inverse.current import horizon_samples
from mrdamper.models.kernels import LPV_N_HEAD as N_HEAD
from mrdamper.models.lpv import TransferFunctionModel

__all__ = ["render_lpv"]

LPV = (
    r"""
#define {P}_N_M {n_m}
#define {P}_N_P {n_p}
#define {P}_N_D {n_d}
static const double {P}_ALPHA[{P}_N_M][{P}_N_P] = {alpha};
static const double {P}_BETA[{P}_N_M][{P}_N_P] = {beta};
static const double {P}_OFFSET = {offset};
static const double {P}_STIFFNESS = {stiffness}; /* parallel stiffness k_x [N/m]: F += k_x x */
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
    double w = input; /* as given, as the model's step */
    double r = w, F;
    if ({P}_LAG >= 0.0 && s->k > 0) r = {P}_LAG * s->rho + (1.0 - {P}_LAG) * s->w;
    s->w = w;
    {p}_advance(s, v);
    {p}_coefficients(s, cf);
    F = {p}_poly(cf, {P}_N_P, r);
    {p}_commit(s, F, v, r);
    return F + {P}_STIFFNESS * x;
}}
"""
)

LPV_STEP = (
    r"""
static const double {P}_BOUND = {bound}; /* largest |y| [N] of the step (divergence) */
static const double {P}_ETA = {eta}; /* drive-lag rate [1/s]; negative: no lag */

/* The model's per-sample step (mrdamper.models.lpv.step) on the state
   s = (rho, z, y[k-N_M] .. y[k-1], u[k-N_M] .. u[k-1]), oldest first; the input as given. */
static double {p}_sforce(const double *s, double e, double *r)
{{
    double cf[{P}_N_P];
    int q, j;
    for (q = 0; q < {P}_N_P; ++q) {{
        double acc = 0.0;
        for (j = 0; j < {P}_N_M; ++j)"""
    r""" acc += {P}_BETA[j][q] * s[1 + 2 * {P}_N_M - j] - {P}_ALPHA[j][q] * s[1 + {P}_N_M - j];
        cf[q] = acc;
    }}
    cf[0] += {P}_OFFSET;
    *r = {P}_ETA >= 0.0 ? s[0] : e;
    return {p}_poly(cf, {P}_N_P, *r);
}}

void {p}_step_init(double *s, double x0, double v0, double e0)
{{
    int j;
    (void)x0;
    (void)v0;
    for (j = 0; j < {P}_STEP_N; ++j) s[j] = 0.0;
    s[0] = e0;
}}

double {p}_step_force(const double *s, double x, double v, double e)
{{
    double r;
    (void)v;
    return {p}_sforce(s, e, &r) + {P}_STIFFNESS * x;
}}

int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, double v1,"""
    r""" double e1, double dt)
{{
    double r, F = {p}_sforce(s, e0, &r), y = F - {P}_OFFSET, u;
    int j;
    (void)x0;
    (void)x1;
    (void)e1;
    if (!(fabs(y) <= {P}_BOUND)) return 1;
    u = {p}_u_of(v0, r, s[1]);
    for (j = 0; j < {P}_N_M - 1; ++j) {{
        s[2 + j] = s[3 + j];
        s[2 + {P}_N_M + j] = s[3 + {P}_N_M + j];
    }}
    s[1 + {P}_N_M] = y;
    s[1 + 2 * {P}_N_M] = u;
    if ({P}_ETA >= 0.0) {{
        double E = exp(-{P}_ETA * dt);
        s[0] = E * r + (1.0 - E) * e0;
    }}
    if ({P}_BLEND != 0.0) {{
        double dx = 0.5 * (v0 + v1) * dt;
        if (dx > 0.0) s[1] = 1.0 + (s[1] - 1.0) * exp(-dx / {P}_STROKE);
        else if (dx < 0.0) s[1] = -1.0 + (s[1] + 1.0) * exp(dx / {P}_STROKE);
    }}
    return 0;
}}
"""
)

LPV_DPOLY = r"""
static const double {P}_HI = {hi}; /* upper input limit of the inverse */
static double {p}_dpoly(const double *c, int n, double r)
{{
    double acc = 0.0;
    int q;
    for (q = n - 1; q > 0; --q) acc = acc * r + q * c[q];
    return acc;
}}
"""

LPV_HORIZON = (
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

LPV_INVERSE = (
    r"""double {p}_inverse_step({p}_state *s, double x, double v, double F_desired, double *F_out)
{{
    double cf[{P}_N_P];
    double a = {P}_LO, b = {P}_HI, prev = s->rho, hold, r, F;
    F_desired -= {P}_STIFFNESS * x; /* the stiffness force is not the input's to give */
    {p}_advance(s, v);
    {p}_coefficients(s, cf);
    {p}_allowed(s->k, {P}_LAG, s->rho, prev, &a, &b);
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
    if (F_out) *F_out = F + {P}_STIFFNESS * x;
    return r;
}}
"""
)


def render_lpv(model: TransferFunctionModel, ctx: Context) -> Rendered:
    """C of an LPV or LTI model at its own rate ``fs``, with the inverse where the model has one."""
    from mrdamper.models.protocols import InvertibleModel

    p, P = ctx.p, ctx.P
    dt = 1.0 / model.fs
    form = model.step().form
    has_inverse = isinstance(model, InvertibleModel)
    lam, rate_step = (
        inverse_settings(model, ctx.reg, ctx.v_ref, ctx.rate, dt) if has_inverse else (0.0, np.inf)
    )
    fmt = fmt_base(model, ctx, lam, rate_step)
    n_m = form.alpha.shape[0]
    lag = -1.0 if form.eta < 0.0 else float(np.exp(-form.eta / model.fs))
    fmt.update(
        n_m=n_m,
        n_p=form.alpha.shape[1],
        n_d=form.gamma_m.shape[1],
        step_n=N_HEAD + 2 * n_m,
        alpha=arr2(form.alpha),
        beta=arr2(form.beta),
        offset=lit(form.offset),
        stiffness=lit(form.stiffness),
        bound=lit(form.bound),
        eta=lit(form.eta),
        lag=lit(lag),
        mode=form.mode,
        gm=arr2(form.gamma_m),
        gc=arr2(form.gamma_c),
        mu_high=arr1(form.mu_high),
        mu_low=arr1(form.mu_low),
        blend=lit(form.blend),
        stroke=lit(form.stroke),
        dt=lit(dt),
        horizon=horizon_samples(model.eta, dt),
        golden=lit(K.GOLDEN),
        n_golden=K.N_GOLDEN,
    )
    state = (
        f"typedef struct {{\n    double y[{n_m}]; "
        "/* past outputs y[k-1-j] (force minus offset) [N] */\n"
        f"    double u[{n_m}]; /* past LPV inputs u[k-1-j] [m/s] */\n"
        "    double rho; /* scheduling value of the last sample */\n"
        "    double w; "
        "/* forward: input of the last sample; inverse: last command (drive lag) */\n"
        "    double z; /* Dahl state of the hysteretic input [-] */\n"
        "    double v_prev; /* velocity of the last sample [m/s] */\n"
        f"    long k; /* samples taken */\n}} {p}_state;\n"
    )
    body = COMMON.format(**fmt) + LPV.format(**fmt) + LPV_STEP.format(**fmt)
    if has_inverse:
        body = (
            COMMON.format(**fmt)
            + INV_CONST.format(**fmt)
            + LPV.format(**fmt)
            + LPV_STEP.format(**fmt)
        )
        body += LPV_DPOLY.format(**fmt)
        body += solver(
            fmt,
            "const double *cf",
            "cf",
            f"{p}_poly(cf, {P}_N_P, {{r}})",
            f"{p}_dpoly(cf, {P}_N_P, {{r}})",
        )
        body += LPV_HORIZON.format(**fmt) + INTERVAL_C.format(**fmt) + LPV_INVERSE.format(**fmt)
    return Rendered(
        state,
        body,
        has_inverse,
        [input_note(model), f"Sample rate: {model.fs!r} Hz (one call per model sample)."]
        + ([f"Inverse: regularisation weight {lam!r}, grid {ctx.n_grid}."] if has_inverse else []),
        sample_time=dt,
        step_n=N_HEAD + 2 * n_m,
        step_dt=True,
    )
