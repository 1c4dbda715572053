"""The inverse wing of :mod:`mrdamper.control`: the current for a desired force.

``current`` (the record inverse, its saturation and drive-lag lead command), ``step_inverse`` (the
numerical inverse of any model's step), ``inverse_check`` (the inverse on a record with a known
input), the compiled kernels (``_inverse_kernels``), what the inverse reads from a model
(``_inverse_setup``) and the forms the compiled controller reads (``_forms``). The names of
``current`` are importable from here."""

from mrdamper.control.inverse.current import (
    DEFAULT_REG_FRACTION,
    DEFAULT_REG_TIME,
    InverseResult,
    default_reg,
    driver_command,
    force_authority,
    horizon_samples,
    inverse_current,
    lpv_hysteresis,
    lpv_inverse_fields,
    lpv_law_arrays,
    model_input_limits,
    static_map_arrays,
)

__all__ = [
    "DEFAULT_REG_FRACTION",
    "DEFAULT_REG_TIME",
    "InverseResult",
    "default_reg",
    "driver_command",
    "force_authority",
    "horizon_samples",
    "inverse_current",
    "lpv_hysteresis",
    "lpv_inverse_fields",
    "lpv_law_arrays",
    "model_input_limits",
    "static_map_arrays",
]
