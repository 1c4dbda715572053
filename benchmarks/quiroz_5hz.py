"""Where the LPV error on Quiroz 2 mm / 5 Hz comes from, record by record.

Scenario (a) of ``generalisation.py``: the default LPV model fitted on the Quiroz conditions up
to 3 Hz and scored on the 5 mm / 4 Hz and 2 mm / 5 Hz records. For every test record it prints
the ESR (eq. 24) of the whole record and of its steady cycles (the ramps up and down left out:
the samples within one period of where the displacement's running peak first and last reaches
97 % of its largest value), and the floor left by the measurement itself: the ESR of the best
periodic fit of the steady force (30 harmonics of the displacement's own frequency, fitted by
least squares). Then, for every condition at the lowest current, the mean measured and predicted
``|F|`` where ``|v|`` lies within 10 % of 0.05 m/s, split by accelerating and decelerating
samples: the force a model has to reproduce at one velocity across strokes and frequencies.

Run::

    python benchmarks/quiroz_5hz.py
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.ndimage import maximum_filter1d
from scipy.optimize import minimize_scalar

sys.path.insert(0, str(Path(__file__).resolve().parent))
import generalisation as G

from mrdamper.metrics import esr

#: Harmonics of the periodic fit that gives the measurement floor [-].
HARMONICS = 30
#: The velocity [m/s] at which forces are compared across conditions, and the band around it [-].
PROBE_V, PROBE_BAND = 0.05, 0.1


def steady(x: np.ndarray, fs: float, frequency: float) -> slice:
    """The steady cycles of a ramped sine record (see the module docstring)."""
    period = round(fs / frequency)
    reach = maximum_filter1d(np.abs(x), period) > 0.97 * np.abs(x).max()
    idx = np.flatnonzero(reach)
    return slice(int(idx[0]) + period, int(idx[-1]) - period)


def _harmonic_residual(t: np.ndarray, y: np.ndarray, f: float, n: int) -> np.ndarray:
    cols = [np.ones_like(t)]
    for h in range(1, n + 1):
        cols += [np.sin(2 * np.pi * h * f * t), np.cos(2 * np.pi * h * f * t)]
    basis = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return np.asarray(y - basis @ coef)


def periodic_floor(t: np.ndarray, x: np.ndarray, F: np.ndarray, nominal: float) -> float:
    """ESR of the best periodic fit of ``F`` at the frequency that fits ``x`` best [-]."""
    fit = minimize_scalar(
        lambda f: float(np.mean(_harmonic_residual(t, x, f, 3) ** 2)),
        bounds=(0.97 * nominal, 1.03 * nominal),
        method="bounded",
    )
    r = _harmonic_residual(t, F, float(fit.x), HARMONICS)
    return float(np.mean(r**2) / np.var(F))


def main(argv: list[str] | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.parse_args(argv)
    t0 = time.perf_counter()
    sc = G.scenario_quiroz_frequency(quick=True)  # the Quiroz records are the same either way
    model, _, err = G.fit_model("lpv", {}, sc.train)
    if model is None:
        raise SystemExit(f"lpv: {err}")
    tests = [(condition, e) for condition, records in sc.tests.items() for e in records]
    lowest = min(e.metadata["current"] for e in sc.train)
    probed = [e for e in sc.train if e.metadata["current"] == lowest]
    everything = probed + [e for _, e in tests]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        predicted = [np.asarray(model.predict(e)) for e in everything]  # each record once
    rows = []
    for (condition, e), Fh in zip(tests, predicted[len(probed) :]):
        t, x, F = np.asarray(e.t), np.asarray(e.x), np.asarray(e.F)
        s = steady(x, e.fs, e.metadata["frequency"])
        rows.append(
            {
                "condition": condition,
                "current_A": e.metadata["current"],
                "esr": esr(F, Fh),
                "esr_steady": esr(F[s], Fh[s]),
                "floor_steady": periodic_floor(t[s], x[s], F[s], e.metadata["frequency"]),
            }
        )
    per_record = pd.DataFrame(rows)
    trained = {e.metadata["condition"] for e in sc.train}
    probe = []
    for e, Fh in zip(everything, predicted):
        if e.metadata["current"] != lowest:
            continue
        v, F = np.asarray(e.v), np.asarray(e.F)
        near = np.abs(np.abs(v) - PROBE_V) <= PROBE_BAND * PROBE_V
        accelerating = v * np.gradient(v, e.t) > 0
        if not near.any():
            continue
        row = {"condition": e.metadata["condition"], "trained": e.metadata["condition"] in trained}
        for side, mask in (("acc", near & accelerating), ("dec", near & ~accelerating)):
            row[f"measured_{side}_N"] = float(np.mean(np.abs(F[mask])))
            row[f"model_{side}_N"] = float(np.mean(np.abs(Fh[mask])))
        probe.append(row)
    forces = pd.DataFrame(probe)
    pd.set_option("display.width", 200)
    print(f"LPV ({model.provenance.get('hysteretic_note', '')})\n")
    print(per_record.to_string(index=False, float_format=lambda z: f"{z:.4g}"))
    means = per_record.groupby("condition")[["esr", "esr_steady", "floor_steady"]].mean()
    print("\nmean per condition\n" + means.to_string(float_format=lambda z: f"{z:.4g}"))
    print(f"\n|F| [N] at |v| = {PROBE_V} m/s +- {PROBE_BAND:.0%}, {lowest:g} A")
    print(forces.to_string(index=False, float_format=lambda z: f"{z:.0f}"))
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return per_record, forces


if __name__ == "__main__":
    main()
