#!/usr/bin/env python3
"""Reference values for cutlab's teach-in tests, computed outside the project.

Writes tests/reference/tuning/ (see the README there):

* teach_cut_log.csv - a logged teach cut as a machine exports it: semicolons, decimal commas, a
                      byte-order mark, German column names, air rows before the cut, the override
                      cycling 100/30/140/60 % and a noisy spindle current (seeded numpy);
* teach_in.json     - what a teach-in must propose from that log, read back with pandas and
                      fitted with numpy: the median force at 100 % override, the least-squares
                      current line, its residual, the calibrated range, and the proposal made by
                      the rule docs/tuning.md states (80 % of that force inside the calibrated
                      range, reference current on the line, gap = max(5 %, 6 sigma / target));
                      and, for paper 001's mills, the force the simulated teach cut must find at
                      100 % override: Altintas' closed-form mean resultant at the programmed feed
                      (Manufacturing Automation, ch. 2), written out independently.

Run from the repository root:  python3 scripts/reference/tuning_reference.py
Needs numpy and pandas (pip install numpy pandas).
"""

import io
import json
import math
import os

import numpy as np
import pandas as pd

OUT = os.path.join("tests", "reference", "tuning")

TARGET_FRACTION = 0.8
MIN_GAP_PCT = 5.0
SIGMAS = 3.0


def write_log():
    """A teach cut at 1200 rpm: 0.06 s periods, 1.5 s per override step, air for the first
    second. The force follows the override (chip load) and a slow rise in depth; the current is
    I = 4.2 A + 0.012 A/N * F plus Gaussian noise of 0.05 A."""
    rng = np.random.RandomState(20261124)
    period_s = 0.06
    steps = [100.0, 30.0, 140.0, 60.0]
    rows = []
    for k in range(250):
        t = (k + 1) * period_s
        override = steps[int(t // 1.5) % 4]
        cutting = t > 1.0
        depth_factor = 1.0 + 0.15 * math.sin(0.4 * t)
        force = 260.0 * (override / 100.0) ** 0.8 * depth_factor if cutting else 0.0
        speed = 1200.0 * (1.0 - 0.004 * force / 300.0) + rng.normal(0.0, 0.5)
        current = 4.2 + 0.012 * force + rng.normal(0.0, 0.05)
        feed = 480.0 * override / 100.0
        rows.append((t, current, speed, feed, override, force, "Schnitt" if cutting else "Luft"))
    text = io.StringIO()
    text.write("\ufeffZeit [s];S_Strom [A];S_Drehzahl (rpm);X_Vorschub [mm/min];Override [%];"
               "Kraft [N];Phase\r\n")
    for t, current, speed, feed, override, force, phase in rows:
        cells = [f"{t:.2f}", f"{current:.5f}", f"{speed:.2f}", f"{feed:.1f}", f"{override:.0f}",
                 f"{force:.3f}", phase]
        text.write(";".join(c.replace(".", ",") for c in cells) + "\r\n")
    with open(os.path.join(OUT, "teach_cut_log.csv"), "w", encoding="utf-8", newline="") as fh:
        fh.write(text.getvalue())


def log_reference():
    """The teach-in of the log, from pandas' reading of it."""
    df = pd.read_csv(os.path.join(OUT, "teach_cut_log.csv"), sep=";", decimal=",",
                     encoding="utf-8-sig")
    force = df["Kraft [N]"].to_numpy()
    current = df["S_Strom [A]"].to_numpy()
    time = df["Zeit [s]"].to_numpy()
    override = df["Override [%]"].to_numpy()
    speed = df["S_Drehzahl (rpm)"].to_numpy()
    feed = df["X_Vorschub [mm/min]"].to_numpy()
    # The teach cut's selection (docs/tuning.md, "What a teach cut keeps"): half a second past an
    # override change, the spindle's speed within 1 % of the row before, the axes feeding, and a
    # positive force.
    changed = np.r_[False, override[1:] != override[:-1]]
    change_time = pd.Series(np.where(changed, time, np.nan)).ffill().fillna(-np.inf).to_numpy()
    settled_override = time - change_time >= 0.5
    steady = np.r_[True, np.abs(np.diff(speed)) <= 0.01 * np.abs(speed[1:])]
    cutting = settled_override & steady & (np.abs(feed) >= 1e-6) & (force > 0)
    full = cutting & (np.abs(override - 100.0) <= 0.5)
    force_full = float(np.median(force[full]))
    speed_full = float(np.median(df["S_Drehzahl (rpm)"].to_numpy()[full]))
    # Least squares I = idle + s F over every row kept (one speed: the droop is < 2 %).
    (slope, idle), ss_res, _, _, _ = np.polyfit(force[cutting], current[cutting], 1, full=True)
    n = int(cutting.sum())
    residual_a = math.sqrt(float(ss_res[0]) / (n - 2))
    residual_n = residual_a / slope
    lo_a, hi_a = float(current[cutting].min()), float(current[cutting].max())
    lo_n, hi_n = (lo_a - idle) / slope, (hi_a - idle) / slope
    target = min(max(TARGET_FRACTION * force_full, lo_n), hi_n)
    return {
        "rows_at_full_override": int(full.sum()),
        "rows_fitted": n,
        "force_at_full_override_n": force_full,
        "spindle_rpm": speed_full,
        "idle_current_a": float(idle),
        "sensitivity_a_per_n": float(slope),
        "residual_std_n": residual_n,
        "calibrated_force_n": [lo_n, hi_n],
        "target_n": target,
        "reference_current_a": float(idle + slope * target),
        "gap_pct": max(MIN_GAP_PCT, 200.0 * SIGMAS * residual_n / target),
    }


# Altintas ch. 2, average forces per revolution of a cutter with `teeth` straight teeth; the same
# expressions as scripts/reference/plant_reference.py (which needs scipy besides).
def mean_forces_xy(teeth, depth, feed, k, st, ex):
    ktc, krc, _, kte, kre, _ = k
    s = teeth * depth / (2.0 * math.pi)

    def fx(p):
        return (feed / 4.0) * (ktc * math.cos(2 * p) - krc * (2 * p - math.sin(2 * p))) + (
            -kte * math.sin(p) + kre * math.cos(p))

    def fy(p):
        return (feed / 4.0) * (ktc * (2 * p - math.sin(2 * p)) + krc * math.cos(2 * p)) - (
            kte * math.cos(p) + kre * math.sin(p))

    return s * (fx(ex) - fx(st)), s * (fy(ex) - fy(st))


def mill_reference():
    """Paper 001's presets (src/plant/presets/definitions.rs): a Ø10 mm 4-flute end mill, down milling 3 mm
    wide, 3000 rpm, 900 mm/min, hardened tool steel; depth 1, 2 and 4 mm."""
    tool_steel = (3600.0, 1500.0, 750.0, 45.0, 60.0, 5.0)
    diameter, teeth, width, rpm, feed = 10.0, 4, 3.0, 3000.0, 900.0
    swept = math.acos(1.0 - 2.0 * width / diameter)
    st, ex = math.pi - swept, math.pi
    out = {}
    for name, depth in [("maneerat-doc-1", 1.0), ("maneerat-doc-2", 2.0)]:
        fx, fy = mean_forces_xy(teeth, depth, feed / (teeth * rpm), tool_steel, st, ex)
        resultant = math.hypot(fx, fy)
        out[name] = {
            "force_at_full_override_n": resultant,
            "target_n": TARGET_FRACTION * resultant,
        }
    return out


def main():
    os.makedirs(OUT, exist_ok=True)
    write_log()
    reference = {"log": log_reference(), "mills": mill_reference()}
    with open(os.path.join(OUT, "teach_in.json"), "w") as fh:
        json.dump(reference, fh, indent=2)
        fh.write("\n")


if __name__ == "__main__":
    main()
