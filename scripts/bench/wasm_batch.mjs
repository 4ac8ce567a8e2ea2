// Times the batched loop against the single loop in wasm under node (issue 28): the four runs of
// examples/common/batch_workload.rs, exported by examples/bench_loop_wasm.rs, one after another
// and as one batch, alternating, best of `rounds` by the process's CPU time.
//
//   node scripts/bench/wasm_batch.mjs <dir with bench_loop_wasm.js> [rounds]
//
// Prints one JSON line: {"simulated_s", "single_wall_s", "single_cpu_s", "batch_wall_s",
// "batch_cpu_s", "digests"}; exits with an error if the two ways computed different runs.
import { createRequire } from "node:module";
import path from "node:path";
import { performance } from "node:perf_hooks";

const [dir, roundsText] = process.argv.slice(2);
if (!dir) {
  console.error("usage: node wasm_batch.mjs <dir> [rounds]");
  process.exit(2);
}
const require = createRequire(import.meta.url);
const bench = require(path.resolve(dir, "bench_loop_wasm.js"));
const rounds = Math.max(1, Number(roundsText ?? 3));
const best = { single: { wall: Infinity, cpu: Infinity }, batch: { wall: Infinity, cpu: Infinity } };
let simulated = NaN;
for (let i = 0; i < rounds; i++) {
  for (const [way, batched] of [["single", false], ["batch", true]]) {
    const start = performance.now();
    const cpuStart = process.cpuUsage();
    simulated = bench.run_batch_workload(batched);
    const cpu = process.cpuUsage(cpuStart);
    best[way].wall = Math.min(best[way].wall, (performance.now() - start) / 1000);
    best[way].cpu = Math.min(best[way].cpu, (cpu.user + cpu.system) / 1e6);
  }
}
if (!Number.isFinite(simulated)) {
  console.error("wasm_batch: a run failed");
  process.exit(1);
}
const digests = bench.batch_workload_digests(false);
if (bench.batch_workload_digests(true) !== digests) {
  console.error("wasm_batch: the batch computed other runs than the single loop");
  process.exit(1);
}
console.log(JSON.stringify({
  simulated_s: simulated,
  single_wall_s: best.single.wall,
  single_cpu_s: best.single.cpu,
  batch_wall_s: best.batch.wall,
  batch_cpu_s: best.batch.cpu,
  digests,
}));
