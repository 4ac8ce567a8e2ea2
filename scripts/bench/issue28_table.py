#!/usr/bin/env python3
"""Issue 28's target table (case | before | now | target) from the JSON lines the suite's parts
print: scripts/bench/closed_loop.py's and, when the browser part ran, scripts/bench/workers.mjs's,
scripts/bench/browser.mjs's and scripts/bench/main_thread.mjs's.

    python3 scripts/bench/issue28_table.py CLOSED_LOOP_OUTPUT [WORKERS_OUTPUT [BROWSER_OUTPUT [MAIN_THREAD_OUTPUT]]]

"before" is the issue's own measurement (² the wasm rate per CPU s before was of the release
profile, not the worker's build) (issue 28, and docs/benchmarks.md's runs of
2026-11-25/26 for the loop rates); "now" is this run's. A case the run did not measure shows "—".
"""
import json
import sys

# (case, before, target as text, test on the measured value, format)
NATIVE = ("closed loop, full chain, native: simulated s per wall s", "733", "≥ 2,500", lambda v: v >= 2500)
WASM = ("closed loop, full chain, wasm (the worker's build) under node: simulated s per wall s", "476", "≥ 1,200", lambda v: v >= 1200)


def last_json(path):
    """The last line of `path` that parses as a JSON object."""
    found = None
    with open(path, encoding="utf-8") as f:
        for line in f:
            line = line.strip()
            if line.startswith("{"):
                try:
                    found = json.loads(line)
                except json.JSONDecodeError:
                    pass
    return found


def row(case, before, now_text, target, met):
    mark = "" if met is None else (" ✓" if met else " ✗")
    print(f"| {case} | {before} | {now_text} | {target}{mark} |")


def main():
    loop = last_json(sys.argv[1]) if len(sys.argv) > 1 else None
    workers = last_json(sys.argv[2]) if len(sys.argv) > 2 else None
    browser = last_json(sys.argv[3]) if len(sys.argv) > 3 else None
    print("| case | before | now | target |")
    print("|---|---:|---:|---|")
    for (case, before, target, test), key in ((NATIVE, "native_sim_s_per_s"), (WASM, "wasm_sim_s_per_s")):
        v = loop and loop.get(key)
        row(case, before, "—" if v is None else f"{v:,.0f}", target, None if v is None else test(v))
    # Per CPU second: what the loop does when it has a core (the machine is shared).
    for case, before, key in (("native: simulated s per CPU s", "733", "native_sim_s_per_cpu_s"),
                              ("wasm (the worker's build): simulated s per CPU s", "563²", "wasm_sim_s_per_cpu_s")):
        v = loop and loop.get(key)
        row(f"closed loop, full chain, {case}", before, "—" if v is None else f"{v:,.0f}", "—", None)
    if not workers:
        return
    presets = workers["presets"]
    first = max(p["metrics"] for p in presets.values())
    first_lo = min(p["metrics"] for p in presets.values())
    row("first metrics (run complete), any of the three presets (Simulate, fresh page)",
        "740–1,182 ms", f"{first_lo:,.0f}–{first:,.0f} ms", "≤ 500 ms", first <= 500)
    savings = max(p["savings"] for p in presets.values())
    row("savings complete, any preset (worst)", "4,401 ms", f"{savings:,.0f} ms", "≤ 1.5 s", savings <= 1500)
    t = workers["throttled_10_mbit"]["metrics"]
    row("first result over 10 Mbit/s (throttled Chromium)", "3,373 ms", f"{t:,.0f} ms", "≤ 1.5 s", t <= 1500)
    tune = workers["tune_search"]
    row(f"Tune search, 60 evaluations, browser ({tune['mostBusy']} workers)", "11,054 ms",
        f"{tune['ms']:,.0f} ms", "≤ 6 s", tune["ms"] <= 6000)
    one = workers.get("tune_search_one_worker")
    if one:
        gain = one["ms"] / tune["ms"]
        row("Tune search: one worker's time over two workers'", "—",
            f"{one['ms']:,.0f} / {tune['ms']:,.0f} ms = {gain:.2f}×", "≥ 1.8×", gain >= 1.8)
    if not browser:
        return
    edit = browser["edit_ms_by_preset"]
    row("controller edit → run done and redrawn, any of the three presets (worst)", "121–378 ms",
        f"{min(edit.values()):,.0f}–{max(edit.values()):,.0f} ms", "≤ 100 ms", max(edit.values()) <= 100)
    drawn = browser.get("first_drawn_ms_by_preset")
    if drawn:
        row("controller edit → the new run's first points drawn, any of the three presets (worst)", "—",
            f"{min(drawn.values()):,.0f}–{max(drawn.values()):,.0f} ms", "~ 50 ms", max(drawn.values()) <= 50)
    compare = browser["compare_ms_by_preset"]
    row("Compare, four variants with savings, any of the three presets (worst)", "~1 s default",
        f"{min(compare.values()):,.0f}–{max(compare.values()):,.0f} ms", "≤ 1 s", max(compare.values()) <= 1000)
    during = browser.get("longest_task_during_runs_ms")
    if during is not None:
        row("main-thread task during any run (Simulate with an edit, Compare, three presets)", "≤ 50 ms",
            f"{during:,.0f} ms", "≤ 50 ms", during <= 50)
    longest = browser["longest_task_ms"]
    row("main-thread task on the same pages from navigation (their start included)", "—",
        f"{longest:,.0f} ms", "—", None)
    main_thread = last_json(sys.argv[4]) if len(sys.argv) > 4 else None
    if main_thread:
        # The same pages' longest tasks with the pool as large as the cores and with one worker:
        # what the workers' competition for the cores adds to the page's tasks.
        for cores in ("real", "1"):
            tasks = [t for key, t in main_thread["worst"].items() if key.endswith(f"cores {cores}")]
            if tasks:
                wall = max(t["wallMs"] for t in tasks)
                pool = "as many workers as cores" if cores == "real" else "one worker"
                row(f"main-thread task from navigation, {pool} (main_thread.mjs)", "—",
                    f"{wall:,.0f} ms", "—", None)

if __name__ == "__main__":
    main()
