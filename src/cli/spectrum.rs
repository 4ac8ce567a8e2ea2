//! `cutlab spectrum`: Welch power spectral density of raw f64 samples on stdin.

use serde::Serialize;

use std::io::Read as _;

use super::args::{reject_extra, required, value_or};
use super::{write_json, CliError, Io};
use crate::signal::spectrum::welch;

/// Welch power spectral density of f64 samples on stdin (scipy.signal.welch).
#[derive(Debug, clap::Args)]
pub struct SpectrumArgs {
    #[arg(
        long = "fs",
        help = "Sampling rate in Hz",
        value_name = "HZ",
        allow_hyphen_values = true
    )]
    fs: Option<String>,
    #[arg(
        long = "nperseg",
        help = "Samples per segment (default 256; shortened to the input if longer, as scipy does)",
        value_name = "N",
        allow_hyphen_values = true
    )]
    nperseg: Option<String>,
    /// Stray words: refused with a hint where such input goes.
    #[arg(hide = true)]
    extra: Vec<String>,
}

pub(crate) const ABOUT: &str = "Power spectral density of raw little-endian f64 samples on stdin, by Welch's method, printed\n\
as JSON {\"freq_hz\": [...], \"psd\": [...]} (unit²/Hz). Equal to scipy.signal.welch(x, fs, nperseg=N)\n\
with its defaults: periodic Hann window, 50 % overlap, each segment's mean removed, density\n\
scaling, one-sided, mean of the segments. Reads the whole input into memory.\n\n\
Example: cutlab spectrum --fs 10000 --nperseg 4096 < current.f64";

#[derive(Serialize)]
struct Output {
    freq_hz: Vec<f64>,
    psd: Vec<f64>,
}

/// The longest record read: 2²⁶ samples (512 MiB of f64).
pub const MAX_SAMPLES: usize = 1 << 26;

/// Runs `cutlab spectrum`.
pub fn run(args: SpectrumArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    reject_extra(&args.extra, "samples come on stdin")?;
    let sample_rate_hz: f64 = required("fs", &args.fs)?;
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(CliError::new(format!(
            "--fs: sample rate must be a positive, finite number of Hz, got {sample_rate_hz}"
        )));
    }
    let nperseg: usize = value_or("nperseg", &args.nperseg, 256)?;
    if nperseg == 0 {
        return Err(CliError::new("--nperseg: must be at least 1"));
    }
    // Refuse a record too long to hold rather than let the allocation abort the process.
    let mut bytes = Vec::new();
    io.stdin
        .take(8 * MAX_SAMPLES as u64 + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() > 8 * MAX_SAMPLES {
        return Err(CliError::new(format!(
            "stdin: more than {MAX_SAMPLES} samples ({} MiB); split the record and average the \
             spectra of its parts",
            8 * MAX_SAMPLES / (1 << 20)
        )));
    }
    let (samples, rest) = bytes.as_chunks::<8>();
    if !rest.is_empty() {
        return Err(CliError::new(format!(
            "stdin: {} bytes is not a whole number of 8-byte f64 samples: the last {} byte(s), \
             from byte offset {}, are left over",
            bytes.len(),
            rest.len(),
            bytes.len() - rest.len()
        )));
    }
    let samples: Vec<f64> = samples.iter().map(|b| f64::from_le_bytes(*b)).collect();
    if let Some(i) = samples.iter().position(|x| !x.is_finite()) {
        return Err(CliError::new(format!(
            "stdin: sample {i} (byte offset {}) is {}, not a finite number",
            8 * i,
            samples[i]
        )));
    }
    let psd = welch(&samples, sample_rate_hz, nperseg)
        .map_err(|e| CliError::new(format!("stdin: {e}")))?;
    // Squares of samples near 1e308 overflow; JSON would print them as null.
    if psd.psd.iter().any(|p| !p.is_finite()) {
        let largest = samples.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        return Err(CliError::new(format!(
            "stdin: the spectrum overflows (samples up to {largest:e} square beyond f64); scale \
             the samples down"
        )));
    }
    write_json(
        io.stdout,
        &Output {
            freq_hz: psd.freq_hz,
            psd: psd.psd,
        },
    )
}
