#!/usr/bin/env python3
"""Filter throughput, cutlab vs scipy, measured side by side in one run.

    python3 scripts/bench/filter_throughput.py [--samples 10000000] [--rounds 7]

Filters the same samples with the same design, butter(10, 50, fs=10000) as second-order
sections (five biquads), on one channel and on three channels, two ways:

  kernel      the filter loop alone, in place on a buffer already in memory:
              scipy's Cython loop scipy.signal._sosfilt._sosfilt (what sosfilt runs on its copy;
              three channels as a (3, N) array) vs cutlab's SosFilter / SosFilterBank
              process_slice (three channels interleaved);
  new output  y = scipy.signal.sosfilt(sos, x) as a whole (allocate, copy, filter; three channels
              both as (N, 3) along axis 0 and as (3, N) along axis 1, the faster counted) vs
              cutlab allocating a new output and filtering into it block by block.

The table sets cutlab's in-place filter against sosfilt as a whole (the issue's comparison) and
against scipy's loop alone (stricter: no copy on scipy's side), and shows both allocating a new
output (a measure of the allocator: numpy asks for transparent huge pages, Rust's Vec does not).

cutlab runs as the release build of examples/bench_filter.rs on the same samples, read from a
file and timed in memory. Rounds alternate scipy and cutlab so both see the same machine load;
each side keeps its best round. Prints a Markdown table for docs/benchmarks.md ("## Filter
throughput") and checks that the outputs agree.
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy
from scipy import signal

from machine import cpus, rustc_version

try:  # private; present in scipy 1.x. Without it the kernel row has no scipy figure.
    from scipy.signal._sosfilt import _sosfilt
except ImportError:  # pragma: no cover
    _sosfilt = None

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def scipy_kernel(sos, planar):
    """_sosfilt on a fresh copy (copy not timed), from rest."""
    work = np.array(planar, copy=True)
    zi = np.zeros((work.shape[0], sos.shape[0], 2))
    t, _ = timed(lambda: _sosfilt(sos, work, zi))
    return t, work


def cutlab(binary, path, channels, mode, repeats, output=None):
    cmd = [binary, "--input", path, "--channels", str(channels), "--mode", mode,
           "--repeats", str(repeats)]
    if output:
        cmd += ["--output", output]
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(done.stdout)["channel_samples_per_s"]


def machine():
    return (
        f"{cpus()}; Python {platform.python_version()}, "
        f"scipy {scipy.__version__}, numpy {np.__version__}; {rustc_version()}, release profile "
        f"(opt-level 3, default x86-64 target; three channels use AVX2 when the CPU has it)"
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000_000, help="samples per channel")
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()

    subprocess.run(["cargo", "build", "--release", "--example", "bench_filter"], cwd=ROOT, check=True)
    binary = os.path.join(ROOT, "target", "release", "examples", "bench_filter")

    sos = signal.butter(10, 50, fs=10000, output="sos")
    rng = np.random.default_rng(2024)
    n = args.samples
    one = rng.standard_normal(n)
    interleaved = rng.standard_normal((n, 3))  # frames in C order: u v w u v w ...
    planar = np.ascontiguousarray(interleaved.T)

    best = {}

    def keep_max(key, rate):
        best[key] = max(best.get(key, 0.0), rate)

    with tempfile.TemporaryDirectory() as tmp:
        paths = {1: os.path.join(tmp, "one.f64"), 3: os.path.join(tmp, "three.f64")}
        one.astype("<f8").tofile(paths[1])
        interleaved.astype("<f8").tofile(paths[3])
        for _ in range(args.rounds):
            # One channel.
            if _sosfilt is not None:
                t, k1 = scipy_kernel(sos, one.reshape(1, -1))
                keep_max("scipy kernel 1", n / t)
            keep_max("cutlab kernel 1", cutlab(binary, paths[1], 1, "kernel", 2))
            t, y1 = timed(lambda: signal.sosfilt(sos, one))
            keep_max("scipy new 1", n / t)
            keep_max("cutlab new 1", cutlab(binary, paths[1], 1, "new-output", 2))
            # Three channels.
            if _sosfilt is not None:
                t, k3 = scipy_kernel(sos, planar)
                keep_max("scipy kernel 3", 3 * n / t)
            keep_max("cutlab kernel 3", cutlab(binary, paths[3], 3, "kernel", 2))
            t, y3 = timed(lambda: signal.sosfilt(sos, interleaved, axis=0))
            keep_max("scipy new 3", 3 * n / t)
            t, _ = timed(lambda: signal.sosfilt(sos, planar, axis=1))
            keep_max("scipy new 3", 3 * n / t)
            keep_max("cutlab new 3", cutlab(binary, paths[3], 3, "new-output", 2))

        out1, out3 = os.path.join(tmp, "y1.f64"), os.path.join(tmp, "y3.f64")
        cutlab(binary, paths[1], 1, "kernel", 1, out1)
        cutlab(binary, paths[3], 3, "kernel", 1, out3)
        c1 = np.fromfile(out1, "<f8")
        c3 = np.fromfile(out3, "<f8").reshape(n, 3)
        agree1 = np.max(np.abs(c1 - y1)) / np.max(np.abs(y1))
        agree3 = np.max(np.abs(c3 - y3)) / np.max(np.abs(y3))

    def row(label, cutlab_key, scipy_key, target):
        s = best.get(scipy_key)
        c = best[cutlab_key]
        if s is None:
            return f"| {label} | n/a | {c/1e6:.0f} | n/a | {target} |"
        return f"| {label} | {s/1e6:.0f} | {c/1e6:.0f} | **{c/s:.2f}×** | {target} |"

    print(f"\nMachine: {machine()}")
    print(f"Samples: {n:,} per channel; best of {args.rounds} alternating rounds\n")
    print("| case | scipy (M channel-samples/s) | cutlab (M channel-samples/s) | cutlab / scipy | target |")
    print("|---|---:|---:|---:|---|")
    for channels, target in ((1, "≥ 1.0×"), (3, "≥ 2.5×")):
        name = "1 channel" if channels == 1 else f"{channels} channels"
        print(row(f"{name}: cutlab's filter vs `sosfilt` as a whole",
                  f"cutlab kernel {channels}", f"scipy new {channels}", target))
        print(row(f"{name}: filter loop vs filter loop (`_sosfilt`)",
                  f"cutlab kernel {channels}", f"scipy kernel {channels}", target))
        print(row(f"{name}: both allocate a new output",
                  f"cutlab new {channels}", f"scipy new {channels}", "(allocator)"))
    print(f"\nOutputs agree: max |cutlab − scipy| / max |scipy| = {agree1:.1e} (1 channel), "
          f"{agree3:.1e} (3 channels)")
    if not (agree1 < 1e-9 and agree3 < 1e-9):
        sys.exit("outputs disagree")


if __name__ == "__main__":
    main()
