#!/usr/bin/env python3
"""Reference values for cutlab's plant tests, computed outside the project.

Writes tests/reference/plant/*.csv (see the README there):

* mean_forces.csv   - Altintas' closed-form mean milling forces (Manufacturing Automation, ch. 2)
                      for straight and helical cutters in up, down and slot milling;
* power_law.csv     - paper 004's power law evaluated with its published weights;
* second_order.csv  - step response of paper 001's eq 2.3 as a transfer function
                      k / (m s^2 + (mc + d) s + dc), by scipy.signal.step;
* bond_graph.csv    - paper 002's eq 5 with Table 1, rated voltages from rest, by
                      scipy.integrate.solve_ivp (Radau, rtol 1e-10);
* liu_cut.csv       - liu-current-step's machining centre in steady state: the cut's mean forces,
                      torque and power (Altintas' closed form, chip forces only) at the feed per
                      tooth the spindle actually turns at, the spindle current from the motor's
                      torque and voltage balances, the x-axis current from the screw's, for
                      three depths and two overrides.

Run from the repository root:  python3 scripts/reference/plant_reference.py
Needs numpy and scipy (pip install numpy scipy).
"""

import csv
import math
import os

import numpy as np
from scipy import integrate, signal

OUT = os.path.join("tests", "reference", "plant")

# The helix does not change the mean over whole revolutions; the tests simulate both.
MATERIALS = {
    # name: (Ktc, Krc, Kac, Kte, Kre, Kae), N/mm^2 and N/mm, as in src/plant/materials.rs
    "sm45c": (2200.0, 790.0, 440.0, 35.0, 45.0, 3.0),
    "aluminium": (796.0, 168.8, 222.0, 27.7, 30.8, 1.8),
    "gc30": (1300.0, 550.0, 300.0, 20.0, 30.0, 2.0),
    "tool-steel": (3600.0, 1500.0, 750.0, 45.0, 60.0, 5.0),
}


def immersion(mode, width, diameter):
    """Entry and exit angles (rad), Altintas' convention."""
    ratio = min(width / diameter, 1.0)
    swept = math.acos(1.0 - 2.0 * ratio)
    if mode == "slot" or ratio >= 1.0:
        return 0.0, math.pi
    if mode == "up":
        return 0.0, swept
    return math.pi - swept, math.pi


def mean_forces(teeth, depth, feed, radius, k, st, ex):
    """Altintas ch. 2: average forces per revolution, written out independently."""
    ktc, krc, kac, kte, kre, kae = k
    s = teeth * depth / (2.0 * math.pi)

    def fx(p):
        return (feed / 4.0) * (ktc * math.cos(2 * p) - krc * (2 * p - math.sin(2 * p))) + (
            -kte * math.sin(p) + kre * math.cos(p)
        )

    def fy(p):
        return (feed / 4.0) * (ktc * (2 * p - math.sin(2 * p)) + krc * math.cos(2 * p)) - (
            kte * math.cos(p) + kre * math.sin(p)
        )

    def fz(p):
        return -kac * feed * math.cos(p) + kae * p

    def tq(p):
        return -ktc * feed * math.cos(p) + kte * p

    return (
        s * (fx(ex) - fx(st)),
        s * (fy(ex) - fy(st)),
        s * (fz(ex) - fz(st)),
        s * radius * 1e-3 * (tq(ex) - tq(st)),
    )


def write_mean_forces():
    rows = []
    cases = [
        # diameter, teeth, mode, width, depth, feed per tooth, material
        (20.0, 2, "slot", 20.0, 3.0, 0.10, "sm45c"),
        (20.0, 2, "up", 5.0, 3.0, 0.10, "sm45c"),
        (20.0, 2, "down", 5.0, 3.0, 0.10, "sm45c"),
        (10.0, 4, "down", 3.0, 4.0, 0.05, "tool-steel"),
        (10.0, 4, "up", 3.0, 4.0, 0.05, "tool-steel"),
        (10.0, 3, "slot", 10.0, 2.0, 0.08, "aluminium"),
        (25.0, 4, "up", 12.5, 5.0, 0.06, "gc30"),
        (25.0, 4, "down", 20.0, 5.0, 0.06, "gc30"),
        (16.0, 1, "up", 2.0, 1.5, 0.12, "aluminium"),
        (16.0, 3, "down", 8.0, 6.0, 0.04, "sm45c"),
    ]
    for d, z, mode, w, a, f, mat in cases:
        st, ex = immersion(mode, w, d)
        fx, fy, fz, tq = mean_forces(z, a, f, d / 2.0, MATERIALS[mat], st, ex)
        rows.append([d, z, mode, w, a, f, mat, st, ex, fx, fy, fz, tq])
    with open(os.path.join(OUT, "mean_forces.csv"), "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(
            [
                "diameter_mm", "teeth", "mode", "width_mm", "depth_mm", "feed_per_tooth_mm",
                "material", "entry_rad", "exit_rad", "mean_fx_n", "mean_fy_n", "mean_fz_n",
                "mean_torque_nm",
            ]
        )
        for r in rows:
            out.writerow([repr(v) if isinstance(v, float) else v for v in r])


# Paper 004's published weights (rows x, y, z; columns in the printed order a_e, f, a_p, d, z_e)
# and biases, as in src/plant/power_law.rs.
POWER_LAW = {
    "carbon-steel": (
        [[1.103, 0.747, 1.002, 0.997, -1.299],
         [1.098, 0.748, 0.997, 1.006, -1.299],
         [1.100, 0.751, 0.995, 1.004, -1.301]],
        [316.91, 814.92, 452.73],
    ),
    "cast-iron": (
        [[1.003, 0.737, 0.902, 0.997, -0.999],
         [0.998, 0.738, 0.897, 1.006, -0.999],
         [1.000, 0.741, 0.895, 1.004, -1.001]],
        [185.41, 476.77, 264.87],
    ),
}


def write_power_law():
    weights = POWER_LAW
    inputs = [
        (5.0, 0.08, 1.5, 20.0, 0.7),
        (10.0, 0.1, 2.0, 20.0, 1.0),
        (2.0, 0.05, 0.5, 20.0, 0.4),
        (20.0, 0.12, 3.0, 20.0, 1.0),
    ]
    with open(os.path.join(OUT, "power_law.csv"), "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(
            ["material", "ae_mm", "f_mm", "ap_mm", "d_mm", "ze", "fx_n", "fy_n", "fz_n"]
        )
        for mat, (w, b) in weights.items():
            for p in inputs:
                f = [b[k] * np.prod([p[i] ** w[k][i] for i in range(5)]) for k in range(3)]
                out.writerow([mat, *p, *[repr(float(v)) for v in f]])


def write_second_order():
    tau_f, tau_c, gain, step = 1.0 / 30.0, 0.02, 0.35, 600.0
    m, d = tau_f, 1.0
    c = 1.0 / tau_c
    k = gain * c * d
    system = signal.TransferFunction([k], [m, m * c + d, d * c])
    t = np.arange(0, 201) * 1e-3
    _, y = signal.step(system, T=t)
    with open(os.path.join(OUT, "second_order.csv"), "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["# tau_f_s", tau_f, "tau_c_s", tau_c, "gain_n_per_mm_min", gain,
                      "step_mm_min", step])
        out.writerow(["time_s", "force_n"])
        for ti, yi in zip(t, y * step):
            out.writerow([repr(float(ti)), repr(float(yi))])


def write_bond_graph():
    se1, se2 = 380.0, 220.0
    r1, r2 = 0.132, 0.15
    l1, l2 = 0.088, 0.085
    rs, rx = 9.68, 0.0561
    j1, j2 = 0.0048, 0.0063
    ms, mx = 0.021, 0.014
    kl, mass, cz = 37e6, 1100.0, 18e3

    def rhs(_t, x):
        p3, p6, p11, p14, q17, p20 = x
        return [
            se1 - r1 / l1 * p3 - rs / j1 * p6,
            rs / l1 * p3 - ms * kl * q17,
            se2 - r2 / l2 * p11 - rx / j2 * p14,
            rx / l2 * p11 - mx * kl * q17,
            ms / j1 * p6 + mx / j2 * p14 - p20 / mass,
            kl * q17 - cz / mass * p20,
        ]

    t = np.arange(0, 601) * 0.01
    sol = integrate.solve_ivp(rhs, (0.0, 6.0), [0.0] * 6, method="Radau", t_eval=t,
                              rtol=1e-10, atol=1e-12, max_step=1e-3)
    with open(os.path.join(OUT, "bond_graph.csv"), "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["time_s", "spindle_current_a", "feed_current_a", "table_velocity_m_s",
                      "contact_force_n"])
        for i, ti in enumerate(sol.t):
            x = sol.y[:, i]
            out.writerow([repr(float(ti)), repr(float(x[0] / l1)), repr(float(x[2] / l2)),
                          repr(float(x[5] / mass)), repr(float(kl * x[4]))])


def write_liu_cut():
    """liu-current-step's steady states, from the balances written out by hand (not from eq 5's
    matrix): the DC spindle motor S_e1 = R_s1*i + r_s*w with r_s*i = b_s*w + T_cut(f_z), the
    feed per tooth f_z = v / (z * n) at the speed n it turns at (solved by fixed point, the force
    falling as the spindle droops), and the x axis r_x*i_x = m_x*(C_z*v + F_feed)."""
    # The machine (src/plant/bond_graph.rs, BondGraphParams::machining_centre and paper_002).
    se1, r1, ks, bs = 380.0, 0.132, 2.4, 0.03
    rx, mx, cz = 1.2, 0.01 / (2.0 * math.pi), 18e3
    i_ref, feed_ref = 25.0, 1500.0
    # The cut (BondGraphCut::paper_002): a 50 mm 5-insert face mill climb milling SM45C 40 mm
    # wide, shearing coefficients only.
    d, z, width, mode = 50.0, 5, 40.0, "down"
    ktc, krc, kac = MATERIALS["sm45c"][:3]
    k = (ktc, krc, kac, 0.0, 0.0, 0.0)
    st, ex = immersion(mode, width, d)

    def forces(depth, fz):
        fx, fy, _, tq = mean_forces(z, depth, fz, d / 2.0, k, st, ex)
        return fx, fy, tq

    # The depth at which the spindle draws I_ref at the programmed feed.
    w_ref = (se1 - r1 * i_ref) / ks
    n_ref = w_ref * 60.0 / (2.0 * math.pi)
    torque_per_mm = forces(1.0, feed_ref / (z * n_ref))[2]
    depth_ref = (ks * i_ref - bs * w_ref) / torque_per_mm

    rows = []
    for step_pct in (0.0, 40.0, 100.0):
        depth = depth_ref * (1.0 + step_pct / 100.0)
        for override_pct in (100.0, 50.0):
            feed = feed_ref * override_pct / 100.0
            w = w_ref
            for _ in range(200):
                fz = feed / (z * w * 60.0 / (2.0 * math.pi))
                torque = forces(depth, fz)[2]
                i_s = (bs * w + torque) / ks
                w_next = (se1 - r1 * i_s) / ks
                if abs(w_next - w) < 1e-13:
                    break
                w = w_next
            n = w * 60.0 / (2.0 * math.pi)
            fz = feed / (z * n)
            fx, fy, torque = forces(depth, fz)
            v = feed / 60e3
            screw = cz * v - fx
            i_x = mx * screw / rx
            rows.append([step_pct, override_pct, feed, depth, n, fz, fx, fy, math.hypot(fx, fy),
                         torque, torque * w, (bs * w + torque) / ks, i_x, screw,
                         depth * width * feed / 60.0])
    with open(os.path.join(OUT, "liu_cut.csv"), "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["load_step_pct", "override_pct", "feed_mm_min", "depth_mm", "spindle_rpm",
                      "feed_per_tooth_mm", "mean_fx_n", "mean_fy_n", "mean_resultant_n",
                      "cutting_torque_nm", "cutting_power_w", "spindle_current_a",
                      "feed_current_a", "screw_force_n", "removal_mm3_s"])
        for r in rows:
            out.writerow([repr(float(v)) for v in r])


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    write_mean_forces()
    write_power_law()
    write_second_order()
    write_bond_graph()
    write_liu_cut()
    print("wrote", ", ".join(sorted(os.listdir(OUT))))
