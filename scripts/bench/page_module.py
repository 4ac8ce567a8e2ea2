#!/usr/bin/env python3
"""What the page's wasm module holds (issue 28): the cutlab core's code in it by module, and which
page functions call into each module.

Reads a module whose function names are kept: the page binary as cargo leaves it, before
wasm-bindgen and wasm-opt (which drops the names), e.g. after `trunk build --release --offline`:

    python3 scripts/bench/page_module.py target/wasm32-unknown-unknown/web-release/cutlab-web.wasm

Needs `twiggy` on PATH (`cargo install twiggy --locked`). Sizes are the code bytes twiggy reports
(`twiggy top`); wasm-opt -Oz and gzip shrink them further, about in proportion. Callers come
from `twiggy paths`: for each core function of at least --min-bytes, the nearest page functions
(`cutlab::web::…`) on its call paths; "fn table" means it is also reached through the module's
function table (a `dyn` call: a controller's or a machine's `step` behind a trait object), whose
caller twiggy cannot see.
"""

import argparse
import collections
import csv
import io
import json
import re
import subprocess

NON_CODE = ('"', "custom section", "data segment", "export ", "import ", "type[", "elem[",
            "table[", "global[", "memory[")
# Modules shown by their submodule, where one submodule is a different thing (the simulated
# machine against the presets' settings, the fuzzy engine against the registry).
SPLIT = ("plant", "control", "closed_loop", "signal", "estimation")


def core_module(name):
    """The core module a function belongs to, or None for the UI and the dependencies."""
    m = re.search(r"cutlab::(\w+)(?:::(\w+))?", name)
    if not m or m.group(1) in ("web", "charts"):
        return None
    sub = m.group(2)
    if m.group(1) in SPLIT and sub and sub[0].islower():
        return f"{m.group(1)}::{sub}"
    return m.group(1)


def page_caller(name):
    m = re.search(r"cutlab::web::(?:pages::)?(\w+)(?:::(\w+))?", name)
    return m.group(1) + (f"::{m.group(2)}" if m.group(2) else "")


def callers_of(node, found):
    for caller in node.get("callers", []):
        name = caller["name"]
        if "cutlab::web" in name:
            found.add(page_caller(name))
        elif name in ("elem[0]", "table[0]"):
            found.add("fn table")
        else:
            callers_of(caller, found)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("wasm")
    parser.add_argument("--min-bytes", type=int, default=1000,
                        help="core functions at least this big are traced to their callers")
    args = parser.parse_args()
    top = subprocess.run(["twiggy", "top", "-n", "1000000", "-f", "csv", args.wasm],
                         capture_output=True, text=True, check=True).stdout
    rows = [(r["Name"], int(r["ShallowSize"])) for r in csv.DictReader(io.StringIO(top))]
    code = [(n, s) for n, s in rows if not n.startswith(NON_CODE)]
    by_part = collections.Counter()
    for name, size in code:
        m = re.search(r"cutlab::(\w+)", name)
        if not m:
            by_part["dependencies (leptos, serde, core/alloc generics, …)"] += size
        elif m.group(1) in ("web", "charts"):
            by_part["the UI (cutlab::web, cutlab::charts)"] += size
        else:
            by_part[f"core: {m.group(1)}"] += size
    total = sum(s for _, s in code)
    print(f"code bytes: {total}")
    print("| part | code bytes | share |\n|---|---:|---:|")
    for part, size in by_part.most_common():
        print(f"| {part} | {size} | {100 * size / total:.1f} % |")

    traced = [n for n, s in code if s >= args.min_bytes and core_module(n)]
    paths = subprocess.run(["twiggy", "paths", args.wasm, *traced, "-d", "12", "-r", "200",
                            "-f", "json"], capture_output=True, text=True, check=True).stdout
    by_module = collections.defaultdict(lambda: [0, set()])
    for tree in json.loads(paths):
        found = set()
        callers_of(tree, found)
        entry = by_module[core_module(tree["name"])]
        entry[0] += tree["shallow_size"]
        entry[1] |= found
    print(f"\ncore functions of at least {args.min_bytes} bytes, by module, and the page code "
          "that calls them")
    print("| core module | code bytes | called from |\n|---|---:|---|")
    for module, (size, found) in sorted(by_module.items(), key=lambda kv: -kv[1][0]):
        print(f"| {module} | {size} | {', '.join(sorted(found))} |")


if __name__ == "__main__":
    main()
