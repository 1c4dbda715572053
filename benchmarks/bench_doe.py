"""Speed of the virtual rig: the whole Table II DoE, and each stage beside a plain peer.

Run: ``python benchmarks/bench_doe.py [--seed N] [--fs HZ] [--repeat R] [--workers W]``

Part 1 generates the whole Table II DoE (61 records, 5820 s of rig time, 5.82 million samples at
1 kHz) with the default reference damper and prints time, samples and samples/s, with the part
spent in the damper model's own ``predict`` measured separately on the same records. Target: under
10 s on a 2-core machine. It is run serially and with ``--workers`` processes (default 2; the
bytes are checked to be the same). The peer is the rig time itself (how much faster than real time).

Part 2 times each rig stage against the obvious implementation with NumPy / SciPy, in the same
run on the same inputs, and prints the ratio (peer time / ours; > 1 means ours is faster):

* road synthesis: inverse real FFT of the random-phase spectrum vs the direct sum of cosines;
* actuator: compiled zero-order-hold recursion vs ``scipy.signal.lsim`` of the same loop;
* driver lag: compiled recursion vs ``scipy.signal.lfilter``;
* PRBS: compiled shift register vs the same register in a Python loop.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from _timing import best_time
from scipy import signal as sps

from mrdamper.rig import ServoActuator, VirtualRig, available_reference_dampers, reference_damper
from mrdamper.rig.doe import TABLE_II, table_ii
from mrdamper.rig.driver import CurrentDriver
from mrdamper.signals import mls, road_profile
from mrdamper.signals.road import ISO_8608_CLASSES, N0


def _damper():  # type: ignore[no-untyped-def]
    if "quiroz2022" in available_reference_dampers():
        return reference_damper("quiroz2022"), "reference quiroz2022"
    from mrdamper.models.spencer import spencer1997

    return spencer1997(), "spencer1997 (quiroz2022.json not installed)"


def part1(seed: int, fs: float, workers: int, scale: float = 1.0) -> None:
    damper, label = _damper()
    rig = VirtualRig(damper=damper, fs=fs)
    table_ii(seed=seed, scale=0.07, rig=rig, experiments=[1])  # compile / load cached kernels
    t0 = time.perf_counter()
    doe = table_ii(seed=seed, scale=scale, rig=rig)
    total = time.perf_counter() - t0
    t0 = time.perf_counter()
    par = table_ii(seed=seed, scale=scale, rig=rig, workers=workers)
    total_par = time.perf_counter() - t0
    same = all(a.F.tobytes() == b.F.tobytes() for a, b in zip(doe, par))
    del par
    n = sum(e.n for e in doe)
    ch = damper.input
    t0 = time.perf_counter()
    for e in doe:
        damper.with_range_policy("clip").predict(e)
    t_damper = time.perf_counter() - t0
    rig_time = sum(s.duration * s.replicates for s in TABLE_II)
    print(f"Table II DoE, damper: {label}, fs {fs:g} Hz, seed {seed}, {os.cpu_count()} CPUs")
    print(f"{'quantity':<44}{'value':>16}")
    print(f"{'records':<44}{len(doe):>16d}")
    print(f"{'samples':<44}{n:>16d}")
    print(f"{'electrical channel':<44}{ch:>16}")
    print(f"{'total time [s]':<44}{total:>16.2f}")
    print(f"{'samples / s':<44}{n / total:>16.3g}")
    print(f"{'damper predict alone, same records [s]':<44}{t_damper:>16.2f}")
    print(f"{'rest of the rig (total - damper) [s]':<44}{max(total - t_damper, 0.0):>16.2f}")
    print(f"{'peer: rig time of the tests [s]':<44}{rig_time:>16.0f}")
    print(f"{'faster than real time (ratio)':<44}{rig_time / total:>16.1f}")
    print(f"{f'total time, {workers} worker processes [s]':<44}{total_par:>16.2f}")
    print(f"{'same bytes as the serial run':<44}{same!s:>16}")
    print(
        f"{'target < 10 s met (serial / workers)':<44}{f'{total < 10.0} / {total_par < 10.0}':>16}"
    )
    print(f"{'load average at the end (1 min)':<44}{os.getloadavg()[0]:>16.2f}")


def _sum_of_cosines(
    n: int, fs: float, fmin: float, fmax: float, rng: np.random.Generator
) -> np.ndarray:
    df = fs / n
    k = np.arange(n // 2 + 1)
    f = k * df
    band = (f >= fmin) & (f <= fmax)
    phases = rng.uniform(0, 2 * np.pi, size=k.size)[band]
    amp = np.sqrt(2 * ISO_8608_CLASSES["C"] * N0**2 * 20.0 / f[band] ** 2 * df)
    t = np.arange(n) / fs
    x = np.zeros(n)
    for a, fk, ph in zip(amp, f[band], phases):
        x += a * np.cos(2 * np.pi * fk * t + ph)
    return x


def _prbs_python(order: int, taps: tuple[int, ...], state: int, n_bits: int) -> list[int]:
    out = []
    top = order - 1
    shifts = [order - t for t in taps]
    for _ in range(n_bits):
        out.append(state & 1)
        fb = 0
        for s in shifts:
            fb ^= (state >> s) & 1
        state = (state >> 1) | (fb << top)
    return out


def part2(fs: float, repeat: int) -> None:
    rows = []
    n30 = int(30 * fs)
    ours = best_time(
        lambda: road_profile(
            fs, 30.0, seed=0, max_frequency=5.5, taper=0.0, fill=None, road_class="A"
        ),
        repeat,
    )
    peer = best_time(lambda: _sum_of_cosines(n30, fs, 0.2, 5.5, np.random.default_rng(0)), repeat)
    rows.append(("road profile 30 s (FFT vs sum of cosines)", ours, peer))

    x = road_profile(fs, 600.0, seed=1, max_frequency=5.5)
    act = ServoActuator()
    act.track(x[:100], fs)
    ours = best_time(lambda: act.track(x, fs), repeat)
    wn = 2 * np.pi * act.bandwidth
    sys = sps.StateSpace(
        [[0, 1], [-wn * wn, -2 * act.damping * wn]], [[0], [wn * wn]], [[1, 0], [0, 1]], [[0], [0]]
    )
    t = np.arange(x.size) / fs
    peer = best_time(lambda: sps.lsim(sys, x, t, X0=[x[0], 0.0], interp=False), repeat)
    rows.append(("actuator 600 s (recursion vs scipy lsim)", ours, peer))

    drv = CurrentDriver()
    i = np.clip(np.abs(x) * 50, 0, 1)
    drv.drive(i[:100], fs)
    ours = best_time(lambda: drv.drive(i, fs), repeat)
    a = np.exp(-1 / (fs * drv.time_constant))
    peer = best_time(lambda: sps.lfilter([0, 1 - a], [1, -a], i, zi=[a * i[0]])[0], repeat)
    rows.append(("driver lag 600 s (recursion vs lfilter)", ours, peer))

    mls(16, seed=0, n_bits=10)
    ours = best_time(lambda: mls(16, seed=0, n_bits=65535), repeat)
    peer = best_time(lambda: _prbs_python(16, (16, 15, 13, 4), 1, 65535), repeat)
    rows.append(("PRBS order 16, one period (numba vs Python)", ours, peer))

    print()
    print(f"{'stage':<48}{'ours [ms]':>12}{'peer [ms]':>12}{'peer/ours':>12}")
    for name, o, p in rows:
        print(f"{name:<48}{1e3 * o:>12.2f}{1e3 * p:>12.2f}{p / o:>12.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--fs", type=float, default=1000.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument(
        "--quick", action="store_true", help="durations x 0.1 and one repetition (seconds)"
    )
    args = ap.parse_args()
    part1(args.seed, args.fs, args.workers, scale=0.1 if args.quick else 1.0)
    part2(args.fs, 1 if args.quick else args.repeat)


if __name__ == "__main__":
    main()
