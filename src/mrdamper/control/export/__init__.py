"""The export wing of :mod:`mrdamper.control`: what leaves the library for a controller.

``statespace`` (realisation, frozen-rho systems, python-control), ``matrices`` (the LPV / LTI
matrices to .mat or JSON), ``c_export`` with its per-family ``c_render`` (C99 step and inverse),
``c_inverse`` (the compiled C inverse called from the loop), ``fmu`` (FMI 2.0 co-simulation units)
and ``fmu_plant`` (an exported FMU as the loop's damper). The names of ``matrices`` are importable
from here."""

from mrdamper.control.export.matrices import (
    EXPORT_FILE,
    EXPORT_SCHEMA,
    export_lpv,
    lpv_export_data,
    warn_if_unstable,
)

__all__ = ["EXPORT_FILE", "EXPORT_SCHEMA", "export_lpv", "lpv_export_data", "warn_if_unstable"]
