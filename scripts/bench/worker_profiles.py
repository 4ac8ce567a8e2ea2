#!/usr/bin/env python3
"""Probes build settings for the computation worker (issue 28): its module's size and the wasm
loop's speed, per variant, without editing Cargo.toml.

  scripts/bench/worker_profiles.py build NAME [--wasm-opt z] [--wasm-opt-param=--converge ...]
                                              [--config 'profile....=...' ...]
  scripts/bench/worker_profiles.py time NAME NAME ... [--rounds 3] [--repeats 3]

`build` compiles the worker (`--bin cutlab-worker`, profile worker-release, feature worker) and
the loop benchmark (`--example bench_loop_wasm`, same profile) with the given `--config` overrides
(cargo's command-line config, which takes precedence over Cargo.toml's profiles), runs wasm-bindgen
and `wasm-opt -O<level>` on each as Trunk 0.21.14 does (the worker: `--target no-modules`, then
`wasm-opt --output=… -O<level>` and the given parameters, as index.html's
`data-wasm-opt-params`), and prints the worker's size raw and gzip -9.
The artefacts go to target/worker-probe/NAME/.

`time` runs scripts/bench/wasm_loop.mjs on each named build in turn, round after round (so the
variants share the machine's load alike), and prints each one's best CPU seconds over all rounds
and its trace digest.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PROBE = os.path.join(ROOT, "target", "worker-probe")
OUT = os.path.join(ROOT, "target", "wasm32-unknown-unknown", "worker-release")


def cargo(args: list[str], config: list[str]) -> None:
    command = ["cargo", "build", "--offline", "-q", "--target", "wasm32-unknown-unknown",
               "--profile", "worker-release"]
    for item in config:
        command += ["--config", item]
    subprocess.run(command + args, cwd=ROOT, check=True)


def gzip9(path: str) -> int:
    """The size of `gzip -9 -c` of the file, as scripts/wasm-size counts it (the header holds the
    file's name; Python's zlib would give a different count)."""
    return len(subprocess.run(["gzip", "-9", "-c", path], check=True, capture_output=True).stdout)


def build(name: str, level: str, params: list[str], config: list[str]) -> dict:
    out = os.path.join(PROBE, name)
    shutil.rmtree(out, ignore_errors=True)
    worker_dir, bench_dir = os.path.join(out, "worker"), os.path.join(out, "bench")
    cargo(["--bin", "cutlab-worker", "--no-default-features", "--features", "worker"], config)
    subprocess.run(["wasm-bindgen", "--target=no-modules", f"--out-dir={worker_dir}",
                    "--out-name=cutlab-worker", os.path.join(OUT, "cutlab-worker.wasm")], check=True)
    worker = os.path.join(worker_dir, "cutlab-worker_bg.wasm")
    subprocess.run(["wasm-opt", f"--output={worker}", f"-O{level}", worker, *params], check=True)
    cargo(["--example", "bench_loop_wasm"], config)
    subprocess.run(["wasm-bindgen", "--target", "nodejs", "--out-dir", bench_dir,
                    os.path.join(OUT, "examples", "bench_loop_wasm.wasm")], check=True)
    bench = os.path.join(bench_dir, "bench_loop_wasm_bg.wasm")
    subprocess.run(["wasm-opt", f"-O{level}", *params, bench, "-o", bench], check=True)
    result = {"name": name, "wasm_opt": level, "wasm_opt_params": params, "config": config,
              "raw_b": os.path.getsize(worker), "gzip9_b": gzip9(worker),
              "bench_raw_b": os.path.getsize(bench)}
    with open(os.path.join(out, "size.json"), "w") as f:
        json.dump(result, f)
    return result


def time_round(name: str, repeats: int) -> dict:
    out = subprocess.run(
        ["node", os.path.join(ROOT, "scripts", "bench", "wasm_loop.mjs"),
         os.path.join(PROBE, name, "bench"), str(repeats)],
        check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    b = sub.add_parser("build")
    b.add_argument("name")
    b.add_argument("--wasm-opt", default="z")
    b.add_argument("--wasm-opt-param", action="append", default=[])
    b.add_argument("--config", action="append", default=[])
    t = sub.add_parser("time")
    t.add_argument("names", nargs="+")
    t.add_argument("--rounds", type=int, default=3)
    t.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    if args.command == "build":
        print(json.dumps(build(args.name, args.wasm_opt, args.wasm_opt_param, args.config)))
        return
    best: dict[str, float] = {}
    digests: dict[str, set] = {}
    for r in range(args.rounds):
        for name in args.names:
            data = time_round(name, args.repeats)
            best[name] = min(best.get(name, float("inf")), data["cpu_s"])
            digests.setdefault(name, set()).add(data["digest"])
            print(f"round {r + 1} {name}: cpu {data['cpu_s']:.3f} s, simulated "
                  f"{data['simulated_s']:.3f} s, load {os.getloadavg()[0]:.2f}", file=sys.stderr)
    for name in args.names:
        with open(os.path.join(PROBE, name, "size.json")) as f:
            size = json.load(f)
        print(json.dumps({**size, "cpu_s_best": best[name], "digests": sorted(digests[name])}))


if __name__ == "__main__":
    main()
