#!/usr/bin/env python3
"""Paper 004's power law under each reading of its weight matrix, against the closed-form
mechanistic mean force, on every mill preset's cut.

Paper 004 prints its inputs as p = {a_e, f, a_p, d, z_e}; read so, the force rises with the tool
diameter (d^+1.0) and falls with the teeth (z_e^-1.3). Its eq 1 gives z_e no learned exponent
(z_e to the first power), and the handbooks' milling force formula reads
F = C * a_e^u * f^y * a_p^x * z / d^q with z the cutter's number of teeth. Three readings of the
same published numbers, each evaluated with the biases in newtons for inputs in mm:

* as-printed - columns a_e, f, a_p, d, z_e (z_e the mean number of teeth in the cut);
* swapped    - columns a_e, f, a_p, z_e, d;
* handbook   - columns a_e, f, a_p, z, d (z the cutter's number of teeth).

The cut of each preset is the one the simulator calibrates the power law on: the programmed feed
per tooth, the largest depth and width (src/plant/simulator.rs, power_law_calibration_cut). The
mechanistic force is Altintas' closed-form mean resultant |(F_x, F_y)| over a revolution, from
plant_reference.py.

Writes tests/reference/plant/power_law_readings.csv; tests/plant_mechanics.rs reads it.
Run from the repository root:  python3 scripts/reference/power_law_readings.py
Needs numpy.
"""

import csv
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plant_reference import MATERIALS, OUT, POWER_LAW, immersion, mean_forces  # noqa: E402

# The mill presets' cuts, copies of src/plant/presets/definitions.rs (change both together): name, tool
# diameter (mm), teeth, mode, radial width (mm), spindle (rpm), programmed feed (mm/min), the
# largest depth (mm), the material whose coefficients give the mechanistic force (kim-material-
# taper's composite region takes its SM45C half's, as src/plant/materials.rs does) and the
# published weights the simulator uses for it (cast iron's for GC30, carbon steel's otherwise).
PRESETS = [
    ("kim-step-doc", 20.0, 2, "slot", 20.0, 1000.0, 200.0, 5.0, "sm45c", "carbon-steel"),
    ("kim-material-taper", 20.0, 2, "slot", 20.0, 600.0, 160.0, 4.0, "sm45c", "carbon-steel"),
    ("kim-circular-taper", 20.0, 2, "slot", 20.0, 3000.0, 170.0, 5.0, "sm45c", "carbon-steel"),
    ("maneerat-doc-1", 10.0, 4, "down", 3.0, 3000.0, 900.0, 1.0, "tool-steel", "carbon-steel"),
    ("maneerat-doc-2", 10.0, 4, "down", 3.0, 3000.0, 900.0, 2.0, "tool-steel", "carbon-steel"),
    ("maneerat-doc-4", 10.0, 4, "down", 3.0, 3000.0, 900.0, 4.0, "tool-steel", "carbon-steel"),
]

# The input each column of the weight matrix is the exponent of.
READINGS = {
    "as-printed": ("ae", "f", "ap", "d", "ze"),
    "swapped": ("ae", "f", "ap", "ze", "d"),
    "handbook": ("ae", "f", "ap", "z", "d"),
}


def resultant(material, reading, values):
    weights, bias = POWER_LAW[material]
    p = [values[name] for name in READINGS[reading]]
    f = [bias[k] * np.prod([p[i] ** weights[k][i] for i in range(5)]) for k in range(3)]
    return math.hypot(f[0], f[1])


def main():
    with open(os.path.join(OUT, "power_law_readings.csv"), "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(
            ["preset", "material", "power_law_material", "ae_mm", "f_mm", "ap_mm", "d_mm",
             "ze", "z", "mechanistic_n", *[f"{r}_n" for r in READINGS]]
        )
        for (name, diameter, teeth, mode, width, rpm, feed, depth, material,
             published) in PRESETS:
            entry, exit_ = immersion(mode, width, diameter)
            values = {
                "ae": 0.5 * diameter * (math.cos(entry) - math.cos(exit_)),
                "f": feed / (teeth * rpm),
                "ap": depth,
                "d": diameter,
                "ze": teeth * (exit_ - entry) / (2.0 * math.pi),
                "z": float(teeth),
            }
            fx, fy, _, _ = mean_forces(teeth, depth, values["f"], diameter / 2.0,
                                       MATERIALS[material], entry, exit_)
            forces = [resultant(published, r, values) for r in READINGS]
            out.writerow(
                [name, material, published,
                 *[repr(float(values[k])) for k in ("ae", "f", "ap", "d", "ze", "z")],
                 repr(math.hypot(fx, fy)), *[repr(float(v)) for v in forces]]
            )
            print(name, f"mechanistic {math.hypot(fx, fy):.1f} N;",
                  "; ".join(f"{r} {v:.4g} N (x{v / math.hypot(fx, fy):.3g})"
                            for r, v in zip(READINGS, forces)))


if __name__ == "__main__":
    main()
