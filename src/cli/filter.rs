//! `cutlab filter design` and `cutlab filter apply`: Butterworth filters on the command line.
//!
//! `design` prints the second-order sections as JSON in scipy's layout; `apply` filters raw
//! little-endian f64 samples from stdin to stdout, causally in constant memory, or zero-phase
//! (scipy's `sosfiltfilt`) through a temporary file.

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::args::{reject_extra, required, value_or};
use super::{CliError, Io};
use crate::input::table::Table;
use crate::signal::butterworth::{DesignError, FilterKind};
use crate::signal::design_settings::{parse_design, FilterSetting};
use crate::signal::filtfilt::{filter_stream, filtfilt_stream, StreamError, MAX_STREAM_CHANNELS};
use crate::signal::sos::Sos;

/// The filter a design or an application describes.
#[derive(Debug, clap::Args)]
pub struct DesignOptions {
    #[arg(
        long = "kind",
        help = "lowpass, highpass, bandpass or bandstop (default lowpass)",
        value_name = "KIND",
        allow_hyphen_values = true
    )]
    kind: Option<String>,
    #[arg(
        long = "order",
        help = "Filter order, 1 to 20 (band filters have 2N poles)",
        value_name = "N",
        allow_hyphen_values = true
    )]
    order: Option<String>,
    #[arg(
        long = "cutoff",
        help = "Cut-off frequency in Hz; lower,upper for bandpass/bandstop",
        value_name = "HZ[,HZ2]",
        allow_hyphen_values = true
    )]
    cutoff: Option<String>,
    #[arg(
        long = "fs",
        help = "Sampling rate in Hz",
        value_name = "HZ",
        allow_hyphen_values = true
    )]
    fs: Option<String>,
}

/// `cutlab filter`: design or apply.
#[derive(Debug, clap::Args)]
pub struct FilterArgs {
    #[command(subcommand)]
    command: Option<FilterCommand>,
}

#[derive(Debug, clap::Subcommand)]
enum FilterCommand {
    /// Print the sections as JSON, equal to scipy.signal.butter(..., output='sos')
    #[command(long_about = DESIGN_ABOUT)]
    Design(DesignArgs),
    /// Filter raw little-endian f64 samples from stdin to stdout
    #[command(long_about = APPLY_ABOUT)]
    Apply(ApplyArgs),
}

#[derive(Debug, clap::Args)]
pub struct DesignArgs {
    #[command(flatten)]
    design: DesignOptions,
    /// Stray words: refused with a hint where such input goes.
    #[arg(hide = true)]
    extra: Vec<String>,
}

#[derive(Debug, clap::Args)]
pub struct ApplyArgs {
    #[command(flatten)]
    design: DesignOptions,
    #[arg(
        long = "channels",
        help = "Interleaved channels per frame, each filtered on its own (default 1)",
        value_name = "C",
        allow_hyphen_values = true
    )]
    channels: Option<String>,
    #[arg(
        long = "zero-phase",
        help = "Filter forward and backward (scipy's sosfiltfilt, default odd padding); buffers through a temporary file"
    )]
    zero_phase: bool,
    #[arg(
        long = "temp-dir",
        help = "Where --zero-phase puts its temporary file (default: the system temp directory, $TMPDIR)",
        value_name = "DIR",
        allow_hyphen_values = true
    )]
    temp_dir: Option<String>,
    /// Stray words: refused with a hint where such input goes.
    #[arg(hide = true)]
    extra: Vec<String>,
}

pub(crate) const ABOUT: &str = "Design a digital Butterworth filter as second-order sections, or apply one to samples.\n\n\
Subcommands:\n  \
design  Print the sections as JSON {\"sos\": [[b0, b1, b2, a0, a1, a2], ...]}, scipy's layout,\n          \
equal to scipy.signal.butter(N, Wn, btype, fs=fs, output='sos')\n  \
apply   Filter raw little-endian f64 samples from stdin to stdout\n\n\
See `cutlab filter design --help` and `cutlab filter apply --help`.";

const DESIGN_ABOUT: &str = "Design a digital Butterworth filter and print its second-order sections as JSON:\n\
{\"sos\": [[b0, b1, b2, a0, a1, a2], ...]} in scipy's layout and order (gain in the first section),\n\
every coefficient at full precision. Equal to scipy.signal.butter(N, Wn, btype, fs=fs, output='sos').\n\n\
Example: cutlab filter design --order 10 --cutoff 50 --fs 10000";

const APPLY_ABOUT: &str =
    "Filter raw little-endian f64 samples from stdin to stdout, in the same format.\n\n\
With --channels C the input is interleaved frames (c0 c1 ... c0 c1 ...), each channel filtered\n\
with its own state; the input length must be a multiple of 8 × C bytes.\n\n\
Causal (default): transposed direct form II from rest, as scipy.signal.sosfilt. Streams in\n\
constant memory whatever the input length; output follows input block by block.\n\n\
--zero-phase: forward then backward, as scipy.signal.sosfiltfilt with its default odd padding\n\
(padlen = 3 × (2 × sections + 1 − first-order sections)); each channel needs more than padlen\n\
samples. The backward pass cannot start before the input ends, so the forward pass goes to a\n\
temporary file of (samples + 2 × padlen) × 8 bytes, is filtered backward in place and then\n\
copied to stdout: memory stays constant, disk holds one copy of the input, and nothing is\n\
written to stdout until the input has ended. The file is removed afterwards.\n\n\
Example: cutlab filter apply --order 10 --cutoff 50 --fs 10000 --channels 3 < in.f64 > out.f64";

/// Runs `cutlab filter`.
/// Runs `cutlab filter`.
pub fn run(args: FilterArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    match args.command {
        Some(FilterCommand::Design(a)) => design(a, io),
        Some(FilterCommand::Apply(a)) => apply(a, io),
        None => Err(CliError::new(
            "cutlab filter needs a subcommand: design or apply (see cutlab filter --help)",
        )),
    }
}

fn design(args: DesignArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    reject_extra(&args.extra, "samples come on stdin")?;
    let sos = design_from(&args.design)?;
    write_sos_json(io.stdout, &sos)
}

fn apply(args: ApplyArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    reject_extra(&args.extra, "samples come on stdin")?;
    let sos = design_from(&args.design)?;
    let channels: usize = value_or("channels", &args.channels, 1)?;
    if channels == 0 {
        return Err(CliError::new("--channels: must be at least 1"));
    }
    if channels > MAX_STREAM_CHANNELS {
        return Err(CliError::new(format!(
            "--channels: at most {MAX_STREAM_CHANNELS}, got {channels}"
        )));
    }
    if args.zero_phase {
        let directory = args
            .temp_dir
            .as_deref()
            .map(PathBuf::from)
            .unwrap_or_else(std::env::temp_dir);
        let mut scratch = TempFile::create(&directory)?;
        filtfilt_stream(&sos, channels, io.stdin, io.stdout, &mut scratch.file)
            .map_err(stream_error)?;
    } else {
        if args.temp_dir.as_deref().is_some() {
            return Err(CliError::new(
                "--temp-dir only matters with --zero-phase (causal filtering needs no temporary file)",
            ));
        }
        filter_stream(&sos, channels, io.stdin, io.stdout).map_err(stream_error)?;
    }
    io.stdout.flush()?;
    Ok(())
}

/// The design the options describe, through the design table's rows (as the Signal chain
/// page's): errors name the option.
pub(crate) fn design_from(args: &DesignOptions) -> Result<Sos, CliError> {
    let order = required::<String>("order", &args.order)?;
    let rate = required::<String>("fs", &args.fs)?;
    let cutoff_text = args
        .cutoff
        .as_deref()
        .ok_or_else(|| CliError::new("missing required option --cutoff"))?;
    let edges: Vec<&str> = cutoff_text.split(',').collect();
    let mut texts = vec![
        (FilterSetting::Order, order.as_str()),
        (FilterSetting::SampleRate, rate.as_str()),
    ];
    if let Some(kind) = args.kind.as_deref() {
        texts.push((FilterSetting::Kind, kind));
    }
    match edges.as_slice() {
        [single] => texts.push((FilterSetting::Cutoff, single)),
        [lower, upper] => {
            texts.push((FilterSetting::Cutoff, lower));
            texts.push((FilterSetting::Upper, upper));
        }
        _ => {
            return Err(CliError::new(format!(
                "--cutoff: expected one frequency or two separated by a comma, got {cutoff_text:?}"
            )))
        }
    }
    // Two edges for a band, one for a low/high-pass (the default kind's too: the design would
    // not read a second edge of a low-pass, so it is refused, never dropped): the design's own
    // words.
    let kind = FilterSetting::Kind
        .read(args.kind.as_deref().unwrap_or_default())
        .ok()
        .flatten()
        .or_else(|| FilterSetting::Kind.row().default_value())
        .and_then(|v| v.choice())
        .and_then(|name| name.parse::<FilterKind>().ok());
    if let Some(kind) = kind.filter(|k| k.is_band() != (edges.len() == 2)) {
        let default_kind = match args.kind {
            None => format!(" (--kind is {} unless given)", kind.name()),
            Some(_) => String::new(),
        };
        return Err(CliError::new(format!(
            "--cutoff: {}{default_kind}",
            DesignError::CutoffCount { kind }
        )));
    }
    parse_design(&texts)
        .map(|(_, sos)| sos)
        .map_err(|errors| match errors.first() {
            // The upper edge is the second value of --cutoff.
            Some(e) if e.setting == FilterSetting::Upper => {
                CliError::new(format!("--cutoff: {}", e.problem))
            }
            Some(e) => CliError::new(e.for_cli()),
            None => CliError::new("the design was refused"),
        })
}

/// `{"sos": [[…], …]}` with one section per line and every coefficient at full precision
/// (serde_json prints the shortest decimal that reads back to the same f64).
fn write_sos_json(out: &mut dyn Write, sos: &Sos) -> Result<(), CliError> {
    let rows = sos.rows();
    out.write_all(b"{\"sos\": [\n")?;
    for (i, row) in rows.iter().enumerate() {
        let text = serde_json::to_string(row)
            .map_err(|e| CliError::new(format!("cannot write JSON: {e}")))?;
        let separator = if i + 1 == rows.len() { "" } else { "," };
        writeln!(out, "  {}{separator}", text.replace(',', ", "))?;
    }
    out.write_all(b"]}\n")?;
    Ok(())
}

fn stream_error(e: StreamError) -> CliError {
    match e {
        StreamError::Io(e) => CliError::from(e),
        other => CliError::new(format!("stdin: {other}")),
    }
}

/// A temporary file removed when dropped (and at once where the system allows removing an open
/// file, so a killed process leaves nothing behind).
struct TempFile {
    file: File,
    path: PathBuf,
}

impl TempFile {
    fn create(directory: &Path) -> Result<Self, CliError> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        let path = directory.join(format!(
            "cutlab-zero-phase-{}-{nanos}-{}.f64",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(|e| {
                CliError::new(format!(
                    "--temp-dir: cannot create a temporary file in {}: {e}",
                    directory.display()
                ))
            })?;
        #[cfg(unix)]
        let _ = fs::remove_file(&path);
        Ok(Self { file, path })
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        // Already gone on Unix; elsewhere it can only go once closed, which happens after this.
        let _ = fs::remove_file(&self.path);
    }
}
