"""C rendering of the one-state hysteresis families' per-sample step (``tanh``, ``boucwen``,
``dahl``, ``lugre``), from their form alone.

The form (:class:`mrdamper.models.kernels.HysteresisForm`: the family code, the
parameter vector in the family's ``PARAM_NAMES`` order and the largest RK4 sub-step ``max_h``) and
the fixed sample time ``dt`` given at export are all the C code needs. Only the chosen family's
state derivative and force are rendered; the interval is the shared one of
:func:`~mrdamper.models.hysteresis.kernels.step_advance`: ``ceil(dt / max_h)`` classical RK4
sub-steps on ``z`` with the velocity linear in between, then (with a drive lag ``eta > 0``) as
many on ``u`` with the input linear in between, or ``u = e1`` without a lag, the same operations
in the same order. ``<name>_step_force`` reads ``u = s[1]`` with a lag and the present input
without one. The rest state is ``(z, u) = (0, e0)``. After a failed interval (non-finite state,
``|z|`` beyond its bound) the step returns NaN from then on and ``status`` keeps the code 1. The
input is not clipped (the Python step does not clip either).

The rendering also has the inverse (``<name>_inverse_step``), the closed form of
:func:`~mrdamper.models.hysteresis.kernels.inverse_run` one sample a call: the state is advanced
from the previous call's motion to this one's with the previous input held, the input ``u`` the
laws read, in its admissible interval (the identified range, or with a drive lag what a command in
it reaches from the previous ``u``; within the rate bound of the previous one), minimising
``(F(u) - F_desired)^2 + reg^2 (u - u_prev)^2`` is taken from the force at both ends of the
interval (the force is affine in ``u``), and ``*F_out`` gets the force with it. It returns ``u``:
without a lag the input, with one the lagged input (the driver command is its lead filter,
:func:`mrdamper.control.driver_command`, as for the LPV export). The regularisation weight is
fixed into the code (default :func:`~mrdamper.control.inverse.current.default_reg` at ``v_ref`` and
``dt``).
"""

from __future__ import annotations

import math

from mrdamper.control.export.c_render._common import (
    COMMON,
    INTERVAL_C,
    STEP_WRAPPER,
    Context,
    Rendered,
    fmt_base,
    inverse_settings,
    lit,
    sampled_step,
    step_state,
)
from mrdamper.models import kernels as HK
from mrdamper.models.base import FittedModel

__all__ = ["render_hysteresis", "render_hysteresis_form"]

_PARAM = r"""
static const double {P}_{name} = {value}; /* {doc} */"""

_HEAD = r"""
static const double {P}_MAX_H = {max_h}; /* largest RK4 sub-step [s] */
static const double {P}_DT = {dt}; /* sample time [s]: one call per sample */
static const double {P}_Z_LIMIT = {z_limit}; /* |z| beyond this counts as divergence */
"""

_SIGN = r"""
static double {p}_sign(double a) {{ return a > 0.0 ? 1.0 : (a < 0.0 ? -1.0 : 0.0); }}
"""

#: dz/dt of each family with a state (tanh has none), as ``_zdot``.
_ZDOT = {
    "boucwen": r"""
/* dz/dt at velocity v (Bouc-Wen); |z|**n by exp/log unless n == 2, as the Python kernel */
static double {p}_zdot(double v, double z)
{{
    double az = fabs(z);
    double zn = az > 0.0 ? ({P}_N == 2.0 ? az * az : exp(({P}_N - 1.0) * log(az)) * az) : 0.0;
    return -{P}_GAMMA * fabs(v) * {p}_sign(z) * zn - {P}_BETA * v * zn + {P}_A * v;
}}
""",
    "dahl": r"""
/* dz/dt at velocity v (modified Dahl) */
static double {p}_zdot(double v, double z)
{{
    return {P}_SIGMA * (v - fabs(v) * z);
}}
""",
    "lugre": r"""
/* dz/dt at velocity v (LuGre bristle) */
static double {p}_zdot(double v, double z)
{{
    return v - {P}_SIGMA_0 * {P}_A0 * fabs(v) * z;
}}
""",
}

#: The force of each family at (x, v, z, u), as ``_force``.
_FORCE = {
    "tanh": r"""
static double {p}_force(double x, double v, double z, double u)
{{
    double c = {P}_CA + {P}_CB * u, al = {P}_ALPHA_A + {P}_ALPHA_B * u;
    (void)z;
    return c * v + {P}_K * x + al * tanh({P}_BETA * v + {P}_DELTA * {p}_sign(x)) + {P}_F0;
}}
""",
    "boucwen": r"""
static double {p}_force(double x, double v, double z, double u)
{{
    return ({P}_C0A + {P}_C0B * u) * v + {P}_K0 * x + ({P}_ALPHA_A + {P}_ALPHA_B * u) * z"""
    r""" + {P}_F0;
}}
""",
    "dahl": r"""
static double {p}_force(double x, double v, double z, double u)
{{
    return ({P}_C0A + {P}_C0B * u) * v + {P}_K0 * x + ({P}_FDA + {P}_FDB * u) * z + {P}_F0;
}}
""",
    "lugre": r"""
static double {p}_force(double x, double v, double z, double u)
{{
    double zd = {p}_zdot(v, z);
    (void)x;
    return ({P}_SIGMA_A + {P}_SIGMA_0 * u) * z + {P}_SIGMA_1 * zd"""
    r""" + ({P}_SIGMA_2 + {P}_SIGMA_B * u) * v + {P}_F0;
}}
""",
}

#: RK4 sub-steps of z over the interval (families with a state), as ``_interval``.
_Z_LOOP = r"""
    {{
        double dv = v1 - v0;
        for (j = 0; j < nsub; ++j) {{
            double t0 = (double)j * hf, va = v0 + t0 * dv, vm = va + 0.5 * hf * dv;
            double vb = va + hf * dv, k1, k2, k3, k4;
            k1 = {p}_zdot(va, z);
            k2 = {p}_zdot(vm, z + 0.5 * h * k1);
            k3 = {p}_zdot(vm, z + 0.5 * h * k2);
            k4 = {p}_zdot(vb, z + h * k3);
            z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }}
    }}"""

_STEP = r"""
/* step_force: the force at the state s = (z, u) and the present motion */
double {p}_step_force(const double *s, double x, double v, double e)
{{
    double u = {P}_ETA > 0.0 ? s[1] : e;
    return {p}_force(x, v, s[0], u);
}}

/* one interval of dt [s], inputs linear between its ends, nsub RK4 sub-steps; returns a status */
static int {p}_interval(double *s, double v0, double e0, double v1, double e1, double dt,
                        long nsub)
{{
    double z = s[0], u = s[1], hf = 1.0 / (double)nsub, h = dt * hf, de = e1 - e0;
    long j;
{z_loop}
    if ({P}_ETA > 0.0) {{
        /* the lag does not depend on z: its own RK4 sub-steps on the linear input */
        for (j = 0; j < nsub; ++j) {{
            double t0 = (double)j * hf, ea = e0 + t0 * de, em = ea + 0.5 * hf * de;
            double eb = ea + hf * de, g1, g2, g3, g4;
            g1 = -{P}_ETA * (u - ea);
            g2 = -{P}_ETA * (u + 0.5 * h * g1 - em);
            g3 = -{P}_ETA * (u + 0.5 * h * g2 - em);
            g4 = -{P}_ETA * (u + h * g3 - eb);
            u += h / 6.0 * (g1 + 2.0 * g2 + 2.0 * g3 + g4);
        }}
    }} else {{
        u = e1;
    }}
    s[0] = z;
    s[1] = u;
    if (!(isfinite(z) && isfinite(u)) || fabs(z) > {P}_Z_LIMIT) return 1;
    return 0;
}}

/* step_advance: sub-steps from the interval and the largest sub-step */
int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, double v1,
                     double e1, double dt)
{{
    double m = ceil(dt / {P}_MAX_H * (1.0 - 1e-12));
    long nsub = m > 1.0 ? (long)m : 1;
    (void)x0;
    (void)x1;
    return {p}_interval(s, v0, e0, v1, e1, dt, nsub);
}}

/* the rest state at the first sample: (z, u) = (0, e) */
void {p}_step_init(double *s, double x0, double v0, double e0)
{{
    (void)x0;
    (void)v0;
    s[0] = 0.0;
    s[1] = e0;
}}
"""


_INVERSE = r"""
static const double {P}_LO = {lo}; /* inverse input range */
static const double {P}_HI = {hi};
static const double {P}_LAM2 = {lam2}; /* squared regularisation weight [N^2 per input unit^2] */
static const double {P}_RATE_STEP = {rate_step}; /* largest input change per sample */
static const double {P}_LAG = {lag}; /* exp(-eta dt) of the drive lag, or -1: none */

/* force at the state s with the input the laws read set to u (with a drive lag: the lagged one) */
static double {p}_force_at(const double *s, double x, double v, double u)
{{
    double t[2];
    t[0] = s[0];
    t[1] = u;
    return {p}_step_force(t, x, v, u);
}}

/* minimiser of (F(u) - target)^2 + lam^2 (u - prev)^2 on [a, b]: F is affine in u at the state */
static double {p}_inverse_solve(const double *s, double x, double v, double target, double a,
                                double b, double prev)
{{
    double f_a = {p}_force_at(s, x, v, a), f_b, g, den, e;
    if (!(b > a)) return a;
    f_b = {p}_force_at(s, x, v, b);
    g = (f_b - f_a) / (b - a);
    den = g * g + {P}_LAM2;
    e = den == 0.0 ? a : a + (g * (target - f_a) + {P}_LAM2 * (prev - a)) / den;
    return {p}_dmin({p}_dmax(e, a), b);
}}

double {p}_inverse_step({p}_state *s, double x, double v, double F_desired, double *F_out)
{{
    double a = {P}_LO, b = {P}_HI, e;
    if (s->status == 0 && s->k > 0) {{
        s->status = {p}_step_advance(s->s, s->x, s->v, s->e, x, v, s->e, {P}_DT);
        {p}_allowed(s->k, {P}_LAG, s->e, s->e, &a, &b);
    }}
    if (s->status != 0) {{
        if (F_out) *F_out = NAN;
        return NAN;
    }}
    e = {p}_inverse_solve(s->s, x, v, F_desired, a, b, s->k > 0 ? s->e : {P}_LO);
    s->s[1] = e;
    s->x = x;
    s->v = v;
    s->e = e;
    s->k += 1;
    if (F_out) *F_out = {p}_step_force(s->s, x, v, e);
    return e;
}}
"""


def _inverse_note(inverse: dict[str, str] | None, lagged: bool) -> str:
    if inverse is None:
        return "."
    note = (
        f"; inverse on [{inverse['lo_text']}, {inverse['hi_text']}], regularisation "
        f"weight {inverse['lam_text']} (closed form per sample)."
    )
    if lagged:
        note += (
            " With the drive lag it returns the lagged input; the driver command is its lead "
            "filter (mrdamper.control.driver_command)."
        )
    return note


def _family(code: int) -> str:
    return next(name for name, c in HK.HYSTERESIS_FAMILIES.items() if c == code)


def render_hysteresis_form(
    form: HK.HysteresisForm,
    dt: float,
    ctx: Context,
    inverse: dict[str, str] | None = None,
) -> Rendered:
    """C of the hysteresis step given by ``form``, called once per sample of ``dt`` [s].

    Parameters
    ----------
    form : HysteresisForm
        Family code, parameter vector (the family's ``PARAM_NAMES`` order, SI) and the largest
        RK4 sub-step [s].
    dt : float
        Sample time [s] of the C step.
    ctx : Context
        Export options (the name; the inverse's settings come in ``inverse``).
    inverse : dict, optional
        Format fields of the inverse (``lo``, ``hi``, ``lam2``, ``rate_step``, ``lag`` as C
        literals); None: no inverse.
    """
    p, P = ctx.p, ctx.P
    family = _family(int(form.family))
    names = HK.HYSTERESIS_PARAM_NAMES[family]
    consts = "".join(
        _PARAM.format(P=P, name=n.upper(), value=lit(v), doc=n) for n, v in zip(names, form.p)
    )
    fmt = {"p": p, "P": P}
    pieces = [
        COMMON.format(**fmt) if inverse is not None else "",
        consts,
        "\n",
        _HEAD.format(P=P, max_h=lit(form.max_h), dt=lit(dt), z_limit=lit(HK.HYSTERESIS_Z_LIMIT)),
    ]
    if family in ("tanh", "boucwen"):
        pieces.append(_SIGN.format(**fmt))
    if family in _ZDOT:
        pieces.append(_ZDOT[family].format(**fmt))
    pieces.append(_FORCE[family].format(**fmt))
    z_loop = (
        _Z_LOOP.format(**fmt)
        if family in _ZDOT
        else "    /* no z: a static map of u */\n    (void)v0;\n    (void)v1;"
    )
    pieces.append(_STEP.format(z_loop=z_loop, **fmt))
    pieces.append(STEP_WRAPPER.format(p=p, P=P, n=2))
    if inverse is not None:
        inv_c = _INVERSE.format(**fmt, **inverse)
        at = inv_c.index(f"double {p}_inverse_step(")
        pieces.append(inv_c[:at] + INTERVAL_C.format(**fmt) + inv_c[at:])
    lag = "with a drive lag" if form.p[0] > 0.0 else "no drive lag"  # p[0]: eta
    return Rendered(
        step_state(p, 2, f"evolutionary variable z, lagged input u ({family}, {lag})"),
        "".join(pieces),
        inverse is not None,
        [
            "The input is not clipped" + _inverse_note(inverse, form.p[0] > 0.0),
            f"Sample rate: {1.0 / dt!r} Hz (one call per sample of {dt!r} s).",
            f"RK4 sub-steps of at most {form.max_h!r} s.",
        ],
        sample_time=dt,
        step_n=2,
    )


def render_hysteresis(model: FittedModel, ctx: Context) -> Rendered:
    """C of the model's step at ``ctx.dt`` (:func:`sampled_step`; the sample time is required)
    and of its inverse (``ctx.reg`` or the default weight at ``ctx.v_ref`` and ``dt``;
    ``ctx.rate``)."""
    step, dt = sampled_step(model, ctx)
    lam, rate_step = inverse_settings(model, ctx.reg, ctx.v_ref, ctx.rate, dt)
    base = fmt_base(model, ctx, lam, rate_step)
    lo, hi = model.input_range
    eta = float(step.form.p[0])  # the step form's drive-lag rate [1/s] (0: none)
    inverse = {
        "lo": base["lo"],
        "hi": base["hi"],
        "lam2": base["lam2"],
        "rate_step": base["rate_step"],
        "lag": lit(math.exp(-eta * dt) if eta > 0.0 else -1.0),
        "lo_text": repr(float(lo)),
        "hi_text": repr(float(hi)),
        "lam_text": repr(lam),
    }
    return render_hysteresis_form(step.form, dt, ctx, inverse)
