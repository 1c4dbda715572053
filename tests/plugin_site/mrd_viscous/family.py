"""F = (c0 + c1 i) v + f0, identified by linear least squares, with its step and its C."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numba import njit

from mrdamper.control.export.c_render import Context, Rendered
from mrdamper.models import Estimator, FittedModel, Identified, RangePolicy, TrainingData
from mrdamper.models.step import STATUS_OK, Step


class ViscousForm(NamedTuple):
    c0: float  # [N s/m]
    c1: float  # [N s/(m A)]
    f0: float  # [N]


@njit(cache=True)
def viscous_force(form: Any, s: Any, x: float, v: float, e: float) -> float:
    return (form.c0 + form.c1 * e) * v + form.f0


@njit(cache=True)
def viscous_advance(
    form: Any, s: Any, x0: Any, v0: Any, e0: Any, x1: Any, v1: Any, e1: Any, dt: Any
) -> int:
    return STATUS_OK


C_BODY = r"""
void {p}_step_init(double *s, double x0, double v0, double e0)
{{
    (void)x0; (void)v0; (void)e0;
    s[0] = 0.0;
}}

double {p}_step_force(const double *s, double x, double v, double e)
{{
    (void)s; (void)x;
    return ({c0} + {c1} * e) * v + {f0};
}}

int {p}_step_advance(double *s, double x0, double v0, double e0, double x1, double v1,
                     double e1, double dt)
{{
    (void)s; (void)x0; (void)v0; (void)e0; (void)x1; (void)v1; (void)e1; (void)dt;
    return 0;
}}

void {p}_init({p}_state *s) {{ s->s[0] = 0.0; }}

double {p}_step({p}_state *s, double x, double v, double input)
{{
    return {p}_step_force(s->s, x, v, input);
}}
"""


@dataclass(frozen=True, kw_only=True)
class ViscousModel(FittedModel):
    """F = (c0 + c1 i) v + f0."""

    kind: ClassVar[str] = "viscous"
    c0: float = 0.0
    c1: float = 0.0
    f0: float = 0.0

    def predict(self, experiment: Any) -> np.ndarray:
        i = self.electrical_input(experiment)
        return (self.c0 + self.c1 * i) * experiment.v + self.f0

    def step(self, *, dt: float = 1e-3, vmax: float = 1.5) -> Step:
        form = ViscousForm(self.c0, self.c1, self.f0)
        return Step(self.kind, form, viscous_force, viscous_advance, lambda x, v, e: np.zeros(1))

    def render_c(self, ctx: Context) -> Rendered:
        consts = {k: float(getattr(self, k)).hex() for k in ("c0", "c1", "f0")}
        state = f"typedef struct {{\n    double s[1];\n}} {ctx.name}_state;\n"
        return Rendered(state, C_BODY.format(p=ctx.name, **consts), False, step_n=1)


@dataclass
class ViscousEstimator(Estimator):
    """Least squares of F on [v, i v, 1]."""

    kind: ClassVar[str] = "viscous"
    model_class: ClassVar[type[FittedModel]] = ViscousModel
    input: str = "i"
    range_policy: RangePolicy = "error"

    def _identify(self, data: TrainingData, **options: Any) -> Identified:
        v = np.concatenate([e.v for e in data.records])
        i = np.concatenate(data.electrical)
        F = np.concatenate([e.F for e in data.records])
        columns = [v, np.ones_like(v)] if data.single else [v, i * v, np.ones_like(v)]
        coef = np.linalg.lstsq(np.column_stack(columns), F, rcond=None)[0]
        c0, c1, f0 = (coef[0], 0.0, coef[1]) if data.single else coef
        return Identified(
            parameters={"c0": float(c0), "c1": float(c1), "f0": float(f0)},
            provenance={"method": "linear least squares", "n_samples": int(F.size)},
        )
