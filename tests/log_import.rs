//! Messy CSV logs load as they are: every dialect gives the same numbers, damaged lines are
//! reported by line and column and kept as gaps, any bytes in any chunking never panic.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::log::{load, ColumnKind, Log, LogBuilder, Role};
use cutlab::rng::Rng;

const COMMA: &[u8] = include_bytes!("data/logs/comma.csv");
const SEMICOLON: &[u8] = include_bytes!("data/logs/semicolon_decimal_comma.csv");
const TAB: &[u8] = include_bytes!("data/logs/tab.csv");
const MESSY: &[u8] = include_bytes!("data/logs/messy_no_header.csv");
const COMMA_BOM_CRLF: &[u8] = include_bytes!("data/logs/comma_bom_crlf.csv");
const QUOTED: &[u8] = include_bytes!("data/logs/quoted_units.csv");
const FIFTY: &[u8] = include_bytes!("data/logs/fifty_columns.csv");
const SLOW: &[u8] = include_bytes!("data/logs/slow_10hz_rms.csv");
const FAST: &[u8] = include_bytes!("data/logs/fast_10khz_phases.tsv");

/// Values compared bit for bit, NaN equal to NaN.
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

#[test]
fn every_dialect_gives_the_same_numbers_labels_and_roles() {
    let reference = load(COMMA, None);
    assert_eq!(reference.rows, 12);
    assert!(reference.header);
    assert_eq!(reference.sample_period_s, Some(0.01));
    assert_eq!(reference.time_column, Some(0));
    let roles: Vec<Option<Role>> = reference.columns.iter().map(|c| c.role).collect();
    assert_eq!(
        roles,
        [
            Some(Role::Time),
            Some(Role::RmsCurrent),
            Some(Role::PhaseCurrent),
            Some(Role::SpindleSpeed),
            Some(Role::Label),
            Some(Role::Force)
        ]
    );
    assert_eq!(reference.columns[1].unit.as_deref(), Some("A"));
    assert_eq!(reference.columns[2].values[0], -1.42e-6);
    let phase = &reference.columns[4];
    assert_eq!(phase.kind, ColumnKind::Text);
    assert_eq!(phase.label_names, ["Prep", "Layer 1 Up", "End"]);
    for (name, bytes) in [
        ("semicolon, decimal comma, BOM, CRLF", SEMICOLON),
        ("tab, no final newline", TAB),
        ("comma, BOM, CRLF", COMMA_BOM_CRLF),
    ] {
        let log = load(bytes, None);
        assert_eq!(log.rows, reference.rows, "{name}");
        assert!(log.problems.is_empty(), "{name}: {:?}", log.problems);
        for (a, b) in log.columns.iter().zip(&reference.columns) {
            assert_eq!(a.name, b.name, "{name}");
            assert!(same(&a.values, &b.values), "{name}: {}", a.name);
            assert_eq!(a.labels, b.labels, "{name}: {}", a.name);
            assert_eq!(a.role, b.role, "{name}: {}", a.name);
        }
    }
    assert_eq!(load(SEMICOLON, None).dialect.delimiter, b';');
    assert!(load(SEMICOLON, None).dialect.decimal_comma);
    assert_eq!(load(TAB, None).dialect.delimiter, b'\t');
}

#[test]
fn damaged_lines_are_reported_by_line_and_column_and_kept_as_gaps() {
    let log = load(MESSY, Some(0.01));
    assert!(!log.header);
    assert_eq!(log.rows, 8);
    assert_eq!(
        log.sample_period_s,
        Some(0.01),
        "given, since there is no time column"
    );
    let values = &log.columns[1];
    assert_eq!(values.kind, ColumnKind::Number);
    assert_eq!(values.values[0], 1.0);
    assert!(values.values[2].is_nan() && values.values[5].is_nan());
    assert_eq!(values.values[6], f64::INFINITY);
    // A quoted label with doubled quotes, and one with a line break inside.
    let labels = &log.columns[2];
    assert_eq!(labels.kind, ColumnKind::Text);
    let label = |row: usize| labels.label_names[labels.labels[row] as usize].as_str();
    assert_eq!(label(1), "a \"quoted\" label");
    assert_eq!(label(2), "two\nlines");
    let found: Vec<(usize, Option<&str>)> = log
        .problems
        .iter()
        .map(|p| (p.line, p.column.as_deref()))
        .collect();
    // The record with the quoted line break spans lines 3–4, so the short record is line 6.
    assert!(found.contains(&(6, None)), "{:?}", log.problems);
    assert!(found.contains(&(7, Some("column 2"))), "{:?}", log.problems);
    assert!(found.contains(&(8, None)), "{:?}", log.problems);
}

#[test]
fn a_time_column_in_milliseconds_is_read_in_seconds_and_its_gaps_reported() {
    let text = "t_ms;Spindle current [A]\n0;1\n10;1\n20;1\n30;1\n80;1\n90;1\n";
    let log = load(text.as_bytes(), None);
    assert_eq!(log.time_column, Some(0));
    assert_eq!(log.sample_period_s, Some(0.01));
    assert_eq!(log.columns[0].values[4], 0.08);
    let gap = log
        .problems
        .iter()
        .find(|p| p.message.contains("gap"))
        .unwrap();
    assert_eq!(gap.line, 6);
}

fn load_in_chunks(bytes: &[u8], chunk: usize) -> Log {
    let mut builder = LogBuilder::new();
    for piece in bytes.chunks(chunk.max(1)) {
        builder.push(piece);
    }
    builder.finish(None)
}

#[test]
fn any_chunking_gives_the_same_log() {
    for bytes in [
        COMMA,
        SEMICOLON,
        TAB,
        MESSY,
        COMMA_BOM_CRLF,
        QUOTED,
        FIFTY,
        SLOW,
    ] {
        let whole = load(bytes, None);
        for chunk in [1, 2, 3, 5, 7, 64] {
            let pieces = load_in_chunks(bytes, chunk);
            assert_eq!(pieces.rows, whole.rows, "chunk {chunk}");
            assert_eq!(pieces.problems, whole.problems, "chunk {chunk}");
            for (a, b) in pieces.columns.iter().zip(&whole.columns) {
                assert!(same(&a.values, &b.values), "chunk {chunk}: {}", a.name);
                assert_eq!(a.labels, b.labels);
            }
        }
    }
}

#[test]
fn random_and_mutated_bytes_never_panic() {
    let mut rng = Rng::seed_from(7);
    let seeds: [&[u8]; 4] = [COMMA, SEMICOLON, TAB, MESSY];
    for round in 0..400usize {
        let mut bytes: Vec<u8> = if round.is_multiple_of(4) {
            (0..(rng.next_u64() % 300))
                .map(|_| rng.next_u64() as u8)
                .collect()
        } else {
            seeds[round % seeds.len()].to_vec()
        };
        // Mutate: flip, insert and delete bytes, favouring the ones the parser cares about.
        for _ in 0..(rng.next_u64() % 12) {
            let special = [
                b'"', b',', b';', b'\t', b'\n', b'\r', 0xEF, 0xFF, b'.', b'e',
            ];
            let byte = if rng.next_u64().is_multiple_of(2) {
                special[(rng.next_u64() % special.len() as u64) as usize]
            } else {
                rng.next_u64() as u8
            };
            let at = if bytes.is_empty() {
                0
            } else {
                (rng.next_u64() % bytes.len() as u64) as usize
            };
            match rng.next_u64() % 3 {
                0 if !bytes.is_empty() => bytes[at] = byte,
                1 => bytes.insert(at, byte),
                _ if !bytes.is_empty() => {
                    bytes.remove(at);
                }
                _ => bytes.push(byte),
            }
        }
        let log = load_in_chunks(&bytes, 1 + (rng.next_u64() % 9) as usize);
        for c in &log.columns {
            assert!(c.values.is_empty() || c.values.len() == log.rows);
        }
    }
}

/// A 1 kHz log of a 50 Hz current over two machining phases, and the same at 10 Hz.
fn sine_log(rate_hz: f64, rows: usize) -> String {
    let mut text = String::from("time [s],Spindle current [A],Phase\n");
    for i in 0..rows {
        let t = i as f64 / rate_hz;
        let phase = if i < rows / 2 {
            "Roughing"
        } else {
            "Finishing"
        };
        let offset = if i < rows / 2 { 10.0 } else { 4.0 };
        let i_a = offset + 2.0 * (std::f64::consts::TAU * 50.0 * t).sin();
        text.push_str(&format!("{t},{i_a},{phase}\n"));
    }
    text
}

#[test]
fn analysis_groups_by_label_filters_below_nyquist_and_finds_the_spectral_line() {
    use cutlab::log::analysis::{analyse, AnalysisRequest};
    let log = load(sine_log(1000.0, 4000).as_bytes(), None);
    assert_eq!(log.sample_period_s, Some(0.001));
    let request = AnalysisRequest {
        by: Some("Phase".into()),
        lowpass: Some((10.0, 4)),
        spectrum: true,
    };
    let a = analyse(&log, "Spindle current [A]", &request).unwrap();
    assert_eq!(a.lowpass, Some((10.0, 4)));
    // The 10 Hz low-pass removes the 50 Hz ripple: the phases' means stay, their spread goes.
    let roughing = &a.by_label[0];
    assert_eq!(roughing.label, "Roughing");
    assert_eq!(roughing.stats.count, 2000);
    assert!((roughing.stats.duration_s.unwrap() - 2.0).abs() < 1e-9);
    assert!((roughing.stats.mean.unwrap() - 10.0).abs() < 0.05);
    let finishing = &a.by_label[1];
    assert!((finishing.stats.mean.unwrap() - 4.0).abs() < 0.05);
    // Unfiltered, the spectrum's strongest line is the 50 Hz current.
    let raw = analyse(
        &log,
        "Spindle current [A]",
        &AnalysisRequest {
            spectrum: true,
            ..AnalysisRequest::default()
        },
    )
    .unwrap();
    let strongest = raw
        .peaks
        .iter()
        .max_by(|a, b| a.psd.total_cmp(&b.psd))
        .unwrap();
    assert!((strongest.freq_hz - 50.0).abs() < 1.0, "{:?}", raw.peaks);
    assert!((raw.whole.max.unwrap() - 12.0).abs() < 0.01);

    // A 10 Hz log cannot take a 10 Hz low-pass: the stage is skipped and the analysis says why.
    let slow = load(sine_log(10.0, 100).as_bytes(), None);
    let a = analyse(&slow, "Spindle current [A]", &request).unwrap();
    assert_eq!(a.lowpass, None);
    assert!(
        a.notes[0].contains("above its Nyquist frequency (5 Hz)"),
        "{:?}",
        a.notes
    );
    // Naming a column that is not there lists the ones that are.
    let e = analyse(&slow, "Current", &request).unwrap_err();
    assert!(
        e.contains("columns: time [s], Spindle current [A], Phase"),
        "{e}"
    );
    assert!(analyse(&slow, "Phase", &request)
        .unwrap_err()
        .contains("holds no numbers"));
}

#[test]
fn quoted_fields_keep_delimiters_quotes_and_line_breaks_and_units_come_in_every_style() {
    let log = load(QUOTED, None);
    assert_eq!(log.rows, 4);
    assert!(log.problems.is_empty(), "{:?}", log.problems);
    let names: Vec<&str> = log.columns.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "Time [s]",
            "Current [A]",
            "I_A",
            "speed(rpm)",
            "Note, free text"
        ]
    );
    let units: Vec<Option<&str>> = log.columns.iter().map(|c| c.unit.as_deref()).collect();
    assert_eq!(units, [Some("s"), Some("A"), None, Some("rpm"), None]);
    let roles: Vec<Option<Role>> = log.columns.iter().map(|c| c.role).collect();
    assert_eq!(
        roles,
        [
            Some(Role::Time),
            Some(Role::RmsCurrent),
            Some(Role::PhaseCurrent),
            Some(Role::SpindleSpeed),
            Some(Role::Label)
        ]
    );
    let notes = &log.columns[4];
    let label = |row: usize| notes.label_names[notes.labels[row] as usize].as_str();
    assert_eq!(
        [label(0), label(1), label(2), label(3)],
        ["a, b", "said \"stop\"", "two\nlines", "plain"]
    );
    // The record with the line break spans lines 4–5: the last row is line 6.
    assert_eq!(log.row_lines, [2, 3, 4, 6]);
    assert_eq!(log.columns[3].values, [1000.0, 1001.0, 1002.0, 1003.0]);
}

#[test]
fn fifty_columns_with_axis_prefixes_a_pass_fail_flag_and_time_in_ms_from_its_step() {
    use cutlab::log::mapping::{Channel, Mapping};
    let log = load(FIFTY, None);
    assert_eq!(log.columns.len(), 50);
    assert_eq!(log.rows, 20);
    // No unit, and a step of 2: read as milliseconds, and said.
    assert_eq!(log.sample_period_s, Some(0.002));
    assert_eq!(log.columns[0].values[3], 0.006);
    assert!(
        log.problems
            .iter()
            .any(|p| p.message.contains("read as milliseconds")
                && p.column.as_deref() == Some("Time")),
        "{:?}",
        log.problems
    );
    let check = log.columns.iter().find(|c| c.name == "Check").unwrap();
    assert_eq!(check.kind, ColumnKind::Text);
    assert_eq!(check.label_names, ["fail", "pass"]);
    let mapping = Mapping::guess(&log);
    // The spindle's (S_) phases and current, the X axis's: the first of each channel.
    assert_eq!(
        mapping.columns_of(Channel::SpindlePhase),
        ["S_I_U", "S_I_V", "S_I_W"]
    );
    assert_eq!(
        mapping.columns_of(Channel::FeedPhase),
        ["X_I_U", "X_I_V", "X_I_W"]
    );
    assert_eq!(
        mapping.columns_of(Channel::SpindleCurrent),
        ["S_Current [A]"]
    );
    assert_eq!(mapping.columns_of(Channel::FeedCurrent), ["X_Current [A]"]);
    assert_eq!(mapping.columns_of(Channel::SpindleSpeed), ["S_Speed [rpm]"]);
    assert_eq!(mapping.columns_of(Channel::Feed), ["X_Feed [mm/min]"]);
    assert_eq!(mapping.columns_of(Channel::Label), ["Check"]);
}

#[test]
fn a_slow_rms_log_and_a_fast_phase_log_load_with_their_rates() {
    let slow = load(SLOW, None);
    assert_eq!((slow.rows, slow.sample_period_s), (60, Some(0.1)));
    assert!(slow.dialect.decimal_comma);
    assert_eq!(slow.columns[1].role, Some(Role::RmsCurrent));
    assert_eq!(slow.columns[1].values[59], 12.0);
    let fast = load(FAST, None);
    assert_eq!(fast.dialect.delimiter, b'\t');
    assert_eq!((fast.rows, fast.sample_period_s), (400, Some(0.0001)));
    assert!(fast.columns[1..]
        .iter()
        .all(|c| c.role == Some(Role::PhaseCurrent)));
    // The 10 Hz log cannot take the lab's 260 Hz low-pass; the 10 kHz one can (replay's chain
    // adapts: tests/log_replay.rs).
    use cutlab::log::analysis::{analyse, AnalysisRequest};
    let request = AnalysisRequest {
        lowpass: Some((260.0, 4)),
        ..AnalysisRequest::default()
    };
    let a = analyse(&slow, "S_Strom [A]", &request).unwrap();
    assert!(a.lowpass.is_none() && a.notes[0].contains("Nyquist"));
    let a = analyse(&fast, "S_I_U [A]", &request).unwrap();
    assert_eq!(a.lowpass, Some((260.0, 4)));
}

#[test]
fn the_pages_chain_filters_takes_the_rms_finds_the_line_and_groups_by_label_in_stages() {
    use cutlab::log::analysis::{analyse, AnalysisRequest, ChainRequest, ChainWork};
    use cutlab::work::Work;
    let log = std::sync::Arc::new(load(sine_log(1000.0, 4000).as_bytes(), None));
    let request = ChainRequest {
        column: "Spindle current [A]".into(),
        lowpass: Some((10.0, 4)),
        rms_window_s: 0.1,
        by: Some("Phase".into()),
        sample_period_s: None,
    };
    let mut work = ChainWork::new(log.clone(), request.clone()).unwrap();
    let mut calls = 0;
    while !work.advance(1).unwrap() {
        calls += 1;
    }
    assert!(calls >= 4, "one stage per call: {calls}");
    let out = work.finish().unwrap();
    assert!(out.lowpass_applied);
    // The per-label statistics are the CLI's (the same zero-phase low-pass).
    let cli = analyse(
        &log,
        "Spindle current [A]",
        &AnalysisRequest {
            by: Some("Phase".into()),
            lowpass: Some((10.0, 4)),
            spectrum: false,
        },
    )
    .unwrap();
    assert_eq!(out.analysis.by_label, cli.by_label);
    assert_eq!(out.analysis.whole, cli.whole);
    // Unfiltered: a 2 A sine on 10 A has an RMS of √(10² + 2²/2) over whole periods, and the
    // strongest line is at 50 Hz.
    let raw = ChainWork::new(
        log,
        ChainRequest {
            lowpass: None,
            ..request
        },
    )
    .unwrap()
    .run_to_end()
    .unwrap();
    let expected = (100.0f64 + 2.0).sqrt();
    assert!((raw.rms[1000] - expected).abs() < 1e-9, "{}", raw.rms[1000]);
    let strongest = raw
        .analysis
        .peaks
        .iter()
        .max_by(|a, b| a.psd.total_cmp(&b.psd))
        .unwrap();
    assert!(
        (strongest.freq_hz - 50.0).abs() < 1.0,
        "{:?}",
        raw.analysis.peaks
    );
    // A cut-off above the Nyquist frequency is a skipped stage, said.
    let slow = std::sync::Arc::new(load(sine_log(10.0, 100).as_bytes(), None));
    let skipped = ChainWork::new(
        slow,
        ChainRequest {
            column: "Spindle current [A]".into(),
            lowpass: Some((10.0, 4)),
            rms_window_s: 1.0,
            by: None,
            sample_period_s: None,
        },
    )
    .unwrap()
    .run_to_end()
    .unwrap();
    assert!(!skipped.lowpass_applied);
    assert!(
        skipped.analysis.notes[0].contains("Nyquist"),
        "{:?}",
        skipped.analysis.notes
    );
}
