// Times examples/bench_loop_wasm.rs under node: the closed loop of kim-step-doc with
// fuzzy-dynamics, compiled to wasm32 (release profile) and bound by wasm-bindgen --target nodejs.
//
//   node scripts/bench/wasm_loop.mjs <dir with bench_loop_wasm.js> [repeats]
//
// Prints the best repeat as one JSON line: {"simulated_s": …, "wall_s": …, "cpu_s": …, "digest": …} (CPU
// time of the process during the run: on a shared machine, the wall time less the waiting).
import { createRequire } from "node:module";
import path from "node:path";
import { performance } from "node:perf_hooks";

const [dir, repeatsText] = process.argv.slice(2);
if (!dir) {
  console.error("usage: node wasm_loop.mjs <dir> [repeats]");
  process.exit(2);
}
const require = createRequire(import.meta.url);
const bench = require(path.resolve(dir, "bench_loop_wasm.js"));
const repeats = Math.max(1, Number(repeatsText ?? 3));
let best = Infinity;
let bestCpu = Infinity;
let simulated = NaN;
for (let i = 0; i < repeats; i++) {
  const start = performance.now();
  const cpuStart = process.cpuUsage();
  simulated = bench.run_kim_step_doc_fuzzy_dynamics();
  const cpu = process.cpuUsage(cpuStart);
  best = Math.min(best, (performance.now() - start) / 1000);
  bestCpu = Math.min(bestCpu, (cpu.user + cpu.system) / 1e6);
}
if (!Number.isFinite(simulated)) {
  console.error("wasm_loop: the run failed");
  process.exit(1);
}
// The run's trace digest, to compare with the native examples/bench_loop's (bit for bit).
const digest = bench.trace_digest_kim_step_doc_fuzzy_dynamics?.() ?? null;
console.log(JSON.stringify({ simulated_s: simulated, wall_s: best, cpu_s: bestCpu, digest }));
