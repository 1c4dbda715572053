"""Excitation signals for MR-damper tests, all on the uniform grid ``t = k / fs``.

Random generators take an explicit ``seed`` (int or :class:`numpy.random.SeedSequence`); the
same seed always gives the same bytes.

* :func:`prbs` / :func:`mls`: maximum-length pseudo-random binary sequences.
* :func:`aprbs`: amplitude-modulated PRBS (random level per PRBS run).
* :func:`icps`: pseudo-random current with an increased clock period (the project's reading of
  the paper's "ICPS", ``paper/READING-NOTES.md`` item 8).
* :func:`stepped_current`: SC, stepped increments of constant current.
* :func:`constant`, :func:`sine`, :func:`ramped_sine`: deterministic basics.
* :func:`road_profile`, :func:`long_road_profile`: ISO 8608 road displacement scaled to the stroke.
"""

from mrdamper.signals.aprbs import aprbs
from mrdamper.signals.basic import constant, n_samples, ramped_sine, sine, time_grid
from mrdamper.signals.icps import icps
from mrdamper.signals.prbs import PRIMITIVE_TAPS, mls, prbs
from mrdamper.signals.road import (
    ISO_8608_CLASSES,
    band_variance,
    long_road_profile,
    road_profile,
    spatial_psd,
    temporal_psd,
)
from mrdamper.signals.stepped import stepped_current

__all__ = [
    "ISO_8608_CLASSES",
    "PRIMITIVE_TAPS",
    "aprbs",
    "band_variance",
    "constant",
    "icps",
    "long_road_profile",
    "mls",
    "n_samples",
    "prbs",
    "ramped_sine",
    "road_profile",
    "sine",
    "spatial_psd",
    "stepped_current",
    "temporal_psd",
    "time_grid",
]
