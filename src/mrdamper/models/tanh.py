"""The tanh family under its earlier import path.

It lives in :mod:`mrdamper.models.hysteresis.tanh`.
"""

from __future__ import annotations

from mrdamper.models.hysteresis.tanh import *
