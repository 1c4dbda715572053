"""C rendering of the polynomial NARX model's per-sample step, from its form alone.

The form (:class:`mrdamper.models.narx.kernels.NARXForm`: base variables, monomials,
coefficients, signal scales, the ``tanh`` velocity, the divergence bound, the largest lag and the
initial force) is all the C code needs. The state is the Python step's: the samples seen so far
(capped at the largest lag ``p``) and the last ``p`` scaled values of every signal row; the first
``p`` forces are the initial condition. The model runs at its own rate: one call of
``<name>_step`` per model sample. The input is not clipped; no inverse.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mrdamper.control.export.c_render._common import (
    STEP_WRAPPER,
    Context,
    Rendered,
    arr1,
    lit,
    step_state,
)
from mrdamper.errors import DataValidationError
from mrdamper.models import kernels as NK
from mrdamper.models.base import FittedModel

__all__ = ["render_narx", "render_narx_form"]

_NARX = r"""
#define {P}_NB {nb} /* base variables */
#define {P}_NT {nt} /* monomials */
#define {P}_ND {nd} /* factors per monomial */
#define {P}_LAGS {lags} /* largest lag p [samples] */
static const int {P}_BASE[{P}_NB][2] = {base}; /* signal row, lag */
static const int {P}_SLOTS[{P}_NT][{P}_ND] = {slots}; /* base variables of each monomial, -1 none */
static const double {P}_THETA[{P}_NT] = {theta};
static const double {P}_SCALES[5] = {scales}; /* F [N], x [m], v [m/s], input, tanh(v / v0) */
static const double {P}_V0 = {v0}; /* velocity of the tanh feature [m/s] */
static const double {P}_BOUND = {bound}; /* largest accepted scaled |F| */
static const double {P}_F_INITIAL = {f_initial}; /* force of the first p samples [N] */
static const double {P}_DT = {dt}; /* model sample time [s] */
static const double {P}_X_LO = {x_lo}; /* regressors clipped to the training envelope [m] */
static const double {P}_X_HI = {x_hi};
static const double {P}_V_LIMIT = {v_limit}; /* [m/s] */

/* scaled value of signal row r (not the force) at the present sample (x, v clipped) */
static double {p}_present(int r, double x, double v, double e)
{{
    double val, vc = v < -{P}_V_LIMIT ? -{P}_V_LIMIT : (v > {P}_V_LIMIT ? {P}_V_LIMIT : v);
    if (r == 1) val = x < {P}_X_LO ? {P}_X_LO : (x > {P}_X_HI ? {P}_X_HI : x);
    else if (r == 2) val = vc;
    else if (r == 3) val = e;
    else val = tanh(vc / {P}_V0);
    return val / {P}_SCALES[r];
}}

/* scaled force at the present sample (the initial condition for the first p samples) */
static double {p}_scaled(const double *s, double x, double v, double e)
{{
    double bv[{P}_NB], acc = 0.0;
    int b, t, q;
    if (s[0] < {P}_LAGS) return {P}_F_INITIAL / {P}_SCALES[0];
    for (b = 0; b < {P}_NB; ++b) {{
        int r = {P}_BASE[b][0], lag = {P}_BASE[b][1];
        bv[b] = lag == 0 ? {p}_present(r, x, v, e) : s[1 + r * {P}_LAGS + lag - 1];
    }}
    for (t = 0; t < {P}_NT; ++t) {{
        double val = 1.0;
        for (q = 0; q < {P}_ND; ++q) {{
            int j = {P}_SLOTS[t][q];
            if (j >= 0) val *= bv[j];
        }}
        acc += {P}_THETA[t] * val;
    }}
    return acc;
}}

void {p}_step_init(double *s, double x0, double v0, double e0)
{{
    int j;
    (void)x0;
    (void)v0;
    (void)e0;
    for (j = 0; j < {P}_STEP_N; ++j) s[j] = 0.0;
}}

double {p}_step_force(const double *s, double x, double v, double e)
{{
    return {p}_scaled(s, x, v, e) * {P}_SCALES[0];
}}

int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, double v1,
                     double e1, double dt)
{{
    double f = {p}_scaled(s, x0, v0, e0);
    int r, lag;
    (void)x1;
    (void)v1;
    (void)e1;
    (void)dt;
    if (!isfinite(f) || fabs(f) > {P}_BOUND) return 1;
    for (r = 0; r < 5; ++r) {{
        int a = 1 + r * {P}_LAGS;
        for (lag = {P}_LAGS - 1; lag > 0; --lag) s[a + lag] = s[a + lag - 1];
        if ({P}_LAGS > 0) s[a] = r == 0 ? f : {p}_present(r, x0, v0, e0);
    }}
    s[0] = s[0] + 1.0 <= (double){P}_LAGS ? s[0] + 1.0 : (double){P}_LAGS;
    return 0;
}}
"""


def _ints(a: Any) -> str:
    return "{" + ", ".join("{" + ", ".join(str(int(v)) for v in row) + "}" for row in a) + "}"


def render_narx_form(form: NK.NARXForm, dt: float, ctx: Context) -> Rendered:
    """C of the NARX step given by ``form`` at its sample time ``dt`` [s]."""
    base, slots = np.asarray(form.base), np.asarray(form.slots)
    if base.shape[0] == 0 or slots.size == 0:
        raise DataValidationError("model", "a NARX model without base variables has no C step")
    p, P = ctx.p, ctx.P
    n = 1 + 5 * int(form.p)
    fmt = {
        "p": p,
        "P": P,
        "nb": base.shape[0],
        "nt": slots.shape[0],
        "nd": slots.shape[1],
        "lags": int(form.p),
        "base": _ints(base),
        "slots": _ints(slots),
        "theta": arr1(form.theta),
        "scales": arr1(form.scales),
        "v0": lit(form.v0),
        "bound": lit(form.bound),
        "f_initial": lit(form.f_initial),
        "dt": lit(dt),
        "x_lo": lit(form.x_lo),
        "x_hi": lit(form.x_hi),
        "v_limit": lit(form.v_limit),
    }
    body = _NARX.format(**fmt) + STEP_WRAPPER.format(p=p, P=P, n=n)
    return Rendered(
        step_state(p, n, "samples seen, then the last p scaled samples of every signal row"),
        body,
        False,
        [
            "The input is not clipped; no inverse.",
            f"Sample rate: {1.0 / dt!r} Hz (one call per model sample).",
        ],
        sample_time=dt,
        step_n=n,
        step_dt=True,
    )


def render_narx(model: FittedModel, ctx: Context) -> Rendered:
    """C of ``model.step()`` at the model's rate (the first ``p`` forces are 0 N)."""
    step = model.step()
    assert step.dt is not None
    return render_narx_form(step.form, float(step.dt), ctx)
