"""Identification time and peak memory against record length, for every model kind.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_scale.py              # 6 min, 1 h, 10 h
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_scale.py --quick      # 12 s, 2 min (seconds)
    python benchmarks/bench_scale.py --lengths 360 3600 --kinds lpv narx --cache /tmp/scale
    # windows vs every sample:
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_scale.py --accuracy lpv p15 narx
    # the records read from files, as `mrdamper fit` reads them:
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_scale.py --lengths 36000 --source parquet-file

The records come from the virtual rig (default reference damper, 1 kHz): road profile (ISO 8608
class C at 20 m/s, 4.5 Hz band) with an APRBS current (0.2 s minimum hold) over the damper's
range, as Table II's sequence 2 but longer. One record is at most one hour long (``--record``);
a longer case uses several records (10 h = ten seeded 1 h records), a shorter one the start of
the first record. The records are generated once, in a subprocess, into ``--cache`` as ``.npy``
files (one per channel).

Every fit runs in its own fresh Python process, so the peak resident memory it reports
(``resource.getrusage(RUSAGE_SELF).ru_maxrss`` of that process, read at its end) belongs to that
fit alone: interpreter, imports, the records (read from the ``.npy`` files) and the
identification. Before the timed fit the process fits the same kind once on the first 12 s of the
data, so loading the compiled kernels is not counted in the fit time (it is in the memory).
``fit [s]`` is the wall time of ``get_estimator(kind).fit(records)`` with default settings; the
CPU time of the process during the fit is printed beside it (on a loaded machine the wall time
follows the load, the CPU time much less).

The table gives, per kind and length, the fit time, the peak RSS, the RSS before the fit (data
loaded) and the ratio of each time to the shortest case's; the summary gives the log-log slope of
fit time against samples (1 = linear) from a least-squares line through all lengths, and checks
the targets: fit <= 30 s and peak <= 1.5 GB at 1 h, 1 h fit <= 12 x the 6 min fit, peak <= 3 GB at
10 h. A fit that takes longer than ``--timeout`` is stopped and reported as such. Timings on a
loaded machine are noisy; the ratios between kinds and lengths of one run are what to compare.

``--source`` says where the fit process takes the records from. ``npy`` (default) maps the
generated ``.npy`` files read-only; the others go through the reader every command uses
(``mrdamper.data.read_records``, as ``mrdamper fit KIND PATH``), from files written once into the
cache: ``parquet-folder`` (one Parquet file per record of at most ``--record`` seconds, 10 h =
a folder of ten 1 h files), ``parquet-file`` (the whole length in one Parquet file, row groups of
10^6 rows) and ``csv-folder`` (as ``parquet-folder``, CSV). Reading is timed apart (``read [s]``)
and counts in the peak memory.

``--accuracy KIND ...`` checks what the long-campaign windows cost in accuracy: each kind is fitted
on the first 1 h record twice in one process, with the windows and on every sample (threshold
raised), and both models are scored in free run on that record and on a second 1 h record.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

SOURCES = ("npy", "parquet-folder", "parquet-file", "csv-folder")
KINDS = ["lpv", "lti", "p15", "sp1", "sp2", "sp3", "sp4", "spencer", "bingham", "narx"]
CHANNELS = ("t", "x", "v", "i", "F")
FS = 1000.0
WARMUP_S = 12.0
TARGETS = {"fit_1h_s": 30.0, "rss_1h_gb": 1.5, "ratio_1h_6min": 12.0, "rss_10h_gb": 3.0}


# ----------------------------------------------------------------------------- child: records
def _generate(cache: Path, record_s: float, n_records: int, seed: int) -> None:
    """Write ``n_records`` rig records of ``record_s`` seconds into ``cache`` (skips existing)."""
    from mrdamper.rig import VirtualRig
    from mrdamper.rig.doe import DoeSequence, make_record, record_seeds

    rig = VirtualRig(fs=FS)
    spec = DoeSequence(2, "Road Profile", "APRBS", record_s, n_records, 4.5)
    for k, rs in enumerate(record_seeds(seed, n_records)):
        folder = cache / f"rec{k:02d}"
        if (folder / "done").is_file():
            continue
        folder.mkdir(parents=True, exist_ok=True)
        rec = make_record(spec, k + 1, rs, rig)
        for ch in CHANNELS:
            arr = getattr(rec, ch)
            if ch == "t":  # every record starts at 0; the fit only needs a uniform time base
                arr = arr - arr[0]
            import numpy as np

            np.save(folder / f"{ch}.npy", np.asarray(arr, dtype=np.float64))
        (folder / "meta.json").write_text(json.dumps({"name": rec.name, "n": rec.n}))
        (folder / "done").write_text("")
        del rec
        print(f"  record {k + 1}/{n_records}: {record_s:g} s", file=sys.stderr, flush=True)


def _load(cache: Path, length_s: float, record_s: float) -> list[Any]:
    import numpy as np

    from mrdamper.data import Experiment

    out = []
    left = round(length_s * FS)
    per = round(record_s * FS)
    k = 0
    while left > 0:
        folder = cache / f"rec{k:02d}"
        n = min(left, per)
        arrs = {ch: np.load(folder / f"{ch}.npy", mmap_mode="r")[:n] for ch in CHANNELS}
        out.append(Experiment(**arrs, name=f"rec{k:02d}"))
        left -= n
        k += 1
    return out


def _campaign(cache: Path, source: str, length_s: float, record_s: float) -> Path:
    """Write the records of ``length_s`` seconds as ``source`` files (once); return the path that
    ``mrdamper fit`` would be given: a folder, or the one file."""
    import numpy as np

    from mrdamper.data import write_csv, write_parquet

    label = f"{source}-{length_s:g}s"
    target = cache / label / ("campaign.parquet" if source == "parquet-file" else "records")
    if (cache / label / "done").is_file():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    records = _load(cache, length_s, record_s)
    if source == "parquet-file":
        import pyarrow as pa
        import pyarrow.parquet as pq

        writer, t0 = None, 0.0
        for rec in records:  # one record at a time, continuous time
            cols = {ch: np.asarray(getattr(rec, ch)) for ch in CHANNELS}
            cols["t"] = cols["t"] - cols["t"][0] + t0
            t0 = float(cols["t"][-1]) + 1.0 / FS
            table = pa.table(cols)
            if writer is None:
                writer = pq.ParquetWriter(target, table.schema)
            writer.write_table(table, row_group_size=1_000_000)
        assert writer is not None
        writer.close()
    else:
        target.mkdir(exist_ok=True)
        write = write_parquet if source == "parquet-folder" else write_csv
        suffix = ".parquet" if source == "parquet-folder" else ".csv"
        for rec in records:
            write(rec, target / f"{rec.name}{suffix}", force=True)
    (cache / label / "done").write_text("")
    return target


def _child_fit(kind: str, cache: Path, length_s: float, record_s: float, source: str) -> None:
    import resource

    from mrdamper.data import read_records
    from mrdamper.models import get_estimator

    read_s = 0.0
    if source == "npy":
        records = _load(cache, length_s, record_s)
    else:
        path = _campaign(cache, source, length_s, record_s)
        t0 = time.perf_counter()
        records = list(read_records([path]))
        read_s = time.perf_counter() - t0
    warm = records[0].slice(0, int(WARMUP_S * FS))
    get_estimator(kind).fit(warm)
    del warm
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB -> GiB
    t0, c0 = time.perf_counter(), time.process_time()
    model = get_estimator(kind).fit(records)
    fit_s, cpu_s = time.perf_counter() - t0, time.process_time() - c0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    prov = dict(model.provenance)
    check = prov.get("full_data_check") or prov.get("chunked") or {}
    print(
        json.dumps(
            {
                "fit_s": fit_s,
                "cpu_s": cpu_s,
                "rss_gb": peak,
                "rss_before_gb": rss_before,
                "read_s": read_s,
                "n": sum(r.n for r in records),
                "check": check,
            },
            default=str,
        )
    )


def _child_accuracy(kind: str, cache: Path) -> None:
    """Fit ``kind`` on record 0 (1 h) with the long-campaign windows and on every sample (threshold
    raised); score both in free run on record 1 (test) and record 0 (train)."""
    from mrdamper.errors import MrDamperError
    from mrdamper.models import _scale, get_estimator

    train, test = _load(cache, 7200.0, 3600.0)
    get_estimator(kind).fit(train.slice(0, int(WARMUP_S * FS)))
    out: dict[str, Any] = {}
    for label in ("windows", "every sample"):
        if label == "every sample":
            _scale.WINDOW_THRESHOLD = 10**12
        t0 = time.perf_counter()
        model = get_estimator(kind).fit(train).with_range_policy("clip")
        fit_s = time.perf_counter() - t0
        scores = {}
        for name, rec in (("train", train), ("test", test)):
            try:
                scores[name] = model.score(rec).esr
            except MrDamperError as exc:  # a diverging free run is a result, not a crash
                scores[name] = f"{type(exc).__name__}"
        out[label] = {"fit_s": fit_s, **scores}
    print(json.dumps(out))


# ----------------------------------------------------------------------------- parent
def _run_child(args: list[str], timeout: float) -> dict[str, Any]:
    env = dict(os.environ, OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    cmd = [sys.executable, str(Path(__file__).resolve()), *args]
    try:
        proc = subprocess.run(
            cmd, capture_output=True, text=True, env=env, timeout=timeout, check=False
        )
    except subprocess.TimeoutExpired:
        return {"status": f"stopped after {timeout:g} s"}
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["?"])[-1]
        return {"status": f"failed: {last[:120]}"}
    return {"status": "ok", **json.loads(proc.stdout.strip().splitlines()[-1])}


def _slope(xs: list[float], ys: list[float]) -> float:
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    den = sum((a - mx) ** 2 for a in lx)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / den if den > 0 else float("nan")


def _label(s: float) -> str:
    return f"{s / 3600:g} h" if s >= 3600 else (f"{s / 60:g} min" if s >= 60 else f"{s:g} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--quick", action="store_true", help="short lengths (12 s, 120 s): seconds per kind"
    )
    ap.add_argument(
        "--lengths", type=float, nargs="+", help="record lengths [s] (default 360 3600 36000)"
    )
    ap.add_argument("--kinds", nargs="+", default=KINDS, help="model kinds (default: all)")
    ap.add_argument(
        "--record", type=float, default=3600.0, help="longest single record [s] (default 3600)"
    )
    ap.add_argument(
        "--cache", type=Path, help="folder for the generated records (default: a temporary one)"
    )
    ap.add_argument("--seed", type=int, default=9)
    ap.add_argument(
        "--source",
        choices=SOURCES,
        default="npy",
        help="where the fit reads the records: mapped .npy (default) or files read as by "
        "'mrdamper fit' (a Parquet or CSV folder, one Parquet file)",
    )
    ap.add_argument("--timeout", type=float, default=900.0, help="stop a fit after this long [s]")
    ap.add_argument("--json", type=Path, help="also write the rows as JSON here")
    ap.add_argument(
        "--accuracy",
        nargs="+",
        metavar="KIND",
        help=(
            "instead of the scaling table: windows vs every sample on 1 h (train record 1, test "
            "record 2)"
        ),
    )
    ap.add_argument("--child-accuracy", nargs=2, metavar=("KIND", "CACHE"), help=argparse.SUPPRESS)
    ap.add_argument(
        "--child",
        nargs=5,
        metavar=("KIND", "CACHE", "LENGTH", "RECORD", "SOURCE"),
        help=argparse.SUPPRESS,
    )
    ap.add_argument(
        "--write-campaign",
        nargs=4,
        metavar=("CACHE", "SOURCE", "LENGTH", "RECORD"),
        help=argparse.SUPPRESS,
    )
    ap.add_argument(
        "--generate", nargs=4, metavar=("CACHE", "RECORD", "N", "SEED"), help=argparse.SUPPRESS
    )
    args = ap.parse_args()
    if args.child:
        kind, cache, length, record, source = args.child
        _child_fit(kind, Path(cache), float(length), float(record), source)
        return
    if args.write_campaign:
        cache, source, length, record = args.write_campaign
        _campaign(Path(cache), source, float(length), float(record))
        return
    if args.child_accuracy:
        _child_accuracy(args.child_accuracy[0], Path(args.child_accuracy[1]))
        return
    if args.generate:
        cache, record, n, seed = args.generate
        _generate(Path(cache), float(record), int(n), int(seed))
        return

    if args.accuracy:
        _accuracy(args)
        return
    lengths = sorted(args.lengths or ([12.0, 120.0] if args.quick else [360.0, 3600.0, 36000.0]))
    unknown = sorted(set(args.kinds) - set(KINDS))
    if unknown:
        raise SystemExit(f"--kinds: unknown {unknown}; expected some of {KINDS}")
    record_s = min(args.record, max(lengths))
    n_records = math.ceil(max(lengths) / record_s - 1e-9)
    with tempfile.TemporaryDirectory(prefix="bench-scale-") as tmp:
        cache = args.cache or Path(tmp)
        cache = cache / f"seed{args.seed}-rec{record_s:g}s"
        print(
            f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs, "
            f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', '1')}; {n_records} "
            f"record(s) of {_label(record_s)} in {cache}",
            flush=True,
        )
        t0 = time.perf_counter()
        subprocess.run(
            [
                sys.executable,
                str(Path(__file__).resolve()),
                "--generate",
                str(cache),
                str(record_s),
                str(n_records),
                str(args.seed),
            ],
            check=True,
        )
        print(f"records ready in {time.perf_counter() - t0:.1f} s", flush=True)
        if args.source != "npy":
            t0 = time.perf_counter()
            for length in lengths:  # written in a process of its own, not counted in the fits
                subprocess.run(
                    [
                        sys.executable,
                        str(Path(__file__).resolve()),
                        "--write-campaign",
                        str(cache),
                        args.source,
                        str(length),
                        str(record_s),
                    ],
                    check=True,
                )
            print(f"{args.source} files ready in {time.perf_counter() - t0:.1f} s", flush=True)
        rows = []
        for kind in args.kinds:
            for length in lengths:
                r = _run_child(
                    ["--child", kind, str(cache), str(length), str(record_s), args.source],
                    args.timeout,
                )
                row = {"kind": kind, "length_s": length, "source": args.source, **r}
                rows.append(row)
                if r["status"] == "ok":
                    print(
                        f"{kind:8s} {_label(length):>7s}: fit {r['fit_s']:8.2f} s (cpu "
                        f"{r['cpu_s']:.2f} s), peak {r['rss_gb']:.2f} GB (before fit "
                        f"{r['rss_before_gb']:.2f} GB)"
                        + (f", read {r['read_s']:.1f} s" if args.source != "npy" else ""),
                        flush=True,
                    )
                else:
                    print(f"{kind:8s} {_label(length):>7s}: {r['status']}", flush=True)
    _report(rows, lengths)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=str) + "\n")


def _accuracy(args: argparse.Namespace) -> None:
    with tempfile.TemporaryDirectory(prefix="bench-scale-") as tmp:
        cache = (args.cache or Path(tmp)) / f"seed{args.seed}-rec3600s"
        subprocess.run(
            [
                sys.executable,
                str(Path(__file__).resolve()),
                "--generate",
                str(cache),
                "3600",
                "2",
                str(args.seed),
            ],
            check=True,
        )
        print(
            "| model | windows: fit [s] / train ESR / test ESR | every sample: fit [s] / train "
            "ESR / test ESR |"
        )
        print("|---|---|---|")
        for kind in args.accuracy:
            r = _run_child(["--child-accuracy", kind, str(cache)], args.timeout)
            if r["status"] != "ok":
                print(f"| {kind} | {r['status']} | |", flush=True)
                continue

            def fmt(d: dict[str, Any]) -> str:
                esr = [
                    f"{d[k]:.6f}" if isinstance(d[k], float) else d[k] for k in ("train", "test")
                ]
                return f"{d['fit_s']:.1f} / {esr[0]} / {esr[1]}"

            print(f"| {kind} | {fmt(r['windows'])} | {fmt(r['every sample'])} |", flush=True)


def _report(rows: list[dict[str, Any]], lengths: list[float]) -> None:
    print(
        "\n| model | "
        + " | ".join(f"{_label(s)}: fit [s] / peak RSS [GB]" for s in lengths)
        + " | log-log slope | targets |"
    )
    print("|---|" + "---|" * len(lengths) + "---|---|")
    for kind in dict.fromkeys(r["kind"] for r in rows):
        by = {r["length_s"]: r for r in rows if r["kind"] == kind}
        cells, ok_x, ok_y = [], [], []
        for s in lengths:
            r = by[s]
            if r["status"] == "ok":
                cells.append(f"{r['fit_s']:.2f} / {r['rss_gb']:.2f}")
                ok_x.append(float(r["n"]))
                ok_y.append(max(float(r["fit_s"]), 1e-3))
            else:
                cells.append(r["status"])
        slope = f"{_slope(ok_x, ok_y):.2f}" if len(ok_x) >= 2 else "-"
        print(f"| {kind} | " + " | ".join(cells) + f" | {slope} | {_targets(by)} |")


def _targets(by: dict[float, dict[str, Any]]) -> str:
    out = []
    one, short, ten = by.get(3600.0), by.get(360.0), by.get(36000.0)
    if one is not None:
        if one["status"] != "ok":
            out.append("1 h: not measured")
        else:
            out.append("1 h fit " + ("ok" if one["fit_s"] <= TARGETS["fit_1h_s"] else "MISSED"))
            out.append("1 h RSS " + ("ok" if one["rss_gb"] <= TARGETS["rss_1h_gb"] else "MISSED"))
            if short is not None and short["status"] == "ok":
                ratio = one["fit_s"] / max(short["fit_s"], 1e-3)
                out.append(
                    f"1 h / 6 min {ratio:.1f}x "
                    + ("ok" if ratio <= TARGETS["ratio_1h_6min"] else "MISSED")
                )
    if ten is not None:
        if ten["status"] != "ok":
            out.append("10 h: not measured")
        else:
            out.append("10 h RSS " + ("ok" if ten["rss_gb"] <= TARGETS["rss_10h_gb"] else "MISSED"))
    return ", ".join(out) or "-"


if __name__ == "__main__":
    main()
