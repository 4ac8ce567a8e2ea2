#!/usr/bin/env python3
"""Reference values for cutlab's fuzzy engine, from tools cutlab did not write.

Engines: paper 002's seven triangular sets on [-6, 6] for E, EC and U, with
  * the experience-based table (MacVicar-Whelan: U = sat(E + EC) in levels), and
  * the dynamics-based table (paper 002 Table 4 with the seventh printed entry of every row
    dropped; see docs/fuzzy.md),
AND = min, implication = min (and product for one case), aggregation = max.

References:
  * fuzzylite 6 (Debian's `fuzzylite` CLI): Centroid and MeanOfMaximum at resolution 10^6,
    from FLL files this script writes itself;
  * scikit-fuzzy: the same inference built from skfuzzy.trimf / interp_membership and
    skfuzzy.defuzz(..., 'centroid') on a universe sampled every 1e-4 (120 001 points);
  * paper 002 eq 7 (weighted average) computed directly with numpy.

Run from the repository root:  python3 scripts/reference/fuzzy_reference.py
Needs: apt-get install fuzzylite;  pip install scikit-fuzzy networkx packaging numpy
Writes tests/reference/fuzzy/reference.json.
"""
import json
import os
import subprocess
import tempfile

import numpy as np
import skfuzzy as fuzz

NAMES = ["NB", "NM", "NS", "ZO", "PS", "PM", "PB"]
TABLE_4_AS_PRINTED = [
    [-3, -3, -3, -2, -2, -1, -1, -1],
    [-3, -3, -2, -2, -1, 0, 1, 1],
    [-3, -2, -2, -1, 0, 1, 1, 2],
    [-2, -2, -1, 0, 1, 1, 1, 2],
    [-2, -1, 0, 1, 1, 2, 2, 2],
    [-1, 0, 1, 1, 1, 2, 2, 2],
    [0, 1, 1, 1, 1, 2, 2, 3],
]
DYNAMICS = [row[:6] + row[7:] for row in TABLE_4_AS_PRINTED]
EXPERIENCE = [[max(-3, min(3, (e - 3) + (ec - 3))) for ec in range(7)] for e in range(7)]


def terms():
    out = []
    for i in range(7):
        peak = 2.0 * (i - 3)
        out.append((NAMES[i], max(peak - 2, -6.0), peak, min(peak + 2, 6.0)))
    return out


def fll(table, defuzzifier, implication="Minimum"):
    lines = ["Engine: reference"]
    for var in ["E", "EC"]:
        lines += [f"InputVariable: {var}", "  enabled: true", "  range: -6 6", "  lock-range: true"]
        lines += [f"  term: {n} Triangle {a} {b} {c}" for n, a, b, c in terms()]
    lines += ["OutputVariable: U", "  enabled: true", "  range: -6 6", "  lock-range: false",
              "  aggregation: Maximum", f"  defuzzifier: {defuzzifier} 1000000", "  default: 0",
              "  lock-previous: false"]
    lines += [f"  term: {n} Triangle {a} {b} {c}" for n, a, b, c in terms()]
    lines += ["RuleBlock: rules", "  enabled: true", "  conjunction: Minimum",
              "  disjunction: Maximum", f"  implication: {implication}", "  activation: General"]
    for e in range(7):
        for ec in range(7):
            lines.append(f"  rule: if E is {NAMES[e]} and EC is {NAMES[ec]} then U is {NAMES[table[e][ec] + 3]}")
    return "\n".join(lines) + "\n"


def fuzzylite(table, defuzzifier, points, implication="Minimum"):
    with tempfile.TemporaryDirectory() as d:
        engine = os.path.join(d, "e.fll")
        data = os.path.join(d, "in.fld")
        with open(engine, "w") as f:
            f.write(fll(table, defuzzifier, implication))
        with open(data, "w") as f:
            f.write("E EC\n" + "".join(f"{e!r} {ec!r}\n" for e, ec in points))
        out = subprocess.run(["fuzzylite", "-i", engine, "-of", "fld", "-d", data, "-decimals", "12"],
                             check=True, capture_output=True, text=True).stdout
    rows = [l.split() for l in out.strip().splitlines()[1:]]
    return [float(r[2]) for r in rows]


UNIVERSE = np.linspace(-6.0, 6.0, 120001)


def degrees(x, table_terms):
    x = min(6.0, max(-6.0, x))
    return [float(fuzz.interp_membership(UNIVERSE, fuzz.trimf(UNIVERSE, [a, b, c]), x))
            for _, a, b, c in table_terms]


def skfuzzy_centroid(table, e, ec, implication="min"):
    t = terms()
    de, dec = degrees(e, t), degrees(ec, t)
    agg = np.zeros_like(UNIVERSE)
    for i in range(7):
        for j in range(7):
            w = min(de[i], dec[j])
            if w <= 0:
                continue
            _, a, b, c = t[table[i][j] + 3]
            mf = fuzz.trimf(UNIVERSE, [a, b, c])
            implied = np.fmin(w, mf) if implication == "min" else w * mf
            agg = np.fmax(agg, implied)
    return float(fuzz.defuzz(UNIVERSE, agg, "centroid"))


def weighted_average(table, e, ec):
    t = terms()
    de, dec = degrees(e, t), degrees(ec, t)
    num = den = 0.0
    for i in range(7):
        for j in range(7):
            w = min(de[i], dec[j])
            num += w * t[table[i][j] + 3][2]
            den += w
    return num / den if den > 0 else 0.0


def main():
    rng = np.random.default_rng(2026)
    points = [(float(e), float(ec)) for e, ec in rng.uniform(-6.5, 6.5, size=(60, 2))]
    points += [(-6.0, -6.0), (6.0, 6.0), (0.0, 0.0), (6.0, -6.0), (-2.0, 3.0), (1.0, 1.0), (-5.5, 0.3)]
    cases = []
    for name, table in [("experience", EXPERIENCE), ("dynamics", DYNAMICS)]:
        cases.append({"rules": name, "defuzzifier": "centroid", "implication": "minimum", "tool": "fuzzylite 6.0",
                      "outputs": fuzzylite(table, "Centroid", points)})
        cases.append({"rules": name, "defuzzifier": "centroid", "implication": "minimum",
                      "tool": f"scikit-fuzzy {fuzz.__version__}",
                      "outputs": [skfuzzy_centroid(table, e, ec) for e, ec in points]})
        cases.append({"rules": name, "defuzzifier": "mean-of-maximum", "implication": "minimum",
                      "tool": "fuzzylite 6.0", "outputs": fuzzylite(table, "MeanOfMaximum", points)})
        cases.append({"rules": name, "defuzzifier": "weighted-average", "implication": "minimum",
                      "tool": "numpy, paper 002 eq 7", "outputs": [weighted_average(table, e, ec) for e, ec in points]})
    cases.append({"rules": "dynamics", "defuzzifier": "centroid", "implication": "product",
                  "tool": "fuzzylite 6.0", "outputs": fuzzylite(DYNAMICS, "Centroid", points, "AlgebraicProduct")})
    cases.append({"rules": "dynamics", "defuzzifier": "centroid", "implication": "product",
                  "tool": f"scikit-fuzzy {fuzz.__version__}",
                  "outputs": [skfuzzy_centroid(DYNAMICS, e, ec, "product") for e, ec in points]})
    out = {
        "generated_by": "scripts/reference/fuzzy_reference.py",
        "versions": {"numpy": np.__version__, "scikit-fuzzy": fuzz.__version__, "fuzzylite": "6.0 (Debian)"},
        "skfuzzy_universe_step": 1e-4,
        "fuzzylite_resolution": 1000000,
        "points": points,
        "cases": cases,
    }
    path = os.path.join("tests", "reference", "fuzzy", "reference.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
    print("wrote", path)


if __name__ == "__main__":
    main()
