#!/usr/bin/env python3
"""Reference values for cutlab's fuzzy engine, from tools cutlab did not write.

tests/reference/fuzzy/reference.json: paper 002's own engine, seven triangular sets on [-6, 6]
for E, EC and U, with
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

tests/reference/fuzzy/engines.json: engines beyond paper 002's own. Each is defined once, below,
as plain data; from it the script writes the FLL text (stored with every case, so tests/fuzzy.rs
builds cutlab's engine through cutlab's FLL parser from exactly the text fuzzylite read) and
builds the scikit-fuzzy and numpy inference:
  (a) paper 002's engine with AND = algebraic product (the conjunction) and implication = min,
      both tables, on reference.json's points; and with product for both, dynamics table;
  (b) "shapes": inputs and output made of trapezoids, shoulders (fuzzylite's Ramp) and triangles,
      two rules weighted; min/min and product/product;
  (c) "two-outputs": one rule base concluding on two outputs at once, a feed change on [-6, 6]
      (seven triangles) and a spindle-speed change on [-1, 1] (two shoulders and a triangle).
References for each: fuzzylite's Centroid and (for implication = min) MeanOfMaximum,
scikit-fuzzy's centroid (trapmf for trapezoids; a shoulder is a trapmf whose plateau runs past
the universe's end), and eq 7 with numpy (a term stands for its peak, the middle of its plateau
or the end of its shoulder, as in cutlab). Every tool runs at its finest practical resolution:
the finest grid at which it still gets more accurate. The aggregate is piecewise linear, so a
tool's discretisation error comes only from the cells holding a kink and falls as h^2, while
the worst-case rounding of its running sums grows as n*eps; the two cross near
  * fuzzylite: resolution 10^6 (as for reference.json; 10^7 would also take half a minute per
    output for 67 points);
  * scikit-fuzzy: a universe sampled every 1e-5 (its centroid is a Python loop: about a second
    per evaluation at this step, ten at the next).
Beside the outputs the script records what tests/fuzzy.rs derives its tolerances from, per
engine and output: the largest total change of slope of the aggregate and the smallest aggregate
area over the points (both measured on scikit-fuzzy's sampled aggregate), the gentlest slope of
an output term's edge, and the points where the aggregate's maximum lies on separate intervals.

Run from the repository root:  python3 scripts/reference/fuzzy_reference.py [paper] [engines]
(without an argument it writes both files; `paper` takes about a minute, `engines` about eight).
Needs: apt-get install fuzzylite;  pip install scikit-fuzzy networkx packaging numpy
Writes tests/reference/fuzzy/reference.json and tests/reference/fuzzy/engines.json.
"""
import json
import os
import subprocess
import sys
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


def paper_points():
    rng = np.random.default_rng(2026)
    points = [(float(e), float(ec)) for e, ec in rng.uniform(-6.5, 6.5, size=(60, 2))]
    points += [(-6.0, -6.0), (6.0, 6.0), (0.0, 0.0), (6.0, -6.0), (-2.0, 3.0), (1.0, 1.0), (-5.5, 0.3)]
    return points


def main_paper():
    points = paper_points()
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


# ---- tests/reference/fuzzy/engines.json: engines beyond paper 002's own ----------------------
#
# An engine is plain data: variables as (name, min, max, [(term, shape, [parameters])]) with
# fuzzylite's shapes (Triangle a b c, Trapezoid a b c d, Ramp start end), rules as
# ([(input, term)], [(output, term)], weight), and the conjunction and implication by fuzzylite's
# names. Inputs are lock-range (clamped into their universe), outputs are not.

FUZZYLITE_RESOLUTION = 1000000
SKFUZZY_STEP = 1e-5


def paper_engine(name, table, conjunction, implication):
    seven = [(n, "Triangle", [a, b, c]) for n, a, b, c in terms()]
    rules = [([("E", NAMES[e]), ("EC", NAMES[ec])], [("U", NAMES[table[e][ec] + 3])], 1.0)
             for e in range(7) for ec in range(7)]
    return {"name": name, "inputs": [("E", -6.0, 6.0, seven), ("EC", -6.0, 6.0, seven)],
            "outputs": [("U", -6.0, 6.0, seven)], "rules": rules,
            "conjunction": conjunction, "implication": implication}


def shapes_engine(name, conjunction, implication):
    load = [("light", "Ramp", [4.0, 1.0]), ("medium", "Trapezoid", [2.0, 4.0, 6.0, 8.0]),
            ("heavy", "Ramp", [6.0, 9.0])]
    trend = [("falling", "Ramp", [0.0, -0.8]), ("steady", "Triangle", [-0.5, 0.0, 0.5]),
             ("rising", "Ramp", [0.0, 0.8])]
    change = [("cut", "Ramp", [-4.0, -9.0]), ("trim", "Trapezoid", [-7.0, -5.0, -3.0, -1.0]),
              ("hold", "Triangle", [-2.0, 0.0, 2.0]), ("raise", "Trapezoid", [1.0, 2.5, 4.0, 6.5]),
              ("push", "Ramp", [4.0, 9.0])]
    table = [("light", "falling", "push", 1.0), ("light", "steady", "raise", 1.0),
             ("light", "rising", "hold", 0.8), ("medium", "falling", "raise", 1.0),
             ("medium", "steady", "hold", 1.0), ("medium", "rising", "trim", 1.0),
             ("heavy", "falling", "trim", 0.6), ("heavy", "steady", "cut", 1.0),
             ("heavy", "rising", "cut", 1.0)]
    rules = [([("load", l), ("trend", t)], [("change", c)], w) for l, t, c, w in table]
    return {"name": name, "inputs": [("load", 0.0, 10.0, load), ("trend", -1.0, 1.0, trend)],
            "outputs": [("change", -10.0, 10.0, change)], "rules": rules,
            "conjunction": conjunction, "implication": implication}


def two_output_engine(name, conjunction, implication):
    five = ["NB", "NS", "ZO", "PS", "PB"]
    inputs = [("NB", "Ramp", [-2.0, -6.0]), ("NS", "Triangle", [-6.0, -3.0, 0.0]),
              ("ZO", "Trapezoid", [-3.0, -1.0, 1.0, 3.0]), ("PS", "Triangle", [0.0, 3.0, 6.0]),
              ("PB", "Ramp", [2.0, 6.0])]
    feed = [(n, "Triangle", [a, b, c]) for n, a, b, c in terms()]
    spindle = [("slower", "Ramp", [0.0, -0.8]), ("keep", "Triangle", [-0.4, 0.0, 0.4]),
               ("faster", "Ramp", [0.0, 0.8])]
    rules = []
    for i in range(5):
        for j in range(5):
            u = NAMES[max(0, min(6, 3 + (i - 2) + (j - 2)))]
            s = "slower" if i <= 1 and j <= 2 else "faster" if i >= 3 and j >= 2 else "keep"
            weight = 0.5 if (i, j) in [(0, 4), (4, 0)] else 1.0
            rules.append(([("E", five[i]), ("EC", five[j])], [("U", u), ("S", s)], weight))
    return {"name": name, "inputs": [("E", -6.0, 6.0, inputs), ("EC", -6.0, 6.0, inputs)],
            "outputs": [("U", -6.0, 6.0, feed), ("S", -1.0, 1.0, spindle)], "rules": rules,
            "conjunction": conjunction, "implication": implication}


def engine_fll(engine, defuzzifier):
    """The FLL text fuzzylite reads and tests/fuzzy.rs parses."""
    resolution = f" {FUZZYLITE_RESOLUTION}" if defuzzifier in ("Centroid", "MeanOfMaximum") else ""
    lines = [f"Engine: {engine['name']}"]
    for name, lo, hi, ts in engine["inputs"]:
        lines += [f"InputVariable: {name}", "  enabled: true", f"  range: {lo!r} {hi!r}",
                  "  lock-range: true"]
        lines += [f"  term: {t} {shape} {' '.join(repr(v) for v in ps)}" for t, shape, ps in ts]
    for name, lo, hi, ts in engine["outputs"]:
        lines += [f"OutputVariable: {name}", "  enabled: true", f"  range: {lo!r} {hi!r}",
                  "  lock-range: false", "  aggregation: Maximum",
                  f"  defuzzifier: {defuzzifier}{resolution}", "  default: 0", "  lock-previous: false"]
        lines += [f"  term: {t} {shape} {' '.join(repr(v) for v in ps)}" for t, shape, ps in ts]
    lines += ["RuleBlock: rules", "  enabled: true", f"  conjunction: {engine['conjunction']}",
              "  disjunction: Maximum", f"  implication: {engine['implication']}", "  activation: General"]
    for antecedents, consequents, weight in engine["rules"]:
        rule = ("if " + " and ".join(f"{v} is {t}" for v, t in antecedents)
                + " then " + " and ".join(f"{v} is {t}" for v, t in consequents))
        lines.append(f"  rule: {rule}" + (f" with {weight!r}" if weight != 1.0 else ""))
    return "\n".join(lines) + "\n"


def fuzzylite_outputs(text, engine, points):
    """Every output at every point, by Debian's fuzzylite CLI."""
    names = [v[0] for v in engine["inputs"]]
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "e.fll")
        data = os.path.join(d, "in.fld")
        with open(path, "w") as f:
            f.write(text)
        with open(data, "w") as f:
            f.write(" ".join(names) + "\n" + "".join(" ".join(repr(x) for x in p) + "\n" for p in points))
        out = subprocess.run(["fuzzylite", "-i", path, "-of", "fld", "-d", data, "-decimals", "12"],
                             check=True, capture_output=True, text=True).stdout
    rows = [line.split() for line in out.strip().splitlines()[1:]]
    return [[float(v) for v in r[len(names):]] for r in rows]


def universe(lo, hi, step):
    return np.linspace(lo, hi, int(round((hi - lo) / step)) + 1)


def sampled(shape, ps, x, lo, hi):
    """A term sampled with scikit-fuzzy; a shoulder is a trapezoid whose plateau runs past the
    universe's end."""
    if shape == "Triangle":
        return fuzz.trimf(x, ps)
    if shape == "Trapezoid":
        return fuzz.trapmf(x, ps)
    start, end = ps
    if start < end:
        return fuzz.trapmf(x, [start, end, hi + 1.0, hi + 2.0])
    return fuzz.trapmf(x, [lo - 2.0, lo - 1.0, end, start])


def centre(shape, ps):
    """The value a term stands for in eq 7: the peak, the plateau's middle, the shoulder's end."""
    if shape == "Trapezoid":
        return (ps[1] + ps[2]) / 2.0
    return ps[1]


class Inference:
    """The engine's inference with scikit-fuzzy on universes sampled every `step`."""

    def __init__(self, engine, step):
        self.engine = engine
        self.step = step
        self.inputs = {}
        for name, lo, hi, ts in engine["inputs"]:
            x = universe(lo, hi, step)
            self.inputs[name] = (lo, hi, x, {t: sampled(shape, ps, x, lo, hi) for t, shape, ps in ts})
        self.outputs = {}
        for name, lo, hi, ts in engine["outputs"]:
            x = universe(lo, hi, step)
            self.outputs[name] = (x, {t: sampled(shape, ps, x, lo, hi) for t, shape, ps in ts},
                                  {t: centre(shape, ps) for t, shape, ps in ts})

    def activations(self, point):
        degrees = {}
        for (name, *_), value in zip(self.engine["inputs"], point):
            lo, hi, x, mfs = self.inputs[name]
            v = min(hi, max(lo, value))
            degrees[name] = {t: float(fuzz.interp_membership(x, mf, v)) for t, mf in mfs.items()}
        out = []
        for antecedents, consequents, weight in self.engine["rules"]:
            mus = [degrees[v][t] for v, t in antecedents]
            w = min(mus) if self.engine["conjunction"] == "Minimum" else float(np.prod(mus))
            out.append((weight * w, consequents))
        return out

    def aggregate(self, point, output):
        x, mfs, _ = self.outputs[output]
        agg = np.zeros_like(x)
        for w, consequents in self.activations(point):
            for v, t in consequents:
                if v != output or w <= 0:
                    continue
                implied = np.fmin(w, mfs[t]) if self.engine["implication"] == "Minimum" else w * mfs[t]
                agg = np.fmax(agg, implied)
        return x, agg

    def weighted_average(self, point, output):
        _, _, centres = self.outputs[output]
        num = den = 0.0
        for w, consequents in self.activations(point):
            for v, t in consequents:
                if v == output and w > 0:
                    num += w * centres[t]
                    den += w
        return num / den if den > 0 else 0.0

    def centroid_and_error_terms(self, point, output):
        """scikit-fuzzy's centroid, and what bounds a sampled centroid's error: the aggregate's
        total change of slope (sum of |second differences| / h) and its area; and whether the
        aggregate reaches its maximum on more than one interval."""
        x, agg = self.aggregate(point, output)
        centroid = float(fuzz.defuzz(x, agg, "centroid"))
        slope_change = float(np.sum(np.abs(np.diff(agg, 2)))) / self.step
        area = float(np.sum((agg[1:] + agg[:-1]) * np.diff(x)) / 2.0)
        top = agg >= agg.max() - 1e-9
        runs = int(np.count_nonzero(np.diff(top.astype(int)) == 1)) + (1 if top[0] else 0)
        return centroid, slope_change, area, runs > 1


def gentlest_edge_slope(ts):
    slopes = []
    for _, shape, ps in ts:
        if shape == "Triangle":
            edges = [(ps[0], ps[1]), (ps[1], ps[2])]
        elif shape == "Trapezoid":
            edges = [(ps[0], ps[1]), (ps[2], ps[3])]
        else:
            edges = [(ps[0], ps[1])]
        slopes += [1.0 / abs(b - a) for a, b in edges if a != b]
    return min(slopes)


def engine_points(engine, seed, count=60):
    """Random points over each input's universe widened by 5 % a side (so lock-range clamps some),
    then the four corners and the middle."""
    rng = np.random.default_rng(seed)
    (lo0, hi0), (lo1, hi1) = [(lo, hi) for _, lo, hi, _ in engine["inputs"]]
    points = [[float(lo - 0.05 * (hi - lo) + rng.uniform() * 1.1 * (hi - lo)) for lo, hi in
               [(lo0, hi0), (lo1, hi1)]] for _ in range(count)]
    points += [[lo0, lo1], [hi0, hi1], [lo0, hi1], [hi0, lo1], [(lo0 + hi0) / 2.0, (lo1 + hi1) / 2.0]]
    return points


def reference_engine(engine, points, about):
    outputs = [v[0] for v in engine["outputs"]]
    inference = Inference(engine, SKFUZZY_STEP)
    print(f"{engine['name']}: {len(points)} points", flush=True)
    sk = [[inference.centroid_and_error_terms(p, o) for o in outputs] for p in points]
    cases = []
    for defuzzifier, key in [("Centroid", "centroid"), ("MeanOfMaximum", "mean-of-maximum")]:
        if key == "mean-of-maximum" and engine["implication"] != "Minimum":
            continue
        text = engine_fll(engine, defuzzifier)
        cases.append({"defuzzifier": key, "tool": "fuzzylite 6.0", "resolution": FUZZYLITE_RESOLUTION,
                      "fll": text, "outputs": fuzzylite_outputs(text, engine, points)})
    cases.append({"defuzzifier": "centroid", "tool": f"scikit-fuzzy {fuzz.__version__}",
                  "universe_step": SKFUZZY_STEP, "fll": engine_fll(engine, "Centroid"),
                  "outputs": [[r[0] for r in row] for row in sk]})
    if engine["implication"] == "Minimum":
        cases.append({"defuzzifier": "weighted-average", "tool": "numpy, paper 002 eq 7",
                      "fll": engine_fll(engine, "WeightedAverage"),
                      "outputs": [[inference.weighted_average(p, o) for o in outputs] for p in points]})
    return {
        "name": engine["name"],
        "about": about,
        "inputs": [v[0] for v in engine["inputs"]],
        "outputs": outputs,
        "output_ranges": [[lo, hi] for _, lo, hi, _ in engine["outputs"]],
        "max_slope_change_sum": [max(row[k][1] for row in sk) for k in range(len(outputs))],
        "min_area": [min(row[k][2] for row in sk) for k in range(len(outputs))],
        "gentlest_edge_slope": [gentlest_edge_slope(ts) for _, _, _, ts in engine["outputs"]],
        "separate_maxima": [[i for i, row in enumerate(sk) if row[k][3]] for k in range(len(outputs))],
        "points": points,
        "cases": cases,
    }


def main_engines():
    paper = [list(p) for p in paper_points()]
    shapes = shapes_engine("shapes", "Minimum", "Minimum")
    two = two_output_engine("two-outputs", "Minimum", "Minimum")
    engines = [
        (paper_engine("paper002-experience-product-and", EXPERIENCE, "AlgebraicProduct", "Minimum"),
         paper, "(a) paper 002's engine, experience table, AND = product, implication = min"),
        (paper_engine("paper002-dynamics-product-and", DYNAMICS, "AlgebraicProduct", "Minimum"),
         paper, "(a) paper 002's engine, dynamics table, AND = product, implication = min"),
        (paper_engine("paper002-dynamics-product-and-product", DYNAMICS, "AlgebraicProduct",
                      "AlgebraicProduct"),
         paper, "(a) paper 002's engine, dynamics table, AND = product, implication = product"),
        (shapes, engine_points(shapes, 7),
         "(b) trapezoid, shoulder and triangle terms, weighted rules, AND = min, implication = min"),
        (shapes_engine("shapes-product", "AlgebraicProduct", "AlgebraicProduct"), engine_points(shapes, 7),
         "(b) the same terms and rules, AND = product, implication = product"),
        (two, engine_points(two, 11),
         "(c) one rule base, two outputs (feed change U, spindle-speed change S), AND = min, "
         "implication = min"),
    ]
    out = {
        "generated_by": "scripts/reference/fuzzy_reference.py engines",
        "versions": {"numpy": np.__version__, "scikit-fuzzy": fuzz.__version__, "fuzzylite": "6.0 (Debian)"},
        "engines": [reference_engine(e, points, about) for e, points, about in engines],
    }
    path = os.path.join("tests", "reference", "fuzzy", "engines.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
    print("wrote", path)


def main():
    which = sys.argv[1:] or ["paper", "engines"]
    for name in which:
        {"paper": main_paper, "engines": main_engines}[name]()


if __name__ == "__main__":
    main()
