"""The inverse's allowed interval, written once: the inputs a controller may choose at one sample.

Every inverse confines the scheduling value ``rho[k]`` (the input, or the input through a drive
lag) to

* the input limits ``[lo, hi]``;
* with a drive lag ``rho[k] = lag rho[k-1] + (1 - lag) w[k-1]`` (``lag = exp(-eta dt) >= 0``;
  negative: none), what a command ``w`` in ``[lo, hi]`` reaches from ``rho[k-1]``; the lag starts
  at rest, so ``rho[1] = rho[0]``;
* the rate bound ``|rho[k] - prev| <= rate_step`` around the previous input ``prev`` (when the
  window misses the interval, the nearest point of the interval to ``prev``).

The regularisation pulls towards the *hold* (:func:`held_input`): the previous input, or with a
drive lag the value ``rho`` takes with the previous command held (the lag's own motion is free);
:func:`lag_command` recovers that command from the chosen ``rho``.

Used by the record inverses and the control samples of :mod:`mrdamper.control` (through
:mod:`mrdamper.models.kernels`) and by the hysteresis families' own inverse; the C export writes
the same rule once in C99 (``INTERVAL_C`` of the C renderers).
"""

from __future__ import annotations

from numba import njit

__all__ = ["allowed_interval", "held_input", "lag_command"]


@njit(cache=True)
def allowed_interval(  # pragma: no cover - numba
    k: int, lo: float, hi: float, lag: float, rho_prev: float, prev: float, rate_step: float
) -> tuple[float, float]:
    """The admissible ``[a, b]`` of ``rho[k]`` (see the module docstring).

    Parameters
    ----------
    k : int
        Sample index (sample 0 is free within ``[lo, hi]``).
    lo, hi : float
        Input limits [input unit].
    lag : float
        ``exp(-eta dt)`` of the drive lag [-], or negative for none.
    rho_prev : float
        ``rho[k-1]`` [input unit].
    prev : float
        The previous input the rate bound is measured from [input unit].
    rate_step : float
        Largest change per sample [input unit] (``inf``: none).

    Returns
    -------
    a, b : float
        Bounds of the interval [input unit].
    """
    a, b = lo, hi
    if lag >= 0.0 and k >= 1:
        if k == 1:  # the lag starts at rest
            a = b = rho_prev
        else:  # what a command in [lo, hi] reaches
            a = max(lag * rho_prev + (1.0 - lag) * lo, lo)
            b = min(lag * rho_prev + (1.0 - lag) * hi, hi)
    if k >= 1:
        a = max(a, prev - rate_step)
        b = min(b, prev + rate_step)
        if b < a:
            a = b = min(max(prev, a), b)
    return a, b


@njit(cache=True)
def held_input(  # pragma: no cover - numba
    k: int, lag: float, prev: float, w_prev: float, a: float, b: float
) -> float:
    """The value the regularisation pulls towards at sample ``k``: ``prev``, or with a drive lag
    (from sample 2) ``rho`` with the previous command ``w_prev`` held, within ``[a, b]``."""
    if lag >= 0.0 and k >= 2:
        return min(max(lag * prev + (1.0 - lag) * w_prev, a), b)
    return prev


@njit(cache=True)
def lag_command(  # pragma: no cover - numba
    k: int, lag: float, r: float, prev: float, lo: float, hi: float, w_prev: float
) -> float:
    """The command of the previous sample that makes ``rho[k] = r`` from ``rho[k-1] = prev``
    (within ``[lo, hi]``; ``r`` itself at samples 0 and 1); ``w_prev`` unchanged without a lag."""
    if lag >= 0.0:
        return r if k <= 1 else min(max((r - lag * prev) / (1.0 - lag), lo), hi)
    return w_prev
