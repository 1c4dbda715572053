"""The LuGre family under its earlier import path.

It lives in :mod:`mrdamper.models.hysteresis.lugre`.
"""

from __future__ import annotations

from mrdamper.models.hysteresis.lugre import *
