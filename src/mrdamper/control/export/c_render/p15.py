"""C rendering of the P-15 model's per-sample step, from its form alone.

The form (:class:`mrdamper.models.p15.kernels.P15Form`: the coefficient matrix of ``w_1 .. w_5``
in its basis, the offset, the largest integration step, the force bound and the drive lag) is all
the C code needs. ``<name>_step_advance`` integrates an interval as ``step_advance`` does:
``ceil(dt / max_step)`` steps of the two-stage L-stable SDIRK scheme, each implicit stage solved
by the same safeguarded Newton iteration, the same operations in the same order.
``<name>_step_init`` sets the rest state ``(F_rest, 0, e0)``: ``F_rest`` is the real root of
``F - f0 - w1 v0 - w4 F^3 - w5 F^5`` with ``g'(F) > 0`` closest to zero (else the real root
closest to zero), as :func:`mrdamper.models.p15.fit.rest_state`; C finds it by bisection on each
interval where the polynomial is monotone (between its critical points, a quadratic in ``F^2``).
The input is not clipped; no inverse (the force is a state: it does not depend on the present
input).
"""

from __future__ import annotations

from mrdamper.control.export.c_render._common import (
    COMMON,
    STEP_WRAPPER,
    Context,
    Rendered,
    arr2,
    lit,
    sampled_step,
    step_state,
)
from mrdamper.models import kernels as PK
from mrdamper.models.base import FittedModel

__all__ = ["render_p15", "render_p15_form"]

_P15 = (
    r"""
static const double {P}_C[5][3] = {C}; /* coefficients of w1 .. w5 in the basis */
static const double {P}_F0 = {f0}; /* force offset [N] */
static const int {P}_BASIS = {basis}; /* 0: monomials in the input, 1: Bernstein on [LO, HI] */
static const double {P}_LO = {lo};
static const double {P}_HI = {hi};
static const double {P}_MAX_STEP = {max_step}; /* largest integration step [s] */
static const double {P}_BOUND = {bound}; /* largest accepted |F| [N] */
static const double {P}_ETA = {eta}; /* drive-lag rate [1/s]; negative: no lag */
static const double {P}_GAMMA = {gamma}; /* 1 - 1/sqrt(2) */
static const double {P}_MAX_SUBSTEPS = {max_substeps};
static const double {P}_DT = {dt}; /* sample time [s] of {p}_step: one call per sample */

/* the coefficients w1 .. w5 at the input ii */
static void {p}_coefs(double ii, double *w)
{{
    double phi[3];
    int j;
    if ({P}_BASIS == 0) {{
        phi[0] = 1.0;
        phi[1] = ii;
        phi[2] = ii * ii;
    }} else {{
        double s = {p}_dmin(1.0, {p}_dmax(0.0, (ii - {P}_LO) / ({P}_HI - {P}_LO)));
        phi[0] = (1.0 - s) * (1.0 - s);
        phi[1] = 2.0 * s * (1.0 - s);
        phi[2] = s * s;
    }}
    for (j = 0; j < 5; ++j)
        w[j] = {P}_C[j][0] * phi[0] + {P}_C[j][1] * phi[1] + {P}_C[j][2] * phi[2];
}}

static double {p}_accel(double F, double G, double vv, const double *w)
{{
    double F2 = F * F;
    return (F - {P}_F0 - w[0] * vv - w[1] * G - w[3] * F2 * F - w[4] * F2 * F2 * F) / w[2];
}}

/* root G of G - B - hg a(A + hg G, G) = 0 (safeguarded Newton); *ok 0 when not found */
static double {p}_stage(double A, double B, double hg, double vv, const double *w, double G0,
                        int *ok)
{{
    double G = G0, lo_b = -HUGE_VAL, hi_b = HUGE_VAL, scale = fabs(B) + fabs(G0) + 1e-300;
    int it;
    for (it = 0; it < 200; ++it) {{
        double F = A + hg * G, F2 = F * F, t3 = w[3] * F2 * F, t5 = w[4] * F2 * F2 * F;
        double a = (F - {P}_F0 - w[0] * vv - w[1] * G - t3 - t5) / w[2];
        double psi = G - B - hg * a, noise, aF, aG, dpsi, step, Gn;
        if (!isfinite(psi)) {{
            *ok = 0;
            return G;
        }}
        noise = 1e-14 * (fabs(G) + fabs(B) + hg * (fabs(F) + fabs({P}_F0) + fabs(w[0] * vv)"""
    r""" + fabs(w[1] * G) + fabs(t3) + fabs(t5)) / fabs(w[2])) + 1e-300;
        if (fabs(psi) <= noise) {{
            *ok = 1;
            return G;
        }}
        aF = (1.0 - 3.0 * w[3] * F2 - 5.0 * w[4] * F2 * F2) / w[2];
        aG = -w[1] / w[2];
        dpsi = 1.0 - hg * (hg * aF + aG);
        if (psi > 0.0) hi_b = {p}_dmin(hi_b, G);
        else lo_b = {p}_dmax(lo_b, G);
        step = dpsi > 0.0 ? psi / dpsi : NAN;
        Gn = G - step;
        if (!(isfinite(Gn) && Gn > lo_b && Gn < hi_b)) {{
            if (isfinite(lo_b) && isfinite(hi_b)) Gn = 0.5 * (lo_b + hi_b);
            else if (isfinite(lo_b)) Gn = lo_b + 2.0 * (fabs(lo_b - G0) + scale);
            else Gn = hi_b - 2.0 * (fabs(hi_b - G0) + scale);
        }}
        if (fabs(Gn - G) <= 1e-14 * (fabs(Gn) + scale)"""
    r""" || hi_b - lo_b <= 1e-13 * (fabs(G) + scale)) {{
            *ok = 1;
            return Gn;
        }}
        G = Gn;
    }}
    *ok = 0;
    return G;
}}

/* integration step q of n_sub (length h) from (F, G); v and the input linear over the interval */
static int {p}_substep(double *yF, double *yG, double va, double vb, double ia, double ib, long q,
                       long n_sub, double h)
{{
    double g = {P}_GAMMA, hg = h * g, ta = ((double)q + g) / (double)n_sub;
    double tb = ((double)q + 1.0) / (double)n_sub, w1[5], w2[5];
    double v1 = va + (vb - va) * ta, v2 = va + (vb - va) * tb, G1, F1, a1, A2, B2, G2;
    int ok1, ok2;
    {p}_coefs(ia + (ib - ia) * ta, w1);
    {p}_coefs(ia + (ib - ia) * tb, w2);
    G1 = {p}_stage(*yF, *yG, hg, v1, w1, *yG, &ok1);
    F1 = *yF + hg * G1;
    a1 = {p}_accel(F1, G1, v1, w1);
    A2 = *yF + h * (1.0 - g) * G1;
    B2 = *yG + h * (1.0 - g) * a1;
    G2 = {p}_stage(A2, B2, hg, v2, w2, G1, &ok2);
    *yF = A2 + hg * G2;
    *yG = G2;
    return ok1 && ok2;
}}

int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, double v1,
                     double e1, double dt)
{{
    double ia, ib, h, yF = s[0], yG = s[1], m;
    long n_sub = 1, q;
    int ok = 1;
    (void)x0;
    (void)x1;
    if ({P}_ETA >= 0.0) {{
        double E = exp(-{P}_ETA * dt);
        ia = s[2];
        ib = E * ia + (1.0 - E) * e0;
    }} else {{
        ia = e0;
        ib = e1;
    }}
    if (isfinite({P}_MAX_STEP)) {{
        m = {p}_dmin({P}_MAX_SUBSTEPS, {p}_dmax(1.0, ceil(dt / {P}_MAX_STEP - 1e-12)));
        n_sub = (long)m;
    }}
    h = dt / (double)n_sub;
    for (q = 0; q < n_sub; ++q) {{
        ok = {p}_substep(&yF, &yG, v0, v1, ia, ib, q, n_sub, h);
        if (!ok) break;
    }}
    s[0] = yF;
    s[1] = yG;
    s[2] = ib;
    if (!ok || !(isfinite(yF) && isfinite(yG)) || fabs(yF) > {P}_BOUND) return 1;
    return 0;
}}

double {p}_step_force(const double *s, double x, double v, double e)
{{
    (void)x;
    (void)v;
    (void)e;
    return s[0];
}}

/* h(F) = F - u - w4 F^3 - w5 F^5 and its slope g'(F) */
static double {p}_rest_h(double F, double u, const double *w)
{{
    return F - u - w[3] * F * F * F - w[4] * F * F * F * F * F;
}}

static double {p}_rest_gp(double F, const double *w)
{{
    return 1.0 - 3.0 * w[3] * F * F - 5.0 * w[4] * F * F * F * F;
}}

/* force at rest (F' = F'' = 0) for the coefficients w and the velocity v0 */
static double {p}_rest(const double *w, double v0)
{{
    double u = {P}_F0 + w[0] * v0, R, br[6], roots[5], best = 0.0;
    int nb = 0, nr = 0, j, found = 0;
    if (w[4] != 0.0) {{
        double a = -5.0 * w[4], b = -3.0 * w[3], disc = b * b - 4.0 * a, t[2];
        R = 1.0 + {p}_dmax(fabs(w[3] / w[4]), {p}_dmax(fabs(1.0 / w[4]), fabs(u / w[4])));
        br[nb++] = -R;
        if (disc >= 0.0) {{
            t[0] = (-b - sqrt(disc)) / (2.0 * a);
            t[1] = (-b + sqrt(disc)) / (2.0 * a);
            if (t[0] > t[1]) {{
                double tt = t[0];
                t[0] = t[1];
                t[1] = tt;
            }}
            for (j = 1; j >= 0; --j)
                if (t[j] > 0.0 && sqrt(t[j]) < R) br[nb++] = -sqrt(t[j]);
            for (j = 0; j < 2; ++j)
                if (t[j] > 0.0 && sqrt(t[j]) < R) br[nb++] = sqrt(t[j]);
        }}
        br[nb++] = R;
    }} else if (w[3] != 0.0) {{
        R = 1.0 + {p}_dmax(fabs(1.0 / w[3]), fabs(u / w[3]));
        br[nb++] = -R;
        if (w[3] > 0.0 && sqrt(1.0 / (3.0 * w[3])) < R) {{
            br[nb++] = -sqrt(1.0 / (3.0 * w[3]));
            br[nb++] = sqrt(1.0 / (3.0 * w[3]));
        }}
        br[nb++] = R;
    }} else {{
        return u;
    }}
    for (j = 0; j + 1 < nb; ++j) {{ /* h is monotone on [br[j], br[j + 1]]: bisect a sign change */
        double a = br[j], b = br[j + 1], ha = {p}_rest_h(a, u, w), hb = {p}_rest_h(b, u, w);
        int it;
        if (ha == 0.0) {{
            roots[nr++] = a;
            continue;
        }}
        if (hb == 0.0 || (ha < 0.0) == (hb < 0.0)) continue;
        for (it = 0; it < 2200; ++it) {{
            double m = 0.5 * (a + b), hm;
            if (m <= a || m >= b) break;
            hm = {p}_rest_h(m, u, w);
            if (hm == 0.0) {{
                a = b = m;
                break;
            }}
            if ((hm < 0.0) == (ha < 0.0)) a = m;
            else b = m;
        }}
        roots[nr++] = fabs({p}_rest_h(a, u, w)) <= fabs({p}_rest_h(b, u, w)) ? a : b;
    }}
    if (nb > 0 && {p}_rest_h(br[nb - 1], u, w) == 0.0) roots[nr++] = br[nb - 1];
    for (j = 0; j < nr; ++j) /* the root with g' > 0 closest to zero */
        if ({p}_rest_gp(roots[j], w) > 0.0 && (!found || fabs(roots[j]) < fabs(best))) {{
            best = roots[j];
            found = 1;
        }}
    for (j = 0; j < nr && !found; ++j) /* else the root closest to zero */
        if (j == 0 || fabs(roots[j]) < fabs(best)) best = roots[j];
    return nr > 0 ? best : u;
}}

void {p}_step_init(double *s, double x0, double v0, double e0)
{{
    double w[5];
    (void)x0;
    {p}_coefs(e0, w);
    s[0] = {p}_rest(w, v0);
    s[1] = 0.0;
    s[2] = e0;
}}
"""
)


def render_p15_form(form: PK.P15Form, dt: float, ctx: Context) -> Rendered:
    """C of the P-15 step given by ``form``; ``<name>_step`` is called once per sample of ``dt``
    [s] (the step functions take any interval)."""
    p, P = ctx.p, ctx.P
    fmt = {
        "p": p,
        "P": P,
        "C": arr2(form.C),
        "f0": lit(form.f0),
        "basis": int(form.basis),
        "lo": lit(form.lo),
        "hi": lit(form.hi),
        "max_step": lit(form.max_step),
        "bound": lit(form.bound),
        "eta": lit(form.eta),
        "gamma": lit(PK.P15_GAMMA),
        "max_substeps": lit(float(PK.P15_MAX_SUBSTEPS)),
        "dt": lit(dt),
    }
    body = COMMON.format(**fmt) + _P15.format(**fmt) + STEP_WRAPPER.format(p=p, P=P, n=3)
    return Rendered(
        step_state(p, 3, "force F [N], its rate G [N/s], the (lagged) input"),
        body,
        False,
        [
            "The input is not clipped; no inverse (the force is a state of the model).",
            f"Sample rate of {p}_step: {1.0 / dt!r} Hz (one call per sample of {dt!r} s).",
            f"Integration steps of at most {form.max_step!r} s.",
        ],
        sample_time=dt,
        step_n=3,
    )


def render_p15(model: FittedModel, ctx: Context) -> Rendered:
    """C of the model's step at ``ctx.dt`` [s] (:func:`sampled_step`), the sample time of
    ``<name>_step``."""
    step, dt = sampled_step(model, ctx)
    return render_p15_form(step.form, dt, ctx)
