"""C rendering of the Spencer model's per-sample step, from its form alone.

The form (:class:`mrdamper.models.spencer.kernels.SpencerForm`: the parameter vector and the
largest RK4 sub-step ``max_h``) and the fixed sample time ``dt`` given at export are all the C code
needs. ``<name>_step`` does what :func:`mrdamper.models.step.run` does for one sample: the first
call sets the rest state ``(y, z, u) = (x, 0, e)``, every later call integrates the interval from
the previous sample's inputs to this one's (inputs linear in between, ``ceil(dt / max_h)``
classical RK4 sub-steps, the same operations in the same order as ``step_advance``), then returns
the force ``step_force``. After a failed interval (non-finite or unbounded state, non-positive
damping) the step returns NaN from then on and ``status`` keeps the code (1 diverged, 2 invalid
damping). The input is not clipped (the Python step does not clip either).
"""

from __future__ import annotations

from mrdamper.control.export.c_render._common import (
    STEP_WRAPPER,
    Context,
    Rendered,
    lit,
    sampled_step,
    step_state,
)
from mrdamper.models import kernels as SK
from mrdamper.models.base import FittedModel

__all__ = ["render_spencer", "render_spencer_form"]

_PARAMS = r"""
static const double {P}_{name} = {value}; /* {doc} */"""

_SPENCER = r"""
static const double {P}_MAX_H = {max_h}; /* largest RK4 sub-step [s] */
static const double {P}_DT = {dt}; /* sample time [s]: one call per sample */
static const double {P}_Z_LIMIT = {z_limit};
static const double {P}_Y_LIMIT = {y_limit};

static double {p}_sign(double a) {{ return a > 0.0 ? 1.0 : (a < 0.0 ? -1.0 : 0.0); }}

/* |z|**n (exp/log unless n == 2, as the Python kernel) */
static double {p}_zn(double z, double n)
{{
    double az = fabs(z);
    if (az > 0.0) {{
        if (n == 2.0) return az * az;
        return exp((n - 1.0) * log(az)) * az;
    }}
    return 0.0;
}}

/* state derivative (dy, dz, du); returns the damping c0 + c1 */
static double {p}_rhs(double x, double xd, double e, double y, double z, double u, double *d)
{{
    double c0 = {P}_C0A + {P}_C0B * u, c1 = {P}_C1A + {P}_C1B * u;
    double al = {P}_ALPHA_A + {P}_ALPHA_B * u, C = c0 + c1;
    double yd = (al * z + c0 * xd + {P}_K0 * (x - y)) / C, w = xd - yd;
    double zn = {p}_zn(z, {P}_N);
    d[0] = yd;
    d[1] = -{P}_GAMMA * fabs(w) * {p}_sign(z) * zn - {P}_BETA * w * zn + {P}_A * w;
    d[2] = -{P}_ETA * (u - e);
    return C;
}}

/* step_force: the force at the state s = (y, z, u) and the present motion */
double {p}_step_force(const double *s, double x, double xd, double e)
{{
    double c0 = {P}_C0A + {P}_C0B * s[2], c1 = {P}_C1A + {P}_C1B * s[2];
    double al = {P}_ALPHA_A + {P}_ALPHA_B * s[2];
    double yd = (al * s[1] + c0 * xd + {P}_K0 * (x - s[0])) / (c0 + c1);
    (void)e;
    return c1 * yd + {P}_K1 * (x - {P}_X0) + {P}_F0;
}}

/* one interval of dt [s], inputs linear between its ends, nsub RK4 sub-steps; returns a status */
static int {p}_interval(double *s, double x0, double v0, double e0, double x1, double v1,
                        double e1, double dt, long nsub)
{{
    double y = s[0], z = s[1], u = s[2], hf = 1.0 / (double)nsub, h = dt * hf;
    double dx = x1 - x0, dv = v1 - v0, de = e1 - e0;
    double a1[3], a2[3], a3[3], a4[3];
    long j;
    for (j = 0; j < nsub; ++j) {{
        double t0 = (double)j * hf, tm = t0 + 0.5 * hf, t1 = t0 + hf;
        double xa = x0 + t0 * dx, va = v0 + t0 * dv, ea = e0 + t0 * de;
        double xm = x0 + tm * dx, vm = v0 + tm * dv, em = e0 + tm * de;
        double xb = x0 + t1 * dx, vb = v0 + t1 * dv, eb = e0 + t1 * de;
        double C = {p}_rhs(xa, va, ea, y, z, u, a1);
        if (!(C > 0.0)) return 2;
        {p}_rhs(xm, vm, em, y + 0.5 * h * a1[0], z + 0.5 * h * a1[1], u + 0.5 * h * a1[2], a2);
        {p}_rhs(xm, vm, em, y + 0.5 * h * a2[0], z + 0.5 * h * a2[1], u + 0.5 * h * a2[2], a3);
        {p}_rhs(xb, vb, eb, y + h * a3[0], z + h * a3[1], u + h * a3[2], a4);
        y += h / 6.0 * (a1[0] + 2.0 * a2[0] + 2.0 * a3[0] + a4[0]);
        z += h / 6.0 * (a1[1] + 2.0 * a2[1] + 2.0 * a3[1] + a4[1]);
        u += h / 6.0 * (a1[2] + 2.0 * a2[2] + 2.0 * a3[2] + a4[2]);
    }}
    s[0] = y;
    s[1] = z;
    s[2] = u;
    if (!(isfinite(y) && isfinite(z) && isfinite(u))) return 1;
    if (fabs(z) > {P}_Z_LIMIT || fabs(y - x1) > {P}_Y_LIMIT) return 1;
    return 0;
}}

/* step_advance: sub-steps from the interval and the largest sub-step */
int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, double v1,
                     double e1, double dt)
{{
    double m = ceil(dt / {P}_MAX_H * (1.0 - 1e-12));
    long nsub = m > 1.0 ? (long)m : 1;
    return {p}_interval(s, x0, v0, e0, x1, v1, e1, dt, nsub);
}}

/* the rest state at the first sample: (y, z, u) = (x, 0, e) */
void {p}_step_init(double *s, double x0, double v0, double e0)
{{
    (void)v0;
    s[0] = x0;
    s[1] = 0.0;
    s[2] = e0;
}}
"""


def render_spencer_form(form: SK.SpencerForm, dt: float, ctx: Context) -> Rendered:
    """C of the Spencer step given by ``form``, called once per sample of ``dt`` [s].

    Parameters
    ----------
    form : SpencerForm
        Parameter vector (:data:`~mrdamper.models.spencer.kernels.PARAM_NAMES` order, SI) and
        the largest RK4 sub-step [s].
    dt : float
        Sample time [s] of the C step.
    ctx : Context
        Export options (only the name is used: the Spencer export has no inverse).
    """
    p, P = ctx.p, ctx.P
    consts = "".join(
        _PARAMS.format(P=P, name=n.upper(), value=lit(v), doc=n)
        for n, v in zip(SK.SPENCER_PARAM_NAMES, form.p)
    )
    body = (
        consts
        + "\n"
        + _SPENCER.format(
            p=p,
            P=P,
            max_h=lit(form.max_h),
            dt=lit(dt),
            z_limit=lit(SK.SPENCER_Z_LIMIT),
            y_limit=lit(SK.SPENCER_Y_LIMIT),
        )
        + STEP_WRAPPER.format(p=p, P=P, n=3)
    )
    state = step_state(p, 3, "internal displacement y [m], z, filtered input u")
    return Rendered(
        state,
        body,
        False,
        [
            "The input is not clipped; no inverse.",
            f"Sample rate: {1.0 / dt!r} Hz (one call per sample of {dt!r} s).",
            f"RK4 sub-steps of at most {form.max_h!r} s.",
        ],
        sample_time=dt,
        step_n=3,
    )


def render_spencer(model: FittedModel, ctx: Context) -> Rendered:
    """C of the model's step at ``ctx.dt`` (:func:`sampled_step`; the sample time is
    required)."""
    step, dt = sampled_step(model, ctx)
    return render_spencer_form(step.form, dt, ctx)
