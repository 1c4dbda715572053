"""The Bouc-Wen family under its earlier import path.

It lives in :mod:`mrdamper.models.hysteresis.boucwen`.
"""

from __future__ import annotations

from mrdamper.models.hysteresis.boucwen import *
