"""The P-15 family under its earlier import path; it lives in :mod:`mrdamper.models.p15`."""

from __future__ import annotations

from mrdamper.models.p15 import *
