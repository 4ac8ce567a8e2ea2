#!/usr/bin/env python3
"""Reference vectors for cutlab's signal chain, computed with scipy.

Writes tests/reference/signal/{design,filtering,welch}.json, which the tests in
tests/signal_*.rs load with include_str! (natively and under wasm). Regenerate with

    python3 scripts/reference/signal_reference.py

(needs numpy and scipy; the versions used are recorded in each file's "generator" entry).

What is computed:
  design.json     scipy.signal.butter(N, Wn, btype, fs=fs, output='sos') over a grid of kinds,
                  orders 1-20 and cut-offs from 5 Hz to 10 Hz below Nyquist at 10 kHz, plus
                  freqz_sos (sosfreqz) at chosen frequencies for every sixth design.
  filtering.json  sosfilt_zi, sosfilt (from rest and from sosfilt_zi * x[0]) and sosfiltfilt
                  with its default padding, for a few designs, on a test signal both sides can
                  generate bit for bit (see test_signal); one three-channel sosfiltfilt along
                  axis 0 (interleaved frames); the padlen rule.
  welch.json      scipy.signal.welch(x, fs, nperseg=n) with default window/overlap/detrend for
                  even, odd and too-long segment lengths.

The test signal uses only integer arithmetic and divisions by powers of two, so Rust rebuilds it
exactly and the files need not store it.
"""

import json
import os
import platform
import sys

import numpy as np
import scipy
from scipy import signal

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "..", "tests", "reference", "signal")
FS = 10_000.0


def test_signal(n, seed=12345):
    """Triangle (period 250) + LCG noise in [-0.5, 0.5) + a step of 3 at sample 600.

    Every value is an exact binary fraction: state>>8 is a 24-bit integer divided by 2**24, the
    triangle is an integer divided by 32. cutlab's tests rebuild it with the same integer steps.
    """
    state = seed
    out = []
    for i in range(n):
        state = (1664525 * state + 1013904223) % 2**32
        noise = (state >> 8) / 2**24 - 0.5
        p = i % 250
        tri = (p if p < 125 else 250 - p) / 32 - 2.0
        step = 3.0 if i >= 600 else 0.0
        out.append(tri + noise + step)
    return np.array(out, dtype=np.float64)


def freqz(sos, freqs, fs):
    if hasattr(signal, "freqz_sos"):
        return signal.freqz_sos(sos, worN=freqs, fs=fs)[1]
    return signal.sosfreqz(sos, worN=freqs, fs=fs)[1]


def generator():
    return {
        "script": "scripts/reference/signal_reference.py",
        "scipy": scipy.__version__,
        "numpy": np.__version__,
        "python": platform.python_version(),
    }


def floats(a):
    return [float(v) for v in np.asarray(a, dtype=np.float64).ravel()]


def design_cases():
    cases = []
    single_cutoffs = [5.0, 50.0, 1000.0, 4000.0, 4900.0, 4990.0]
    orders = [1, 2, 3, 4, 5, 8, 10, 11, 15, 20]
    for kind in ["lowpass", "highpass"]:
        for order in orders:
            for cutoff in single_cutoffs:
                cases.append((kind, order, [cutoff], FS))
    bands = [(5.0, 50.0), (40.0, 400.0), (1000.0, 4000.0), (4500.0, 4990.0), (10.0, 4950.0)]
    band_orders = [1, 2, 3, 4, 7, 10, 13, 20]
    for kind in ["bandpass", "bandstop"]:
        for order in band_orders:
            for band in bands:
                cases.append((kind, order, list(band), FS))
    # The papers' filters and other sampling rates.
    cases += [
        ("lowpass", 2, [260.0], FS),
        ("lowpass", 2, [50.0], FS),
        ("lowpass", 10, [5.0], FS),
        ("lowpass", 4, [100.0], 1000.0),
        ("bandstop", 3, [45.0, 55.0], 1000.0),
        ("highpass", 6, [20.0], 44100.0),
        ("bandpass", 5, [3.0, 7.0], 200.0),
    ]
    return cases


def response_freqs(cutoffs, fs):
    nyq = fs / 2
    grid = list(np.geomspace(fs * 1e-5, nyq * 0.9999, 24))
    edges = list(cutoffs) + [0.0, nyq * 0.5]
    return sorted(set(float(f) for f in grid + edges))


def tied_poles(z, p):
    """Whether two pole pairs are (nearly) equally close to the unit circle.

    zpk2sos places the pole closest to the circle last; for a band centred on fs/4 (f1 + f2 =
    fs/2) mirror-image poles tie in exact arithmetic and scipy's rounding decides the order of
    the sections. The tests compare such designs by response and by their set of denominators.
    """
    upper = [q for q in p if q.imag >= 0]
    d = np.sort(np.abs(1 - np.abs(np.array(upper))))
    gaps = np.diff(d)
    return bool(np.any(gaps <= 1e-9 * d[1:]))


def make_design():
    cases = []
    for i, (kind, order, cutoffs, fs) in enumerate(design_cases()):
        wn = cutoffs[0] if len(cutoffs) == 1 else cutoffs
        sos = signal.butter(order, wn, btype=kind, fs=fs, output="sos")
        z, p, _ = signal.butter(order, wn, btype=kind, fs=fs, output="zpk")
        case = {
            "kind": kind,
            "order": order,
            "cutoff_hz": cutoffs,
            "sample_rate_hz": fs,
            "tied_poles": tied_poles(z, p),
            "sos": [floats(row) for row in sos],
        }
        if i % 6 == 0:
            f = response_freqs(cutoffs, fs)
            h = freqz(sos, np.array(f), fs)
            case["response"] = {"freq_hz": f, "re": floats(h.real), "im": floats(h.imag)}
        cases.append(case)
    return {"generator": generator(), "cases": cases}


def make_filtering():
    n = 1000
    x = test_signal(n)
    cases = []
    specs = [
        ("lowpass", 10, [50.0], FS),
        ("lowpass", 10, [5.0], FS),
        ("bandpass", 4, [40.0, 400.0], FS),
        ("highpass", 3, [4500.0], FS),
        ("lowpass", 15, [1000.0], FS),
    ]
    for kind, order, cutoffs, fs in specs:
        wn = cutoffs[0] if len(cutoffs) == 1 else cutoffs
        sos = signal.butter(order, wn, btype=kind, fs=fs, output="sos")
        zi = signal.sosfilt_zi(sos)
        ntaps = 2 * len(sos) + 1 - min((sos[:, 2] == 0).sum(), (sos[:, 5] == 0).sum())
        case = {
            "kind": kind,
            "order": order,
            "cutoff_hz": cutoffs,
            "sample_rate_hz": fs,
            "sos": [floats(row) for row in sos],
            "zi": [floats(row) for row in zi],
            "padlen": int(3 * ntaps),
            "sosfilt": floats(signal.sosfilt(sos, x)),
            "sosfiltfilt": floats(signal.sosfiltfilt(sos, x)),
        }
        if kind == "lowpass" and cutoffs == [50.0]:
            case["sosfilt_from_steady_state"] = floats(signal.sosfilt(sos, x, zi=zi * x[0])[0])
        cases.append(case)

    # The shortest input sosfiltfilt accepts: padlen + 1 samples.
    sos = signal.butter(4, 100.0, fs=FS, output="sos")
    padlen = 3 * (2 * len(sos) + 1)
    short = x[: padlen + 1]
    shortest = {
        "kind": "lowpass",
        "order": 4,
        "cutoff_hz": [100.0],
        "sample_rate_hz": FS,
        "padlen": padlen,
        "sosfiltfilt": floats(signal.sosfiltfilt(sos, short)),
    }
    try:
        signal.sosfiltfilt(sos, x[:padlen])
        rejects = False
    except ValueError:
        rejects = True
    shortest["rejects_padlen_samples"] = rejects

    # Three channels as interleaved frames (shape (frames, 3), filtered along axis 0).
    frames = 400
    three = np.stack([x[:frames], x[200 : 200 + frames], -x[400 : 400 + frames]], axis=1)
    sos = signal.butter(6, 200.0, fs=FS, output="sos")
    multi = {
        "kind": "lowpass",
        "order": 6,
        "cutoff_hz": [200.0],
        "sample_rate_hz": FS,
        "channels": 3,
        "offsets": [0, 200, 400],
        "signs": [1.0, 1.0, -1.0],
        "frames": frames,
        "sosfiltfilt_interleaved": floats(signal.sosfiltfilt(sos, three, axis=0)),
    }
    return {
        "generator": generator(),
        "signal": {"length": n, "seed": 12345},
        "cases": cases,
        "shortest": shortest,
        "three_channels": multi,
    }


def make_welch():
    x = test_signal(3000)
    cases = []
    for nperseg, length in [(256, 3000), (100, 3000), (255, 3000), (1024, 600)]:
        f, p = signal.welch(x[:length], fs=FS, nperseg=nperseg)
        cases.append(
            {"nperseg": nperseg, "length": length, "freq_hz": floats(f), "psd": floats(p)}
        )
    return {
        "generator": generator(),
        "signal": {"seed": 12345},
        "sample_rate_hz": FS,
        "cases": cases,
    }


def main():
    os.makedirs(OUT, exist_ok=True)
    import warnings

    warnings.simplefilter("ignore")  # welch warns when nperseg > len(x): that case is intended
    for name, make in [("design", make_design), ("filtering", make_filtering), ("welch", make_welch)]:
        data = make()
        path = os.path.join(OUT, f"{name}.json")
        with open(path, "w") as fh:
            json.dump(data, fh, separators=(",", ":"))
            fh.write("\n")
        print(f"wrote {os.path.relpath(path)} ({os.path.getsize(path)} bytes)", file=sys.stderr)


if __name__ == "__main__":
    main()
