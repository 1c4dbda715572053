"""A toy plug-in family installed for the tests (``tests/plugin_site`` on the path): its entry
point (``mrd_viscous-0.1.dist-info/entry_points.txt``) names this row, which imports nothing
heavy; the classes are in :mod:`mrd_viscous.family`."""

from mrdamper.kinds import KindSpec

KIND = KindSpec(
    "viscous",
    "mrd_viscous.family",
    "ViscousEstimator",
    "ViscousModel",
    "linear viscous damper (toy plug-in)",
    "0.4",
    default=False,
)
