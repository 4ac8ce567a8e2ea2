#!/usr/bin/env python3
"""Loading a big machine log, measured side by side in one run (issue 15's benchmark):

* `cutlab log inspect FILE --json` (release build): the whole load through src/log's reader —
  dialect sniffed, every cell parsed, columns built — plus each column's statistics and the time
  column's steps checked, then the JSON printed; wall time of the process and its peak RSS;
* `pandas.read_csv(FILE, engine="c")` in a fresh Python process: the call's own time (the
  interpreter's start and `import pandas` are not counted) and the process's peak RSS.

The file is generated here, never kept in git: --rows rows (default 1,000,000) of a 10 kHz DAQ
export with 10 numeric columns (time, three spindle and three feed phase currents, speed, feed,
force), about 95 MB. Each case runs --rounds times, alternating, and keeps its best round. The
script also checks that both read the same numbers (row count and every column's mean). Prints a
Markdown table for docs/benchmarks.md.

    python3 scripts/bench/log_load.py [--rows 1000000] [--rounds 5] [--file /tmp/big.csv]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import pandas as pd

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CUTLAB = os.path.join(ROOT, "target", "release", "cutlab")

PANDAS_CHILD = r"""
import json, resource, sys, time
import pandas as pd
before_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
frame = pd.read_csv(sys.argv[1], engine="c")
seconds = time.perf_counter() - start
peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"seconds": seconds, "peak_kb": peak_kb, "before_kb": before_kb,
                  "rows": len(frame), "means": {c: float(frame[c].mean()) for c in frame}}))
"""


def generate(path: str, rows: int) -> None:
    """A 10 kHz export: time, phase currents of both drives, speed, feed, force."""
    rng = np.random.default_rng(1)
    t = np.arange(rows) / 10_000.0
    theta = 2 * np.pi * 66.7 * t
    amplitude = 10 + 2 * np.sin(2 * np.pi * 0.3 * t)
    shift = 2 * np.pi / 3
    columns = {"time_s": t}
    for k, name in enumerate(("U", "V", "W")):
        columns[f"S_I_{name} [A]"] = amplitude * np.cos(theta - k * shift) + 0.05 * rng.standard_normal(rows)
    for k, name in enumerate(("U", "V", "W")):
        columns[f"X_I_{name} [A]"] = 0.5 * np.cos(theta / 10 - k * shift) + 0.01 * rng.standard_normal(rows)
    columns["S_speed [rpm]"] = 1000 + rng.standard_normal(rows)
    columns["X_feed [mm/min]"] = 300 + 0.1 * rng.standard_normal(rows)
    columns["Fx [N]"] = 300 + 30 * rng.standard_normal(rows)
    pd.DataFrame(columns).to_csv(path, index=False, float_format="%.7g")


def timed(command: list) -> tuple:
    """Runs `command` under /usr/bin/time: (stdout, wall seconds, peak RSS in kB)."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as report:
        out = subprocess.run(
            ["/usr/bin/time", "-f", "%e %M", "-o", report.name] + command,
            check=True, capture_output=True, text=True,
        ).stdout
        wall_s, peak_kb = report.read().split()
    return out, float(wall_s), int(peak_kb)


def run_cutlab(path: str) -> dict:
    out, wall_s, peak_kb = timed([CUTLAB, "log", "inspect", path, "--json"])
    report = json.loads(out)
    return {
        "seconds": wall_s,
        "peak_kb": peak_kb,
        "rows": report["rows"],
        "means": {c["name"]: c["mean"] for c in report["columns"]},
    }


def run_pandas(path: str) -> dict:
    out, _, peak_kb = timed([sys.executable, "-c", PANDAS_CHILD, path])
    result = json.loads(out)
    result["process_peak_kb"] = peak_kb
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--file", help="where to write the generated log (default: a temporary file)")
    args = parser.parse_args()
    subprocess.run(["cargo", "build", "--release", "--features", "cli", "-q"], cwd=ROOT, check=True)
    with tempfile.TemporaryDirectory() as scratch:
        path = args.file or os.path.join(scratch, "big-log.csv")
        if not (args.file and os.path.exists(path)):
            generate(path, args.rows)
        size_mb = os.path.getsize(path) / 1e6
        cutlab, pandas = [], []
        for _ in range(args.rounds):
            cutlab.append(run_cutlab(path))
            pandas.append(run_pandas(path))
        best_c = min(cutlab, key=lambda r: r["seconds"])
        best_p = min(pandas, key=lambda r: r["seconds"])
        # Both read the same numbers.
        assert best_c["rows"] == best_p["rows"] == args.rows, (best_c["rows"], best_p["rows"])
        for name, mean in best_p["means"].items():
            ours = best_c["means"][name]
            assert abs(ours - mean) <= 1e-9 * max(1.0, abs(mean)), (name, ours, mean)
    ratio = best_p["seconds"] / best_c["seconds"]
    print(f"{args.rows:,} rows × 10 columns, {size_mb:.1f} MB, best of {args.rounds} rounds each, "
          f"alternating; both read the same numbers (rows and every column's mean)\n")
    print("| reader | time (s) | MB/s | peak memory (MB) |")
    print("|---|---|---|---|")
    print(f"| `cutlab log inspect --json` (load + statistics, whole process) | {best_c['seconds']:.2f} | "
          f"{size_mb / best_c['seconds']:.0f} | {best_c['peak_kb'] / 1024:.0f} |")
    print(f"| `pandas.read_csv(engine=\"c\")` (the call alone) | {best_p['seconds']:.2f} | "
          f"{size_mb / best_p['seconds']:.0f} | {best_p['process_peak_kb'] / 1024:.0f} "
          f"({(best_p['peak_kb'] - best_p['before_kb']) / 1024:.0f} above the interpreter with pandas) |")
    print(f"\ncutlab's speed: {ratio:.2f}× pandas's (target ≥ 1×); pandas {pd.__version__}, "
          f"numpy {np.__version__}")


if __name__ == "__main__":
    main()
