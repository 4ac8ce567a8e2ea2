#!/usr/bin/env python3
"""Fuzzy engine throughput, cutlab vs scikit-fuzzy and fuzzylite, measured side by side in one run.

    python3 scripts/bench/fuzzy_engine.py [--grid 100] [--rounds 3] [--skfuzzy-points 100]
        [--skfuzzy-blocks-points 1000] [--no-install]

The engine is paper 002's, with the dynamics-based rules: seven triangular sets on [-6, 6] for
E, EC and U, 49 rules, AND = min, implication = min, aggregation = max, centroid. Every tool
reads it from the same FLL text, www/data/paper-002-dynamics.fll (what `cutlab fuzzy export
--rules dynamics` writes), or builds it from the same numbers:

  cutlab       the release build of examples/bench_fuzzy.rs: cutlab's FLL parser, then
               Engine::evaluate once per point, timed in memory. Its centroid is exact (the
               aggregate is integrated piece by piece in closed form): no resolution.
  fuzzylite    Debian's `fuzzylite` 6.0 CLI, timed by its own `fuzzylite benchmark ENGINE.fll
               POINTS.fld RUNS` (C++, the engine's process() per point, timed inside the process;
               no file I/O in the timing), at two centroid resolutions: 100, the FLL's own
               (fuzzylite's default), and 1,000 (a step of 0.012, like scikit-fuzzy's below).
               Outputs from `fuzzylite -i ENGINE.fll -of fld -d POINTS.fld`.
  scikit-fuzzy 0.5, on a universe sampled every 0.01 (1,201 points; a resolution its users
               commonly pick, a step like fuzzylite's at 1,000), two ways:
                 ControlSystem  the library's engine (skfuzzy.control: Antecedent, Consequent,
                                Rule, ControlSystemSimulation with cache=False, so a round does
                                not return stored answers), min/min/max and centroid, its
                                defaults;
                 building blocks the inference written with its functions (trimf,
                                interp_membership, numpy fmin/fmax, defuzz 'centroid'), as
                                scripts/reference/fuzzy_reference.py builds its references.
               Both are slow in Python (tens of ms and about a millisecond per evaluation), so
               they run on a seeded random subset of the grid (--skfuzzy-points,
               --skfuzzy-blocks-points); the rate is evaluations per second all the same.

The points are the --grid N × N lattice on [-6, 6]² (E varying slowest), written once and read
by every tool. Rounds alternate the tools so they all see the same machine load; each keeps its
best round. Prints a Markdown table for docs/benchmarks.md ("## Fuzzy engine") and checks the
outputs agree with cutlab's exact centroid within a resolution-limited tolerance: a sampled
centroid of a piecewise-linear aggregate errs where a cell holds a kink, so its error falls as
the square of the step h; the tolerance is h² (0.0144 for fuzzylite at 100, 1.44e-4 at 1,000,
1e-4 for scikit-fuzzy at 0.01), several times the largest error seen.

Installs what is missing, once: `pip install scikit-fuzzy networkx packaging` and
`apt-get install -y fuzzylite` (as root; skipped with --no-install). A peer that still cannot be
found is reported as such and the others are still timed.
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from machine import cpus, load_average, rustc_version

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
FLL = os.path.join(ROOT, "www", "data", "paper-002-dynamics.fll")
NAMES = ["NB", "NM", "NS", "ZO", "PS", "PM", "PB"]
FUZZYLITE_RESOLUTIONS = (100, 1000)
SKFUZZY_STEP = 0.01


def log(message):
    print(message, file=sys.stderr, flush=True)


# ---- installing the peers, idempotently ----------------------------------------------------

def ensure_skfuzzy(install):
    try:
        import skfuzzy  # noqa: F401
        from skfuzzy import control  # noqa: F401
        return None
    except ImportError as err:
        missing = str(err)
    if install:
        log(f"scikit-fuzzy missing ({missing}): pip install scikit-fuzzy networkx packaging")
        done = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet",
                               "scikit-fuzzy", "networkx", "packaging"])
        if done.returncode == 0:
            try:
                import skfuzzy  # noqa: F401
                from skfuzzy import control  # noqa: F401
                return None
            except ImportError as err:
                missing = str(err)
    return f"scikit-fuzzy not available ({missing})"


def ensure_fuzzylite(install):
    if shutil.which("fuzzylite"):
        return None
    if install and shutil.which("apt-get") and os.geteuid() == 0:
        log("fuzzylite missing: apt-get install -y fuzzylite")
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        if subprocess.run(["apt-get", "install", "-y", "fuzzylite"], **quiet).returncode != 0:
            subprocess.run(["apt-get", "update"], **quiet)
            subprocess.run(["apt-get", "install", "-y", "fuzzylite"], **quiet)
    if shutil.which("fuzzylite"):
        return None
    return "fuzzylite not available (Debian package `fuzzylite`: apt-get install -y fuzzylite, as root)"


# ---- the engine, read from the FLL file ------------------------------------------------------

def read_fll(text):
    """The terms and rules of a two-input, one-output FLL engine of triangles."""
    terms, rules = {}, []
    variable = None
    for line in text.splitlines():
        key, _, value = line.strip().partition(": ")
        if key in ("InputVariable", "OutputVariable"):
            variable = value
            terms[variable] = {}
        elif key == "term":
            name, shape, *params = value.split()
            if shape != "Triangle":
                sys.exit(f"{FLL}: term {name} is a {shape}; this benchmark reads triangles only")
            terms[variable][name] = [float(p) for p in params]
        elif key == "rule":
            words = value.split()  # if E is A and EC is B then U is C
            rules.append((words[3], words[7], words[11]))
    return terms, rules


def with_resolution(text, resolution):
    lines = []
    for line in text.splitlines():
        if line.strip().startswith("defuzzifier: Centroid"):
            line = f"  defuzzifier: Centroid {resolution}"
        lines.append(line)
    return "\n".join(lines) + "\n"


# ---- the tools -------------------------------------------------------------------------------

def cutlab(binary, points_path, repeats, output=None):
    cmd = [binary, "--fll", FLL, "--points", points_path, "--repeats", str(repeats)]
    if output:
        cmd += ["--output", output]
    done = subprocess.run(cmd, check=True, capture_output=True, text=True, cwd=ROOT)
    return json.loads(done.stdout)


def fuzzylite_rate(fll_path, fld_path, runs, tmp):
    """Evaluations per second of fuzzylite's best run, timed by fuzzylite itself."""
    tsv = os.path.join(tmp, "fuzzylite-benchmark.tsv")
    subprocess.run(["fuzzylite", "benchmark", fll_path, fld_path, str(runs), tsv],
                   check=True, capture_output=True, text=True)
    with open(tsv) as fh:
        values = [line.rstrip("\n").split("\t") for line in fh if line.strip()][1]
    # library name inputs outputs ruleBlocks rules runs evaluations, then (the data file holding
    # no expected outputs, the error columns are left out) units sum(t) mean(t) sd(t) t1 … tN.
    if "nanoseconds" not in values:
        raise RuntimeError(f"unexpected `fuzzylite benchmark` output: {values}")
    units = values.index("nanoseconds")
    evaluations = int(values[7])
    times_ns = [float(v) for v in values[units + 4:units + 4 + runs]]
    return evaluations / (min(times_ns) * 1e-9)


def fuzzylite_outputs(fll_path, fld_path):
    out = subprocess.run(["fuzzylite", "-i", fll_path, "-of", "fld", "-d", fld_path,
                          "-decimals", "12"], check=True, capture_output=True, text=True).stdout
    rows = [line.split() for line in out.strip().splitlines()[1:]]
    return np.array([float(r[2]) for r in rows])


class SkfuzzyControlSystem:
    """scikit-fuzzy's own engine, skfuzzy.control."""

    def __init__(self, terms, rules):
        import skfuzzy as fuzz
        from skfuzzy import control as ctrl
        u = np.linspace(-6.0, 6.0, int(round(12.0 / SKFUZZY_STEP)) + 1)
        variables = {"E": ctrl.Antecedent(u, "E"), "EC": ctrl.Antecedent(u, "EC"),
                     "U": ctrl.Consequent(u, "U")}
        for name, variable in variables.items():
            for term, abc in terms[name].items():
                variable[term] = fuzz.trimf(u, abc)
        system = ctrl.ControlSystem([
            ctrl.Rule(variables["E"][a] & variables["EC"][b], variables["U"][c])
            for a, b, c in rules])
        self.sim = ctrl.ControlSystemSimulation(system, cache=False)

    def __call__(self, e, ec):
        self.sim.input["E"] = e
        self.sim.input["EC"] = ec
        self.sim.compute()
        return self.sim.output["U"]


class SkfuzzyBlocks:
    """The same inference from scikit-fuzzy's functions (scripts/reference/fuzzy_reference.py)."""

    def __init__(self, terms, rules):
        import skfuzzy as fuzz
        self.fuzz = fuzz
        self.u = np.linspace(-6.0, 6.0, int(round(12.0 / SKFUZZY_STEP)) + 1)
        self.mf = {v: {t: fuzz.trimf(self.u, abc) for t, abc in ts.items()}
                   for v, ts in terms.items()}
        self.rules = rules

    def __call__(self, e, ec):
        fuzz, u = self.fuzz, self.u
        de = {t: fuzz.interp_membership(u, m, e) for t, m in self.mf["E"].items()}
        dec = {t: fuzz.interp_membership(u, m, ec) for t, m in self.mf["EC"].items()}
        aggregate = np.zeros_like(u)
        for a, b, c in self.rules:
            w = min(de[a], dec[b])
            if w > 0:
                aggregate = np.fmax(aggregate, np.fmin(w, self.mf["U"][c]))
        return float(fuzz.defuzz(u, aggregate, "centroid"))


def timed_rate(evaluate, points):
    out = np.empty(len(points))
    t = time.perf_counter()
    for k, (e, ec) in enumerate(points):
        out[k] = evaluate(e, ec)
    return len(points) / (time.perf_counter() - t), out


def machine():
    return (f"{cpus()}, load average {load_average()}; "
            f"Python {platform.python_version()}, numpy {np.__version__}; {rustc_version()}, release profile")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=100, help="N for the N × N grid of (E, EC)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--skfuzzy-points", type=int, default=100,
                        help="points of the grid scikit-fuzzy's ControlSystem evaluates per round")
    parser.add_argument("--skfuzzy-blocks-points", type=int, default=1000,
                        help="points of the grid the scikit-fuzzy building blocks evaluate per round")
    parser.add_argument("--no-install", action="store_true", help="do not pip/apt-get install peers")
    args = parser.parse_args()
    if args.grid < 2 or args.rounds < 1:
        sys.exit("--grid must be at least 2 and --rounds at least 1")

    missing = {}
    missing["scikit-fuzzy"] = ensure_skfuzzy(not args.no_install)
    missing["fuzzylite"] = ensure_fuzzylite(not args.no_install)

    subprocess.run(["cargo", "build", "--release", "--example", "bench_fuzzy"], cwd=ROOT, check=True)
    binary = os.path.join(ROOT, "target", "release", "examples", "bench_fuzzy")

    with open(FLL) as fh:
        fll_text = fh.read()
    terms, rules = read_fll(fll_text)
    axis = np.linspace(-6.0, 6.0, args.grid)
    points = np.array([(e, ec) for e in axis for ec in axis])
    n = len(points)
    rng = np.random.default_rng(14)
    subset = {
        "ControlSystem": np.sort(rng.choice(n, size=min(args.skfuzzy_points, n), replace=False)),
        "blocks": np.sort(rng.choice(n, size=min(args.skfuzzy_blocks_points, n), replace=False)),
    }

    skfuzzy = {}
    if missing["scikit-fuzzy"] is None:
        skfuzzy = {"ControlSystem": SkfuzzyControlSystem(terms, rules),
                   "blocks": SkfuzzyBlocks(terms, rules)}
        import skfuzzy as fuzz
        skfuzzy_version = fuzz.__version__

    best, outputs = {}, {}

    def keep_max(key, rate):
        best[key] = max(best.get(key, 0.0), rate)

    with tempfile.TemporaryDirectory() as tmp:
        points_path = os.path.join(tmp, "points.f64")
        points.astype("<f8").tofile(points_path)
        fld_path = os.path.join(tmp, "points.fld")
        with open(fld_path, "w") as fh:
            fh.write("E EC\n" + "".join(f"{e!r} {ec!r}\n" for e, ec in points.tolist()))
        fll_paths = {}
        for resolution in FUZZYLITE_RESOLUTIONS:
            fll_paths[resolution] = os.path.join(tmp, f"engine-{resolution}.fll")
            with open(fll_paths[resolution], "w") as fh:
                fh.write(with_resolution(fll_text, resolution))

        for r in range(args.rounds):
            log(f"round {r + 1}/{args.rounds}")
            keep_max("cutlab", cutlab(binary, points_path, 3)["evaluations_per_s"])
            if missing["fuzzylite"] is None:
                for resolution in FUZZYLITE_RESOLUTIONS:
                    keep_max(f"fuzzylite {resolution}",
                             fuzzylite_rate(fll_paths[resolution], fld_path, 3, tmp))
            for kind, evaluate in skfuzzy.items():
                rate, out = timed_rate(evaluate, points[subset[kind]].tolist())
                keep_max(f"skfuzzy {kind}", rate)
                outputs[f"skfuzzy {kind}"] = out

        cutlab_out_path = os.path.join(tmp, "cutlab.f64")
        info = cutlab(binary, points_path, 1, cutlab_out_path)
        exact = np.fromfile(cutlab_out_path, "<f8")
        if missing["fuzzylite"] is None:
            for resolution in FUZZYLITE_RESOLUTIONS:
                outputs[f"fuzzylite {resolution}"] = fuzzylite_outputs(fll_paths[resolution], fld_path)

    rows = [("cutlab (exact centroid)", "cutlab", None, None, None)]
    if missing["fuzzylite"] is None:
        for resolution in FUZZYLITE_RESOLUTIONS:
            h = 12.0 / resolution
            rows.append((f"fuzzylite 6.0 CLI, Centroid resolution {resolution:,}",
                         f"fuzzylite {resolution}", None, h * h, n))
    if skfuzzy:
        h = SKFUZZY_STEP
        rows.append((f"scikit-fuzzy {skfuzzy_version} ControlSystem, universe step {h}",
                     "skfuzzy ControlSystem", subset["ControlSystem"], h * h, len(subset["ControlSystem"])))
        rows.append((f"scikit-fuzzy {skfuzzy_version} building blocks, universe step {h}",
                     "skfuzzy blocks", subset["blocks"], h * h, len(subset["blocks"])))

    print(f"\nMachine: {machine()}")
    print(f"Engine: {os.path.relpath(FLL, ROOT)} (paper 002, dynamics rules: 7 triangles on [-6, 6] "
          f"for E, EC, U; 49 rules; min/min/max; centroid); {n:,} points on a {args.grid} × "
          f"{args.grid} grid of [-6, 6]²; best of {args.rounds} alternating rounds\n")
    print("| engine | points timed | evaluations/s | cutlab / peer | max \\|peer − cutlab\\| | tolerance (h²) |")
    print("|---|---:|---:|---:|---:|---:|")
    failures = []
    for label, key, idx, tolerance, count in rows:
        if key == "cutlab":
            print(f"| {label} | {n:,} | {best[key]:,.0f} | 1 | — | — |")
            continue
        diff = np.max(np.abs(outputs[key] - (exact if idx is None else exact[idx])))
        ratio = best["cutlab"] / best[key]
        ratio_text = f"{ratio:.1f}" if ratio < 100 else f"{ratio:,.0f}"
        print(f"| {label} | {count:,} | {best[key]:,.0f} | **{ratio_text}×** | {diff:.1e} | {tolerance:.1e} |")
        if not diff <= tolerance:
            failures.append(f"{label}: max |difference| {diff:.3g} > {tolerance:.3g}")
    print(f"\ncutlab checksum (sum of the {n:,} outputs): {info['checksum']!r}; "
          f"first outputs: {info['first_outputs']}")
    for peer, why in missing.items():
        if why:
            print(f"\n**{peer} was not measured:** {why}.")
    if failures:
        sys.exit("outputs disagree: " + "; ".join(failures))


if __name__ == "__main__":
    main()
