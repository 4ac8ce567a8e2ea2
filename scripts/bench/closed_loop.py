#!/usr/bin/env python3
"""Simulation speed, measured side by side in one run (issue 14's benchmark):

* cutlab's closed loop with the full chain (10 kHz three-phase currents of both drives, Hall
  sensors and noise, filters, RMS, estimator, fuzzy controller, envelope) on kim-step-doc:
  simulated seconds (teach cut + run) per wall second, natively (`cutlab sim`);
* the same closed loop compiled to wasm32 as the browser's worker is built (profile
  worker-release, wasm-opt -Oz) and run under node (examples/bench_loop_wasm.rs,
  scripts/bench/wasm_loop.mjs), simulated seconds per wall second;
* `cutlab compare` of six controllers with the fixed-feed references on kim-step-doc: wall time;
* the batched loop (issue 28): four runs of kim-step-doc one after another and as one batch
  (`closed_loop::batch`), natively (examples/bench_batch.rs) and in wasm
  (scripts/bench/wasm_batch.mjs), simulated seconds per CPU second of each way;
* the NumPy anchor: an open-loop milling simulation vectorised with NumPy at the same 10 kHz
  (mechanistic forces of a 2-tooth cutter, two three-phase drives with noise, RMS per period),
  simulated seconds per wall second.

Each case runs --rounds times, alternating, and keeps its best round. Prints a Markdown table and
one JSON line (for scripts/bench/run).

    python3 scripts/bench/closed_loop.py [--rounds 3] [--no-wasm] [--no-build]
"""
import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CUTLAB = os.path.join(ROOT, "target", "release", "cutlab")
WASM_DIR = os.path.join(ROOT, "target", "bench-wasm")
RATE_HZ = 10_000.0


def numpy_anchor(seconds: float, seed: int = 1) -> float:
    """Open-loop milling at 10 kHz, vectorised: returns the wall time."""
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    n = int(seconds * RATE_HZ)
    t = np.arange(n) / RATE_HZ
    rpm, teeth, feed_per_tooth, depth = 1000.0, 2, 0.1, 2.5
    ktc, krc, kte, kre = 2000.0, 800.0, 20.0, 25.0
    phi = 2 * np.pi * rpm / 60.0 * t
    fx = np.zeros(n)
    fy = np.zeros(n)
    for k in range(teeth):
        angle = np.mod(phi + 2 * np.pi * k / teeth, 2 * np.pi)
        cutting = angle < np.pi  # slot
        h = feed_per_tooth * np.sin(angle) * cutting
        ft = (ktc * h + kte * cutting) * depth
        fr = (krc * h + kre * cutting) * depth
        fx += -ft * np.cos(angle) - fr * np.sin(angle)
        fy += ft * np.sin(angle) - fr * np.cos(angle)
    torque = 0.01 * np.hypot(fx, fy)
    rms = []
    for pole_pairs, speed_hz, gain in ((2, rpm / 60.0, 0.4), (4, 4.0, 0.01)):
        theta = 2 * np.pi * pole_pairs * speed_hz * t
        amplitude = gain * (torque + 5.0)
        phases = [amplitude * np.cos(theta - s) for s in (0.0, 2 * np.pi / 3, 4 * np.pi / 3)]
        phases = [p + 0.02 * rng.standard_normal(n) for p in phases]
        instantaneous = np.sqrt((phases[0] ** 2 + phases[1] ** 2 + phases[2] ** 2) / 3.0)
        period = int(0.06 * RATE_HZ)
        usable = n - n % period
        rms.append(instantaneous[:usable].reshape(-1, period).mean(axis=1))
    _ = float(rms[0].sum() + rms[1].sum())
    return time.perf_counter() - start


def children_cpu_s() -> float:
    """Processor seconds of this script's finished child processes so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def cutlab_sim() -> tuple[float, float, float]:
    """Wall time of `cutlab sim`, its CPU time (the wall time less the waiting for a core on a
    shared machine) and the seconds it simulated (teach cut + run)."""
    with tempfile.TemporaryDirectory() as d:
        report = os.path.join(d, "r.json")
        cpu_start = children_cpu_s()
        start = time.perf_counter()
        subprocess.run(
            [CUTLAB, "sim", "--scenario", "kim-step-doc", "--controller", "fuzzy-dynamics",
             "--no-references", "--json", report],
            check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - start
        cpu = children_cpu_s() - cpu_start
        data = json.load(open(report))
    return wall, cpu, data["metrics"]["cycle_time_s"] + data["calibration"]["duration_s"]


def build_wasm() -> None:
    """The wasm workload built as the browser's computation worker is (Cargo profile
    `worker-release`, then `wasm-opt -Oz` as Trunk runs it, when wasm-opt is on PATH), bound for
    node by wasm-bindgen."""
    subprocess.run(
        ["cargo", "build", "--profile", "worker-release", "--target", "wasm32-unknown-unknown",
         "--example", "bench_loop_wasm", "-q"], cwd=ROOT, check=True)
    wasm = os.path.join(ROOT, "target", "wasm32-unknown-unknown", "worker-release", "examples",
                        "bench_loop_wasm.wasm")
    subprocess.run(["wasm-bindgen", "--target", "nodejs", "--out-dir", WASM_DIR, wasm], check=True)
    if shutil.which("wasm-opt"):
        bound = os.path.join(WASM_DIR, "bench_loop_wasm_bg.wasm")
        subprocess.run(["wasm-opt", "-Oz", "--enable-bulk-memory", "--enable-nontrapping-float-to-int",
                        "--enable-sign-ext", "--enable-mutable-globals", bound, "-o", bound], check=True)


def cutlab_wasm() -> tuple[float, float, float]:
    """Wall time of one run of the workload in wasm under node, its CPU time and the seconds it
    simulated."""
    out = subprocess.run(
        ["node", os.path.join(ROOT, "scripts", "bench", "wasm_loop.mjs"), WASM_DIR, "1"],
        check=True, capture_output=True, text=True).stdout
    data = json.loads(out.strip().splitlines()[-1])
    return data["wall_s"], data["cpu_s"], data["simulated_s"]


def batched_loop(wasm: bool) -> dict:
    """The four runs of examples/common/batch_workload.rs one after another and as one batch,
    natively or in wasm under node; the JSON line of examples/bench_batch.rs or
    scripts/bench/wasm_batch.mjs (best of three alternating rounds each)."""
    if wasm:
        command = ["node", os.path.join(ROOT, "scripts", "bench", "wasm_batch.mjs"), WASM_DIR, "3"]
    else:
        command = [os.path.join(ROOT, "target", "release", "examples", "bench_batch"),
                   "--repeats", "3"]
    out = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def cutlab_compare() -> float:
    start = time.perf_counter()
    subprocess.run(
        [CUTLAB, "compare", "--scenario", "kim-step-doc", "--controllers",
         "fixed,restriction,threshold,fuzzy-experience,fuzzy-dynamics,pi"],
        check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-wasm", action="store_true", help="skip the wasm case")
    parser.add_argument("--no-build", action="store_true",
                        help="time the builds already made (target/release/cutlab, target/bench-wasm)")
    args = parser.parse_args()
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--features", "cli", "-q"], cwd=ROOT,
                       check=True)
        subprocess.run(["cargo", "build", "--release", "--example", "bench_batch", "-q"],
                       cwd=ROOT, check=True)
        if not args.no_wasm:
            build_wasm()
    sim_best = compare_best = anchor_best = wasm_best = None
    sim_cpu_best = wasm_cpu_best = float("inf")
    simulated = None
    for _ in range(args.rounds):
        wall, cpu, simulated = cutlab_sim()
        sim_best = wall if sim_best is None else min(sim_best, wall)
        sim_cpu_best = min(sim_cpu_best, cpu)
        anchor = numpy_anchor(simulated)
        anchor_best = anchor if anchor_best is None else min(anchor_best, anchor)
        if not args.no_wasm:
            w, wasm_cpu, wasm_simulated = cutlab_wasm()
            wasm_cpu_best = min(wasm_cpu_best, wasm_cpu)
            if abs(wasm_simulated - simulated) > 1e-6:
                sys.exit(f"wasm simulated {wasm_simulated} s, native {simulated} s: not the same run")
            wasm_best = w if wasm_best is None else min(wasm_best, w)
        c = cutlab_compare()
        compare_best = c if compare_best is None else min(compare_best, c)
    # The batched loop after the rounds above: each call alternates its two ways itself.
    batches = {"native": batched_loop(False)}
    if not args.no_wasm:
        batches["wasm"] = batched_loop(True)
    cutlab_rate = simulated / sim_best
    anchor_rate = simulated / anchor_best
    print(f"simulated seconds per run: {simulated:.1f} (teach cut + cut)", file=sys.stderr)
    print("| case | measured | target |")
    print("|---|---:|---|")
    print(f"| closed loop, full chain, native: simulated s per wall s | {cutlab_rate:.0f} | ≥ 2500 |")
    if wasm_best is not None:
        print(f"| closed loop, full chain, wasm under node: simulated s per wall s | {simulated / wasm_best:.0f} | ≥ 1200 |")
    print(f"| closed loop, full chain, native: simulated s per CPU s | {simulated / sim_cpu_best:.0f} | — |")
    if wasm_best is not None:
        print(f"| closed loop, full chain, wasm under node: simulated s per CPU s | {simulated / wasm_cpu_best:.0f} | — |")
    print(f"| NumPy anchor (open loop, vectorised): simulated s per wall s | {anchor_rate:.0f} | — |")
    print(f"| cutlab native / NumPy anchor | {cutlab_rate / anchor_rate:.2f}× | ≥ 4.35× |")
    if wasm_best is not None:
        print(f"| cutlab wasm / NumPy anchor | {simulated / wasm_best / anchor_rate:.2f}× | — |")
    print(f"| `cutlab compare`, six controllers with references: wall s | {compare_best:.2f} | ≤ 1.5 |")
    for where, b in batches.items():
        for way in ("single", "batch"):
            label = "one after another" if way == "single" else "as one batch"
            print(f"| batched loop, {where}: four kim-step-doc runs {label}, simulated s per CPU s "
                  f"| {b['simulated_s'] / b[way + '_cpu_s']:.0f} | — |")
    print(json.dumps({
        "simulated_s": simulated,
        "native_sim_s_per_s": cutlab_rate,
        "wasm_sim_s_per_s": None if wasm_best is None else simulated / wasm_best,
        "native_sim_s_per_cpu_s": simulated / sim_cpu_best,
        "wasm_sim_s_per_cpu_s": None if wasm_best is None else simulated / wasm_cpu_best,
        "numpy_sim_s_per_s": anchor_rate,
        "native_over_numpy": cutlab_rate / anchor_rate,
        "compare_wall_s": compare_best,
        "batched_loop": {
            where: {way: b["simulated_s"] / b[way + "_cpu_s"] for way in ("single", "batch")}
            for where, b in batches.items()
        },
    }))


if __name__ == "__main__":
    main()
