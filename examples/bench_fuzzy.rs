//! Fuzzy engine throughput: cutlab's Mamdani engine evaluated on a grid of (E, EC) points, timed
//! in memory.
//!
//! Driven by `scripts/bench/fuzzy_engine.py`, which times scikit-fuzzy and fuzzylite on the same
//! points with the same FLL text side by side; see docs/benchmarks.md. On its own:
//!
//! ```text
//! cargo run --release --example bench_fuzzy -- [--fll www/data/paper-002-dynamics.fll]
//!     [--grid 100 | --points xy.f64] [--repeats 5] [--output u.f64]
//! ```
//!
//! The engine is built by cutlab's FLL parser from the file (default: paper 002's engine with the
//! dynamics-based rules, as `cutlab fuzzy export --rules dynamics` writes it: seven triangles on
//! [-6, 6] for E, EC and U, 49 rules, min/min/max, centroid, which cutlab integrates exactly and
//! so ignores the FLL's resolution). The points are either a `--grid N` × N lattice on [-6, 6]²
//! (E varies slowest) or `--points FILE`, raw little-endian f64 pairs `E EC E EC …`.
//!
//! A repeat evaluates every point once, one `Engine::evaluate` call per point, as the controller
//! calls it once per control period. Prints the best repeat as one JSON line with the evaluations
//! per second, the sum of the outputs (a checksum) and the outputs of the first few points;
//! `--output` writes every output as raw little-endian f64.

use std::error::Error;
use std::time::Instant;

use cutlab::control::fuzzy::fll;

/// Outputs quoted in the JSON line, so a reader can compare a few values by eye.
const SHOWN: usize = 5;

struct Args {
    fll: String,
    grid: usize,
    points: Option<String>,
    repeats: usize,
    output: Option<String>,
}

fn parse_args() -> Result<Args, Box<dyn Error>> {
    let mut args = Args {
        fll: "www/data/paper-002-dynamics.fll".into(),
        grid: 100,
        points: None,
        repeats: 5,
        output: None,
    };
    let mut iter = std::env::args().skip(1);
    while let Some(arg) = iter.next() {
        let mut value = || iter.next().ok_or_else(|| format!("{arg} needs a value"));
        match arg.as_str() {
            "--fll" => args.fll = value()?,
            "--grid" => args.grid = value()?.parse()?,
            "--points" => args.points = Some(value()?),
            "--repeats" => args.repeats = value()?.parse()?,
            "--output" => args.output = Some(value()?),
            other => return Err(format!("unknown argument {other:?}").into()),
        }
    }
    if args.grid < 2 || args.repeats == 0 {
        return Err("--grid must be at least 2 and --repeats at least 1".into());
    }
    Ok(args)
}

/// The (E, EC) points, interleaved.
fn points(args: &Args) -> Result<Vec<f64>, Box<dyn Error>> {
    if let Some(path) = &args.points {
        let bytes = std::fs::read(path)?;
        let (chunks, rest) = bytes.as_chunks::<8>();
        if !rest.is_empty() || chunks.len() % 2 != 0 || chunks.is_empty() {
            return Err(
                format!("{path}: not a whole, non-zero number of f64 (E, EC) pairs").into(),
            );
        }
        return Ok(chunks.iter().map(|b| f64::from_le_bytes(*b)).collect());
    }
    let n = args.grid;
    let axis: Vec<f64> = (0..n)
        .map(|i| -6.0 + 12.0 * i as f64 / (n - 1) as f64)
        .collect();
    Ok(axis
        .iter()
        .flat_map(|&e| axis.iter().flat_map(move |&ec| [e, ec]))
        .collect())
}

fn main() -> Result<(), Box<dyn Error>> {
    let args = parse_args()?;
    let text = std::fs::read_to_string(&args.fll).map_err(|e| format!("{}: {e}", args.fll))?;
    let mut engine = fll::parse(&text).map_err(|e| format!("{}: {e}", args.fll))?;
    if engine.inputs().len() != 2 || engine.outputs().len() != 1 {
        return Err(format!("{}: expected two inputs and one output", args.fll).into());
    }
    let xy = points(&args)?;
    let mut outputs = vec![0.0; xy.len() / 2];
    let mut best_s = f64::INFINITY;
    for _ in 0..args.repeats {
        engine.reset();
        let start = Instant::now();
        for (pair, u) in xy.chunks_exact(2).zip(outputs.iter_mut()) {
            let mut out = [0.0];
            engine.evaluate(std::hint::black_box(pair), &mut out);
            *u = out[0];
        }
        best_s = best_s.min(start.elapsed().as_secs_f64());
        std::hint::black_box(&outputs);
    }
    if let Some(path) = &args.output {
        let out: Vec<u8> = outputs.iter().flat_map(|x| x.to_le_bytes()).collect();
        std::fs::write(path, out)?;
    }
    let checksum: f64 = outputs.iter().sum();
    let line = serde_json::json!({
        "engine": engine.name,
        "evaluations": outputs.len(),
        "best_s": best_s,
        "evaluations_per_s": outputs.len() as f64 / best_s,
        "checksum": checksum,
        "first_outputs": &outputs[..outputs.len().min(SHOWN)],
    });
    println!("{line}");
    Ok(())
}
