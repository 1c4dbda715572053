"""The Dahl family under its earlier import path.

It lives in :mod:`mrdamper.models.hysteresis.dahl`.
"""

from __future__ import annotations

from mrdamper.models.hysteresis.dahl import *
