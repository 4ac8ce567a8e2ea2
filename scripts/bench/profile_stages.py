#!/usr/bin/env python3
"""Where the closed loop's time goes, by stage (issue 28): summarises a native `perf record` or a
node `--cpu-prof` profile.

Natively the whole per-sample path is inlined into a few functions (`step_block`,
`OnMachine::advance`), so `perf report --sort symbol` shows little. This attributes each sample
to the innermost *cutlab* source file of its inlined call stack (addr2line -i on a build with line
tables), counting `src/math` and `src/rng.rs` helpers to the file that called them:

    CARGO_PROFILE_RELEASE_DEBUG=line-tables-only cargo build --release --features cli
    perf record -F 5000 -o kim.data -- bash -c 'for i in 1 2 3 4 5; do \\
        target/release/cutlab sim --scenario kim-step-doc --controller fuzzy-dynamics \\
        --no-references >/dev/null; done'
    python3 scripts/bench/profile_stages.py perf kim.data target/release/cutlab

In wasm under node, functions keep their names when the module is not passed through wasm-opt:

    node --cpu-prof --cpu-prof-dir=prof scripts/bench/wasm_loop.mjs target/bench-wasm 3
    python3 scripts/bench/profile_stages.py cpuprof prof/*.cpuprofile

Prints "share  stage" lines, largest first.
"""
import collections
import json
import re
import subprocess
import sys


def perf_stages(data, binary):
    out = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym,symoff,dso"],
                         capture_output=True, text=True, check=True).stdout
    symbols = {}
    for line in subprocess.run(["nm", "-C", "--defined-only", binary], capture_output=True,
                               text=True, check=True).stdout.splitlines():
        parts = line.split(" ", 2)
        if len(parts) == 3:
            symbols.setdefault(parts[2], int(parts[0], 16))
    at = collections.Counter()
    for line in out.splitlines():
        m = re.match(r"\s*[0-9a-f]+ (.*)\+0x([0-9a-f]+) \((.*)\)$", line)
        # The program's own samples (not the kernel's, not a shared library's).
        if m and not m.group(3).startswith("[") and ".so" not in m.group(3) and m.group(1) in symbols:
            at[symbols[m.group(1)] + int(m.group(2), 16)] += 1
    addresses = list(at)
    text = subprocess.run(["addr2line", "-a", "-i", "-f", "-C", "-e", binary]
                          + [hex(a) for a in addresses], capture_output=True, text=True,
                          check=True).stdout.splitlines()
    frames, current, i = {}, None, 0
    while i < len(text):
        if text[i].startswith("0x"):
            current = int(text[i], 16)
            frames[current] = []
            i += 1
            continue
        frames[current].append(text[i + 1].split(":")[0])
        i += 2

    def stage(files):
        ours = [f.split("/src/", 1)[1] for f in files if "/src/" in f and "/.cargo/" not in f
                and "/rustc/" not in f]
        for f in ours:
            if not (f.startswith("math/") or f == "rng.rs"):
                return f
        return ours[0] if ours else "(libraries: " + (files[0].rsplit("/", 1)[-1] if files else "?") + ")"

    stages = collections.Counter()
    for address, n in at.items():
        stages[stage(frames.get(address, []))] += n
    return stages


def cpuprof_stages(path):
    profile = json.load(open(path, encoding="utf-8"))
    nodes = {n["id"]: n for n in profile["nodes"]}
    stages = collections.Counter()
    for node_id, n in collections.Counter(profile["samples"]).items():
        frame = nodes[node_id]["callFrame"]
        stages[re.sub(r"::h[0-9a-f]{16}$", "", frame["functionName"] or frame["url"])] += n
    return stages


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "perf":
        stages = perf_stages(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 3 and sys.argv[1] == "cpuprof":
        stages = cpuprof_stages(sys.argv[2])
    else:
        sys.exit("usage: profile_stages.py perf DATA BINARY | cpuprof FILE.cpuprofile")
    total = sum(stages.values())
    print(f"{total} samples")
    for name, n in stages.most_common(25):
        print(f"{100 * n / total:6.2f} %  {name}")


if __name__ == "__main__":
    main()
