"""The SP-1 ... SP-4 family under its earlier import path; it lives in :mod:`mrdamper.models.sp`."""

from __future__ import annotations

from mrdamper.models.sp import *
