//! Filter throughput: cutlab's biquad cascade on a file of samples, timed in memory.
//!
//! Driven by `scripts/bench/filter_throughput.py`, which times scipy on the same samples side by
//! side; see docs/benchmarks.md. On its own:
//!
//! ```text
//! cargo run --release --example bench_filter -- --input x.f64 [--channels 3] [--repeats 5]
//!     [--mode kernel|new-output] [--per-sample] [--output y.f64]
//! ```
//!
//! The input is raw little-endian f64, interleaved when `--channels` > 1. The filter is
//! `butter(10, 50, fs=10000)` (paper 000's order: five sections), run from rest.
//!
//! - `--mode kernel` (default): filter a buffer in place, already in memory (the copy of the
//!   input into it is not timed). Compare with scipy's Cython loop `_sosfilt`, which `sosfilt`
//!   runs on its own copy.
//! - `--mode new-output`: what `y = scipy.signal.sosfilt(sos, x)` does as a whole: allocate a new
//!   output (page faults included) and fill it with the filtered input, block by block (8192
//!   frames: copy the block, filter it in place while it is in cache, as `cutlab filter apply`
//!   streams).
//! - `--per-sample`: call `process` on every sample instead of `process_slice` (kernel mode).
//!
//! Prints the best repeat as one JSON line.

use std::error::Error;
use std::time::Instant;

use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use cutlab::signal::filter::{SosFilter, SosFilterBank};
use cutlab::signal::sos::Sos;

/// Frames per block in new-output mode: 8192 × 3 × 8 bytes = 192 KiB, inside an L2 cache.
const BLOCK_FRAMES: usize = 8192;

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Kernel,
    NewOutput,
}

struct Args {
    input: String,
    channels: usize,
    repeats: usize,
    mode: Mode,
    per_sample: bool,
    output: Option<String>,
}

fn parse_args() -> Result<Args, Box<dyn Error>> {
    let mut args = Args {
        input: String::new(),
        channels: 1,
        repeats: 5,
        mode: Mode::Kernel,
        per_sample: false,
        output: None,
    };
    let mut iter = std::env::args().skip(1);
    while let Some(arg) = iter.next() {
        let mut value = || iter.next().ok_or_else(|| format!("{arg} needs a value"));
        match arg.as_str() {
            "--input" => args.input = value()?,
            "--channels" => args.channels = value()?.parse()?,
            "--repeats" => args.repeats = value()?.parse()?,
            "--mode" => {
                args.mode = match value()?.as_str() {
                    "kernel" => Mode::Kernel,
                    "new-output" => Mode::NewOutput,
                    other => return Err(format!("unknown mode {other:?}").into()),
                }
            }
            "--per-sample" => args.per_sample = true,
            "--output" => args.output = Some(value()?),
            other => return Err(format!("unknown argument {other:?}").into()),
        }
    }
    if args.input.is_empty() {
        return Err("--input FILE is required".into());
    }
    if args.channels == 0 || args.repeats == 0 {
        return Err("--channels and --repeats must be at least 1".into());
    }
    Ok(args)
}

/// Filters `samples` in place from rest with the fastest path for the channel count.
fn filter_in_place(
    sos: &Sos,
    channels: usize,
    per_sample: bool,
    samples: &mut [f64],
) -> Result<(), Box<dyn Error>> {
    if per_sample {
        let mut bank = SosFilterBank::new(sos, channels)?;
        for x in samples.iter_mut() {
            *x = bank.process(*x);
        }
    } else if channels == 1 {
        SosFilter::new(sos).process_slice(samples);
    } else {
        SosFilterBank::new(sos, channels)?.process_slice(samples);
    }
    Ok(())
}

/// Allocates a new output and fills it with the filtered input, block by block.
fn filter_to_new_output(
    sos: &Sos,
    channels: usize,
    input: &[f64],
) -> Result<Vec<f64>, Box<dyn Error>> {
    let mut output = vec![0.0; input.len()];
    let block = BLOCK_FRAMES * channels;
    let mut bank = SosFilterBank::new(sos, channels)?;
    let mut single = SosFilter::new(sos);
    for (src, dst) in input.chunks(block).zip(output.chunks_mut(block)) {
        dst.copy_from_slice(src);
        if channels == 1 {
            single.process_slice(dst);
        } else {
            bank.process_slice(dst);
        }
    }
    Ok(output)
}

fn main() -> Result<(), Box<dyn Error>> {
    let args = parse_args()?;
    let bytes = std::fs::read(&args.input)?;
    let (chunks, rest) = bytes.as_chunks::<8>();
    if !rest.is_empty() || chunks.len() % args.channels != 0 {
        return Err("input is not a whole number of f64 frames".into());
    }
    let input: Vec<f64> = chunks.iter().map(|b| f64::from_le_bytes(*b)).collect();
    let sos = butter(&ButterworthSpec {
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: Cutoff::Single(50.0),
        sample_rate_hz: 10_000.0,
    })?;
    let mut output = vec![0.0; input.len()];
    let mut best_s = f64::INFINITY;
    for _ in 0..args.repeats {
        match args.mode {
            Mode::Kernel => {
                output.copy_from_slice(&input);
                let start = Instant::now();
                filter_in_place(&sos, args.channels, args.per_sample, &mut output)?;
                best_s = best_s.min(start.elapsed().as_secs_f64());
            }
            Mode::NewOutput => {
                drop(std::mem::take(&mut output));
                let start = Instant::now();
                output = filter_to_new_output(&sos, args.channels, &input)?;
                best_s = best_s.min(start.elapsed().as_secs_f64());
            }
        }
        std::hint::black_box(&output);
    }
    if let Some(path) = &args.output {
        let out: Vec<u8> = output.iter().flat_map(|x| x.to_le_bytes()).collect();
        std::fs::write(path, out)?;
    }
    let mode = match (args.mode, args.per_sample) {
        (Mode::Kernel, false) => "kernel",
        (Mode::Kernel, true) => "kernel-per-sample",
        (Mode::NewOutput, _) => "new-output",
    };
    println!(
        "{{\"channels\": {}, \"channel_samples\": {}, \"mode\": \"{mode}\", \"best_s\": {best_s}, \"channel_samples_per_s\": {}}}",
        args.channels,
        input.len(),
        input.len() as f64 / best_s,
    );
    Ok(())
}
