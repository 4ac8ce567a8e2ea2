//! `cutlab filter design|apply` and `cutlab spectrum`, driven in-process: output against the
//! library and scipy's reference, and errors that are one line naming what is wrong.
#![cfg(feature = "cli")]
// Helpers outside #[test] functions are test code too: a failed unwrap is a failed test.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;
use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use cutlab::signal::filter::SosFilterBank;
use cutlab::signal::filtfilt::filtfilt_interleaved;
use cutlab::signal::spectrum::welch;
use serde_json::Value;

const DESIGN: &str = include_str!("reference/signal/design.json");

fn cutlab(args: &[&str], stdin: &[u8]) -> (Result<(), String>, Vec<u8>) {
    common::cutlab_bytes(args, stdin)
}

fn error_of(args: &[&str], stdin: &[u8]) -> String {
    let (result, _) = cutlab(args, stdin);
    let message = result.expect_err("the command should fail");
    assert!(!message.contains('\n'), "one line: {message:?}");
    message
}

fn to_bytes(x: &[f64]) -> Vec<u8> {
    x.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn to_floats(b: &[u8]) -> Vec<f64> {
    assert_eq!(b.len() % 8, 0);
    b.as_chunks::<8>()
        .0
        .iter()
        .map(|c| f64::from_le_bytes(*c))
        .collect()
}

/// The numbers in a piece of JSON text, parsed exactly (serde_json's default float parser may be
/// off by an ulp, and the point here is that the CLI prints full precision).
fn numbers_in(text: &str) -> Vec<f64> {
    text.split(|c: char| !(c.is_ascii_digit() || "eE+-.".contains(c)))
        .filter_map(|token| token.parse::<f64>().ok())
        .collect()
}

fn signal(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| (i as f64 * 0.013).sin() * 3.0 + ((i * 7919) % 101) as f64 / 50.0 - 1.0)
        .collect()
}

fn paper_lowpass() -> cutlab::signal::sos::Sos {
    butter(&ButterworthSpec {
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: Cutoff::Single(50.0),
        sample_rate_hz: 10_000.0,
    })
    .unwrap()
}

#[test]
fn filter_design_prints_scipy_sections_at_full_precision() {
    let (result, out) = cutlab(
        &[
            "filter", "design", "--kind", "lowpass", "--order", "10", "--cutoff", "50", "--fs",
            "10000",
        ],
        b"",
    );
    assert_eq!(result, Ok(()));
    let json: Value = serde_json::from_slice(&out).unwrap();
    let rows = json["sos"].as_array().unwrap();
    assert_eq!(rows.len(), 5);
    // Bit for bit what the library designs, which matches scipy (checked to 1e-9 here too).
    let ours = paper_lowpass().rows();
    let reference: Value = serde_json::from_str(DESIGN).unwrap();
    let scipy = reference["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| {
            c["kind"] == "lowpass"
                && c["order"] == 10
                && c["cutoff_hz"][0] == 50.0
                && c["sample_rate_hz"] == 10_000.0
        })
        .unwrap();
    let text = String::from_utf8(out.clone()).unwrap();
    let printed_all = numbers_in(&text);
    assert_eq!(printed_all.len(), 30);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.as_array().unwrap().len(), 6);
        let printed = &printed_all[6 * k..6 * k + 6];
        assert_eq!(printed, ours[k], "section {k}");
        for (a, b) in printed.iter().zip(scipy["sos"][k].as_array().unwrap()) {
            let b = b.as_f64().unwrap();
            assert!((a - b).abs() <= 1e-9 * b.abs(), "section {k}: {a} vs {b}");
        }
    }
}

#[test]
fn filter_design_takes_bands_and_defaults_to_lowpass() {
    let (result, out) = cutlab(
        &[
            "filter", "design", "--kind", "bandstop", "--order", "3", "--cutoff", "45,55", "--fs",
            "1000",
        ],
        b"",
    );
    assert_eq!(result, Ok(()));
    let json: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(json["sos"].as_array().unwrap().len(), 3);
    let (result, out) = cutlab(
        &[
            "filter",
            "design",
            "--order=2",
            "--cutoff=260",
            "--fs=10000",
        ],
        b"",
    );
    assert_eq!(result, Ok(()));
    let json: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(json["sos"].as_array().unwrap().len(), 1);
}

#[test]
fn filter_design_errors_name_the_option() {
    let base = [
        "filter", "design", "--order", "4", "--cutoff", "50", "--fs", "10000",
    ];
    let with = |i: usize, value: &'static str| {
        let mut args = base.to_vec();
        args[i] = value;
        args
    };
    let order_zero = error_of(&with(3, "0"), b"");
    assert!(
        order_zero.starts_with("--order: order must be"),
        "{order_zero}"
    );
    let nyquist = error_of(&with(5, "5000"), b"");
    assert_eq!(
        nyquist,
        "--cutoff: cut-off 5000 Hz must be below the Nyquist frequency, 5000 Hz"
    );
    assert!(error_of(&with(5, "-3"), b"").starts_with("--cutoff: cut-off must be above 0 Hz"));
    // The words the Signal chain page shows beside its fields (one table of the design's rows).
    assert_eq!(
        error_of(&with(5, "abc"), b""),
        "--cutoff: \"abc\" is not a number"
    );
    assert!(error_of(&with(5, "1,2,3"), b"").starts_with("--cutoff: expected one frequency"));
    assert_eq!(
        error_of(&with(7, "inf"), b""),
        "--fs: \"inf\" is not a number"
    );
    assert!(error_of(&with(7, "0"), b"").starts_with("--fs: sample rate"));
    assert_eq!(
        error_of(&with(3, "-1"), b""),
        "--order: \"-1\" is not a whole number"
    );
    let kind = error_of(
        &[
            "filter", "design", "--kind", "comb", "--order", "2", "--cutoff", "5", "--fs", "100",
        ],
        b"",
    );
    assert!(
        kind.starts_with("--kind: unknown filter kind \"comb\""),
        "{kind}"
    );
    let band = error_of(
        &[
            "filter", "design", "--kind", "bandpass", "--order", "2", "--cutoff", "5", "--fs",
            "100",
        ],
        b"",
    );
    assert!(band.contains("lower and an upper"), "{band}");
    assert_eq!(
        error_of(&["filter", "design", "--order", "2", "--fs", "100"], b""),
        "missing required option --cutoff"
    );
    // A list where one cut-off is expected is refused, whether the kind is given or the default
    // low-pass (it was read as its first number, the second dropped); apply designs the same way.
    assert_eq!(
        error_of(&with(5, "40,50"), b""),
        "--cutoff: a low-pass filter takes one cut-off, not a band (--kind is lowpass unless \
         given)"
    );
    let mut applied = with(5, "40,50");
    applied[1] = "apply";
    assert!(error_of(&applied, b"").starts_with("--cutoff: a low-pass filter takes one cut-off"));
    let high = error_of(
        &[
            "filter", "design", "--kind", "highpass", "--order", "2", "--cutoff", "5,10", "--fs",
            "100",
        ],
        b"",
    );
    assert_eq!(
        high,
        "--cutoff: a high-pass filter takes one cut-off, not a band"
    );
    assert!(error_of(&["filter", "frobnicate"], b"").starts_with("unknown filter subcommand"));
    assert!(error_of(&["filter"], b"").contains("design or apply"));
}

#[test]
fn filter_apply_streams_causal_filtering_bit_for_bit() {
    let sos = paper_lowpass();
    for channels in [1usize, 3, 5] {
        let x = signal(3 * 10_000 + channels * 77);
        let x = &x[..x.len() - x.len() % channels];
        let c = channels.to_string();
        let (result, out) = cutlab(
            &[
                "filter",
                "apply",
                "--order",
                "10",
                "--cutoff",
                "50",
                "--fs",
                "10000",
                "--channels",
                &c,
            ],
            &to_bytes(x),
        );
        assert_eq!(result, Ok(()));
        let mut expected = x.to_vec();
        SosFilterBank::new(&sos, channels)
            .unwrap()
            .process_slice(&mut expected);
        assert_eq!(to_floats(&out), expected, "{channels} channels");
    }
}

#[test]
fn filter_apply_zero_phase_equals_sosfiltfilt() {
    let sos = paper_lowpass();
    let x = signal(3 * 20_000);
    let (result, out) = cutlab(
        &[
            "filter",
            "apply",
            "--order",
            "10",
            "--cutoff",
            "50",
            "--fs",
            "10000",
            "--channels",
            "3",
            "--zero-phase",
        ],
        &to_bytes(&x),
    );
    assert_eq!(result, Ok(()));
    assert_eq!(to_floats(&out), filtfilt_interleaved(&sos, &x, 3).unwrap());
}

#[test]
fn filter_apply_errors_say_where() {
    let args = [
        "filter",
        "apply",
        "--order",
        "10",
        "--cutoff",
        "50",
        "--fs",
        "10000",
        "--channels",
        "3",
    ];
    // 5 frames of 3 channels plus 11 stray bytes.
    let mut bytes = to_bytes(&[1.0; 15]);
    bytes.extend([0u8; 11]);
    let e = error_of(&args, &bytes);
    assert_eq!(
        e,
        "stdin: input is 131 bytes, not a whole number of 24-byte frames (3 channel(s) × 8-byte \
         f64): the last 11 byte(s), from byte offset 120, were not filtered"
    );
    let mut zero_phase = args.to_vec();
    zero_phase.push("--zero-phase");
    let e = error_of(&zero_phase, &to_bytes(&[1.0; 3 * 33]));
    assert_eq!(
        e,
        "stdin: zero-phase filtering needs more than 33 samples per channel (the default padding \
         of scipy's sosfiltfilt for this filter), got 33"
    );
    let mut none = args.to_vec();
    none[9] = "0";
    assert_eq!(error_of(&none, b""), "--channels: must be at least 1");
    let mut temp = args.to_vec();
    temp.extend(["--temp-dir", "/tmp"]);
    assert!(error_of(&temp, b"").starts_with("--temp-dir only matters with --zero-phase"));
    zero_phase.extend(["--temp-dir", "/nonexistent/cutlab"]);
    assert!(error_of(&zero_phase, b"").starts_with("--temp-dir: cannot create a temporary file"));
    assert!(error_of(
        &["filter", "apply", "--order", "2", "--cutoff", "50", "--fs", "100"],
        b""
    )
    .starts_with("--cutoff: cut-off 50 Hz must be below the Nyquist frequency"));
}

#[test]
fn empty_input_gives_empty_output_causally() {
    let (result, out) = cutlab(
        &[
            "filter", "apply", "--order", "2", "--cutoff", "50", "--fs", "1000",
        ],
        b"",
    );
    assert_eq!(result, Ok(()));
    assert!(out.is_empty());
}

#[test]
fn spectrum_prints_welch_json() {
    let x = signal(5000);
    let (result, out) = cutlab(
        &["spectrum", "--fs", "10000", "--nperseg", "512"],
        &to_bytes(&x),
    );
    assert_eq!(result, Ok(()));
    let json: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(json["psd"].as_array().unwrap().len(), 257);
    let expected = welch(&x, 10_000.0, 512).unwrap();
    let text = String::from_utf8(out).unwrap();
    let (freq_text, psd_text) = text.split_at(text.find("\"psd\"").unwrap());
    assert_eq!(numbers_in(freq_text), expected.freq_hz);
    assert_eq!(numbers_in(psd_text), expected.psd);
    // Default segment length 256.
    let (result, out) = cutlab(&["spectrum", "--fs", "10000"], &to_bytes(&x));
    assert_eq!(result, Ok(()));
    let json: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(json["psd"].as_array().unwrap().len(), 129);
}

#[test]
fn spectrum_errors_say_where() {
    let mut bytes = to_bytes(&[1.0, 2.0, 3.0]);
    bytes.push(7);
    assert_eq!(
        error_of(&["spectrum", "--fs", "100"], &bytes),
        "stdin: 25 bytes is not a whole number of 8-byte f64 samples: the last 1 byte(s), from \
         byte offset 24, are left over"
    );
    assert_eq!(
        error_of(&["spectrum", "--fs", "100"], &to_bytes(&[1.0, f64::NAN])),
        "stdin: sample 1 (byte offset 8) is NaN, not a finite number"
    );
    assert!(error_of(&["spectrum", "--fs", "100"], b"").starts_with("stdin: need at least 1"));
    assert_eq!(error_of(&["spectrum"], b""), "missing required option --fs");
    assert!(error_of(&["spectrum", "--fs", "0"], b"").starts_with("--fs: sample rate"));
    assert_eq!(
        error_of(&["spectrum", "--fs", "1", "--nperseg", "0"], b""),
        "--nperseg: must be at least 1"
    );
}

#[test]
fn help_describes_streaming_and_zero_phase_buffering() {
    for args in [
        &["filter", "--help"][..],
        &["filter", "design", "--help"],
        &["filter", "apply", "--help"],
        &["spectrum", "--help"],
    ] {
        let (result, out) = cutlab(args, b"");
        assert_eq!(result, Ok(()));
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("Usage: cutlab"), "{args:?}");
    }
    let (_, out) = cutlab(&["filter", "apply", "--help"], b"");
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("constant memory"));
    assert!(text.contains("temporary file"));
}

/// Samples whose squares overflow gave a spectrum of nulls with exit 0; an endless input aborted
/// on allocation. Both are refused with a message.
#[test]
fn spectrum_refuses_overflow_and_records_too_long_to_hold() {
    let huge = to_bytes(&vec![1e300; 5000]);
    let e = error_of(&["spectrum", "--fs", "1000"], &huge);
    assert!(e.starts_with("stdin: the spectrum overflows"), "{e}");

    let mut endless = std::io::BufReader::new(std::io::repeat(0));
    let mut out = Vec::new();
    let args: Vec<String> = ["spectrum", "--fs", "1000"].map(String::from).to_vec();
    let e = cutlab::cli::run(
        &args,
        &mut cutlab::cli::Io {
            stdin: &mut endless,
            stdout: &mut out,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("stdin: more than 67108864 samples"), "{e}");
}
