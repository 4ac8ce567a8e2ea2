//! Messy CSV logs load as they are: every dialect gives the same numbers, damaged lines are
//! reported by line and column and kept as gaps, any bytes in any chunking never panic.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::log::{load, ColumnKind, Log, LogBuilder, ReadError, Role};
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
const DAMAGED: &[u8] = include_bytes!("data/logs/damaged.csv");

/// Values compared bit for bit, NaN equal to NaN.
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

#[test]
fn every_dialect_gives_the_same_numbers_labels_and_roles() {
    let reference = load(COMMA, None).unwrap();
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
        let log = load(bytes, None).unwrap();
        assert_eq!(log.rows, reference.rows, "{name}");
        assert!(log.problems.is_empty(), "{name}: {:?}", log.problems);
        for (a, b) in log.columns.iter().zip(&reference.columns) {
            assert_eq!(a.name, b.name, "{name}");
            assert!(same(&a.values, &b.values), "{name}: {}", a.name);
            assert_eq!(a.labels, b.labels, "{name}: {}", a.name);
            assert_eq!(a.role, b.role, "{name}: {}", a.name);
        }
    }
    assert_eq!(load(SEMICOLON, None).unwrap().dialect.delimiter, b';');
    assert!(load(SEMICOLON, None).unwrap().dialect.decimal_comma);
    assert_eq!(load(TAB, None).unwrap().dialect.delimiter, b'\t');
}

#[test]
fn damaged_lines_are_reported_by_line_and_column_and_kept_as_gaps() {
    let log = load(MESSY, Some(0.01)).unwrap();
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
    let log = load(text.as_bytes(), None).unwrap();
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

fn load_in_chunks(bytes: &[u8], chunk: usize) -> Result<Log, ReadError> {
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
        DAMAGED,
    ] {
        let whole = load(bytes, None).unwrap();
        for chunk in [1, 2, 3, 5, 7, 64] {
            let pieces = load_in_chunks(bytes, chunk).unwrap();
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
fn random_and_mutated_bytes_never_panic_and_a_refusal_is_one_line() {
    let mut rng = Rng::seed_from(7);
    let seeds: [&[u8]; 4] = [COMMA, SEMICOLON, TAB, MESSY];
    for round in 0..2000usize {
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
                b'"', b',', b';', b'\t', b'\n', b'\r', 0xEF, 0xFF, 0xFE, 0, b'.', b'e', b'#',
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
        match load_in_chunks(&bytes, 1 + (rng.next_u64() % 9) as usize) {
            Ok(log) => {
                assert_lines_add_up(&log, &format!("round {round}"));
                for c in &log.columns {
                    assert!(c.values.is_empty() || c.values.len() == log.rows);
                }
            }
            Err(e) => {
                let e = e.to_string();
                assert!(!e.contains('\n') && e.len() < 400, "round {round}: {e}");
            }
        }
    }
}

/// One random log: a header (or none) and comment lines before it, clean rows, then rows with
/// every kind of damage the reader keeps (NaN, ±∞, 1e309, empty and text cells, short and long
/// rows, lines of delimiters, blank lines, quoted line breaks), in a random dialect and line
/// end. Returns the bytes, the data rows written and the cells not finite per column.
fn random_damaged_log(rng: &mut Rng) -> (Vec<u8>, usize, Vec<usize>) {
    let pick = |rng: &mut Rng, n: u64| (rng.next_u64() % n) as usize;
    let width = 2 + pick(rng, 5);
    let delimiter = [',', ';', '\t'][pick(rng, 3)];
    let decimal_comma = delimiter != ',' && pick(rng, 2) == 0;
    let line_end = ["\n", "\r\n", "\r"][pick(rng, 3)];
    let header = pick(rng, 4) != 0;
    let number = |v: f64| {
        let text = format!("{v}");
        if decimal_comma {
            text.replace('.', ",")
        } else {
            text
        }
    };
    let mut lines: Vec<String> = Vec::new();
    if header {
        for k in 0..pick(rng, 3) {
            lines.push(format!("# exported by a logger, note {k}"));
        }
        let names: Vec<String> = (0..width)
            .map(|c| {
                if c == 0 {
                    "t [s]".to_string()
                } else {
                    format!("ch{c} [A]")
                }
            })
            .collect();
        lines.push(names.join(&delimiter.to_string()));
    }
    let rows = 5 + pick(rng, 60);
    let mut data_rows = 0;
    let mut not_finite = vec![0; width];
    for row in 0..rows {
        let clean = row < 5;
        // About a row in three damaged: a log that is mostly damage has no dialect to find.
        let damage = if clean { 99 } else { pick(rng, 30) };
        let mut cells: Vec<String> = (0..width)
            .map(|c| {
                if c == 0 {
                    number(row as f64 * 0.5)
                } else {
                    number((rng.next_u64() % 1000) as f64 / 8.0)
                }
            })
            .collect();
        match damage {
            0 => {
                // A blank line: no row.
                lines.push(" ".repeat(pick(rng, 3)));
                continue;
            }
            1 => cells = vec![String::new(); width],
            2 => {
                let c = 1 + pick(rng, width as u64 - 1);
                cells[c] = ["NaN", "inf", "-inf", "1e309"][pick(rng, 4)].into();
                not_finite[c] += 1;
            }
            3 => {
                let c = 1 + pick(rng, width as u64 - 1);
                not_finite[c] += 1;
                cells[c] = "9".repeat(400);
            }
            4 => cells[1 + pick(rng, width as u64 - 1)] = String::new(),
            5 => cells.truncate(1 + pick(rng, width as u64 - 1)),
            6 => cells.push("extra".into()),
            7 if pick(rng, 4) == 0 => cells[1] = "n/a".into(),
            8 => cells[1] = format!("\"{}\"", cells[1]),
            9 => {
                cells.push(format!("\"a note{line_end}over two lines\""));
            }
            _ => {}
        }
        lines.push(cells.join(&delimiter.to_string()));
        data_rows += 1;
    }
    let mut text = lines.join(line_end);
    if pick(rng, 2) == 0 {
        text.push_str(line_end);
    }
    let mut bytes = text.into_bytes();
    if pick(rng, 4) == 0 {
        bytes.splice(0..0, [0xEF, 0xBB, 0xBF]);
    }
    (bytes, data_rows, not_finite)
}

#[test]
fn random_damage_leaves_every_row_read_and_every_cell_counted() {
    let mut rng = Rng::seed_from(27);
    for round in 0..2000 {
        let (bytes, data_rows, not_finite) = random_damaged_log(&mut rng);
        let chunk = [1, 2, 5, 64, 1 << 16][(rng.next_u64() % 5) as usize];
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let log = load_in_chunks(&bytes, chunk)
            .unwrap_or_else(|e| panic!("round {round}: refused: {e}\n{text}"));
        // Rows read + rows reported = rows in the file: no damage drops a row.
        assert_eq!(
            log.rows, data_rows,
            "round {round}\n{text}\n{:?}",
            log.problems
        );
        assert_lines_add_up(&log, &format!("round {round}"));
        assert_eq!(log.account.cells, log.rows * log.columns.len());
        for (c, column) in log.columns.iter().enumerate().skip(1) {
            assert_eq!(
                column.kind,
                ColumnKind::Number,
                "round {round}: {}\n{text}",
                column.name
            );
            // Every cell is a finite number, a gap or a number not finite: the statistics
            // leave out exactly the gaps and the numbers not finite.
            let stats = cutlab::log::analysis::Stats::of(&column.values, None);
            assert_eq!(stats.count + stats.left_out, log.rows);
            assert_eq!(
                stats.left_out,
                column.missing + column.not_finite,
                "round {round}"
            );
            assert_eq!(
                column.not_finite, not_finite[c],
                "round {round}: {}\n{text}",
                column.name
            );
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
    let log = load(sine_log(1000.0, 4000).as_bytes(), None).unwrap();
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
    let slow = load(sine_log(10.0, 100).as_bytes(), None).unwrap();
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
    let log = load(QUOTED, None).unwrap();
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
    let log = load(FIFTY, None).unwrap();
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
    let slow = load(SLOW, None).unwrap();
    assert_eq!((slow.rows, slow.sample_period_s), (60, Some(0.1)));
    assert!(slow.dialect.decimal_comma);
    assert_eq!(slow.columns[1].role, Some(Role::RmsCurrent));
    assert_eq!(slow.columns[1].values[59], 12.0);
    let fast = load(FAST, None).unwrap();
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
    let log = std::sync::Arc::new(load(sine_log(1000.0, 4000).as_bytes(), None).unwrap());
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
    let slow = std::sync::Arc::new(load(sine_log(10.0, 100).as_bytes(), None).unwrap());
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

/// `rows` clean data lines of a time, a current and a label, under a header.
fn clean_log(rows: usize) -> String {
    let mut text = String::from("t [s],I [A],Phase\n");
    for i in 0..rows {
        text.push_str(&format!("{},{},cut\n", i as f64 * 0.01, 10 + i % 3));
    }
    text
}

/// The account's lines add up: rows, the header, a preamble and blank lines are every line.
fn assert_lines_add_up(log: &Log, what: &str) {
    let a = &log.account;
    assert_eq!(
        a.lines,
        a.header_lines + a.preamble_lines + a.blank_lines + a.row_lines,
        "{what}: {a:?}"
    );
    assert!(a.row_lines >= log.rows, "{what}: {a:?}");
}

/// A damaged file: what the damage is, the file, the rows in it, what the log must show.
type DamageCase = (&'static str, String, usize, Box<dyn Fn(&Log)>);

#[test]
fn every_damage_leaves_every_data_line_a_row_and_every_other_line_counted() {
    let rows = 50;
    let clean = clean_log(rows);
    let mut lines: Vec<String> = clean.lines().map(String::from).collect();
    let data = |lines: &[String]| lines.join("\n") + "\n";
    // (what, the file, rows in it, what the account must say)
    let mut cases: Vec<DamageCase> = Vec::new();
    cases.push((
        "clean",
        clean.clone(),
        rows,
        Box::new(|l: &Log| {
            assert!(l.account.unread().is_empty(), "{:?}", l.account.unread());
        }),
    ));
    // 6: CR-only line ends.
    cases.push((
        "CR line ends",
        clean.replace('\n', "\r"),
        rows,
        Box::new(|l: &Log| {
            assert!(l.account.cr_line_ends);
            assert_eq!(l.sample_period_s, Some(0.01));
        }),
    ));
    // 13: rows of only delimiters are rows of gaps: the duration keeps them.
    let mut with_delimiters = lines.clone();
    with_delimiters[10] = ",,".into();
    with_delimiters[20] = ",,".into();
    cases.push((
        "rows of delimiters",
        data(&with_delimiters),
        rows,
        Box::new(|l: &Log| {
            assert_eq!(l.account.empty_rows, 2);
            assert_eq!(l.columns[1].missing, 2);
            // The duration keeps them: 50 rows of 10 ms.
            let stats = cutlab::log::analysis::Stats::of(&l.columns[1].values, l.sample_period_s);
            assert!((stats.duration_s.unwrap() - 0.5).abs() < 1e-12, "{stats:?}");
            assert!(l
                .problems
                .iter()
                .any(|p| p.line == 11 && p.message.contains("every cell is empty")));
        }),
    ));
    // Blank lines are counted, not rows.
    let mut with_blanks = lines.clone();
    with_blanks.insert(5, String::new());
    with_blanks.insert(30, "   ".into());
    cases.push((
        "blank lines",
        data(&with_blanks),
        rows,
        Box::new(|l: &Log| {
            assert_eq!((l.account.blank_lines, l.account.first_blank_line), (2, 6));
        }),
    ));
    // 26: comment lines and a preamble before the header.
    let mut with_preamble = lines.clone();
    for (i, line) in [
        "# exported 2026-11-20",
        "Machine: DMU 50; program O1234",
        "",
    ]
    .iter()
    .enumerate()
    {
        with_preamble.insert(i, (*line).to_string());
    }
    cases.push((
        "a preamble",
        data(&with_preamble),
        rows,
        Box::new(|l: &Log| {
            assert!(l.header);
            assert_eq!(l.columns[1].name, "I [A]");
            assert_eq!(
                (l.account.preamble_lines, l.account.first_preamble_line),
                (2, 1)
            );
            assert_eq!(l.account.blank_lines, 1);
        }),
    ));
    // 26: a damaged second line does not turn the header into data.
    let mut damaged_second = lines.clone();
    damaged_second[1] = "x,y,z".into();
    cases.push((
        "a damaged second line",
        data(&damaged_second),
        rows,
        Box::new(|l: &Log| {
            assert!(l.header);
            assert_eq!(l.time_column, Some(0));
            assert_eq!(l.account.text_cells, 2);
        }),
    ));
    let mut short_second = lines.clone();
    short_second[1] = "garbage".into();
    cases.push((
        "a short second line",
        data(&short_second),
        rows,
        Box::new(|l: &Log| {
            assert!(l.header);
            assert_eq!(l.columns.len(), 3);
            assert_eq!(l.account.short_cells, 2);
        }),
    ));
    // 26: a header written with another delimiter than the data.
    let mut mixed = lines.clone();
    mixed[0] = "t [s];I [A];Phase".into();
    cases.push((
        "a header with another delimiter",
        data(&mixed),
        rows,
        Box::new(|l: &Log| {
            assert!(l.header);
            assert_eq!(l.columns[1].name, "I [A]");
            assert!(l
                .problems
                .iter()
                .any(|p| p.line == 1 && p.message.contains("delimited by ;")));
        }),
    ));
    // 10: NaN, ±inf, 1e309 and a 400-digit integer are kept, counted and left out.
    let mut not_finite = lines.clone();
    not_finite[3] = "0.02,NaN,cut".into();
    not_finite[4] = "0.03,inf,cut".into();
    not_finite[5] = "0.04,1e309,cut".into();
    not_finite[6] = format!("0.05,{},cut", "9".repeat(400));
    cases.push((
        "numbers that are not finite",
        data(&not_finite),
        rows,
        Box::new(|l: &Log| {
            assert_eq!(l.columns[1].not_finite, 4);
            assert_eq!(l.account.not_finite_cells, 4);
            let stats = cutlab::log::analysis::Stats::of(&l.columns[1].values, None);
            assert_eq!((stats.count, stats.left_out), (46, 4));
            assert!(l
                .problems
                .iter()
                .any(|p| p.line == 4 && p.message.contains("4 numbers are not finite")));
        }),
    ));
    // Short and long rows, text in a numeric column.
    let mut cells = lines.clone();
    cells[7] = "0.06,11".into();
    cells[8] = "0.07,12,cut,extra,more".into();
    cells[9] = "0.08,abc,cut".into();
    cases.push((
        "short, long and text cells",
        data(&cells),
        rows,
        Box::new(|l: &Log| {
            let a = &l.account;
            assert_eq!((a.short_cells, a.extra_cells, a.text_cells), (1, 2, 1));
            assert_eq!(a.cells, 50 * 3);
        }),
    ));
    // A quoted label with a line break is one row on two lines.
    let mut quoted = lines.clone();
    quoted[12] = "0.11,12,\"two\nlines\"".into();
    cases.push((
        "a quoted line break",
        data(&quoted),
        rows,
        Box::new(|l: &Log| {
            assert_eq!(l.account.row_lines, 51);
        }),
    ));
    lines.truncate(1);
    // 7: a one-row log whose row has text is a row, not a header.
    cases.push((
        "one row with text",
        "0.5,12,cut\n".into(),
        1,
        Box::new(|l: &Log| {
            assert!(!l.header);
            assert_eq!(l.columns[0].values, [0.5]);
        }),
    ));
    // A header alone is refused (a_file_without_data_rows_is_refused_saying_what_it_holds).
    for (what, text, expected_rows, check) in &cases {
        for chunk in [1, 7, 1 << 16] {
            let log = load_in_chunks(text.as_bytes(), chunk)
                .unwrap_or_else(|e| panic!("{what}: refused: {e}"));
            // Rows read and lines reported make up the file.
            assert_eq!(log.rows, *expected_rows, "{what}, chunks of {chunk}");
            assert_lines_add_up(&log, what);
            check(&log);
        }
    }
}

#[test]
fn what_cannot_be_read_without_guessing_is_refused_where_it_is() {
    let clean = clean_log(60_000);
    let mut lines: Vec<String> = clean.lines().map(String::from).collect();
    // 5: an unclosed quote in the data would swallow the rest of the file.
    lines[2] = "0.01,\"8.7,cut".into();
    let swallowing = lines.join("\n") + "\n";
    let e = load(swallowing.as_bytes(), None).unwrap_err();
    assert_eq!(e.line, 3, "{e}");
    assert!(
        e.message.contains("never closed") && e.message.contains("59998 lines"),
        "{e}"
    );
    // One that closes many lines later swallowed whole records on the way.
    lines[40] = "0.39,\"12,cut".into();
    let e = load((lines.join("\n") + "\n").as_bytes(), None).unwrap_err();
    assert_eq!(e.line, 3, "{e}");
    assert!(e.message.contains("delimiters of a whole record"), "{e}");
    // 5: in the header.
    let e = load(b"\"t [s],I [A]\n0,1\n1,2\n", None).unwrap_err();
    assert_eq!(e.line, 1, "{e}");
    // 8: UTF-16 and UTF-32, with a byte-order mark or without.
    let text = "t [s],I [A]\n0,1\n0.1,2\n";
    let utf16le: Vec<u8> = text.encode_utf16().flat_map(u16::to_le_bytes).collect();
    let utf16be: Vec<u8> = text.encode_utf16().flat_map(u16::to_be_bytes).collect();
    let utf32le: Vec<u8> = text
        .chars()
        .flat_map(|c| (c as u32).to_le_bytes())
        .collect();
    let utf32be: Vec<u8> = text
        .chars()
        .flat_map(|c| (c as u32).to_be_bytes())
        .collect();
    for (name, bytes, bom) in [
        ("UTF-16 (little-endian)", &utf16le, &[0xFF, 0xFE][..]),
        ("UTF-16 (big-endian)", &utf16be, &[0xFE, 0xFF][..]),
        ("UTF-32 (little-endian)", &utf32le, &[0xFF, 0xFE, 0, 0][..]),
        ("UTF-32 (big-endian)", &utf32be, &[0, 0, 0xFE, 0xFF][..]),
    ] {
        for with_bom in [false, true] {
            let file = if with_bom {
                [bom, bytes].concat()
            } else {
                bytes.clone()
            };
            for chunk in [1, 3, 1 << 16] {
                let e = load_in_chunks(&file, chunk).unwrap_err();
                assert!(e.message.contains(name), "{name} BOM {with_bom}: {e}");
                assert_eq!(e.line, 1);
            }
        }
    }
    // Each refusal is one line, short whatever the file.
    let e = load(swallowing.as_bytes(), None).unwrap_err().to_string();
    assert!(!e.contains('\n') && e.len() < 300, "{e}");
}

#[test]
fn time_columns_in_any_unit_are_read_in_seconds_and_other_units_are_not_time() {
    for (name, step, period) in [
        ("Time [min]", "0.01", 0.6),
        ("time [h]", "0.001", 3.6),
        ("time [ns]", "1000000", 1e-3),
        ("t [µs]", "500", 5e-4),
        ("t [us]", "500", 5e-4),
        ("time_ms", "2", 2e-3),
        ("Zeit [s]", "0.05", 0.05),
    ] {
        let mut text = format!("{name},I [A]\n");
        for i in 0..5 {
            text.push_str(&format!("{}*{i},1\n", step));
        }
        // Written out: the step times the row.
        let text: String = text
            .lines()
            .map(|l| match l.split_once('*') {
                Some((s, rest)) => {
                    let (i, tail) = rest.split_once(',').unwrap();
                    format!(
                        "{},{tail}\n",
                        s.parse::<f64>().unwrap() * i.parse::<f64>().unwrap()
                    )
                }
                None => format!("{l}\n"),
            })
            .collect();
        let log = load(text.as_bytes(), None).unwrap();
        assert_eq!(log.time_column, Some(0), "{name}");
        let got = log.sample_period_s.unwrap();
        assert!(
            (got - period).abs() < 1e-12 * period.max(1.0),
            "{name}: {got}"
        );
        assert!(
            !log.problems
                .iter()
                .any(|p| p.message.contains("milliseconds")),
            "{name}: {:?}",
            log.problems
        );
    }
    // A unit that is no time unit is not guessed at: no time column, and said.
    let log = load(b"Zeit [Tage],I [A]\n0,1\n1,2\n", None).unwrap();
    assert_eq!(log.time_column, None);
    assert_eq!(log.sample_period_s, None);
    assert!(log.columns[0]
        .role_reason
        .as_deref()
        .unwrap()
        .contains("\"Tage\" is no time unit"));
    assert_eq!(log.problems[0].line, 1);
}

#[test]
fn a_time_column_that_does_not_increase_is_said_at_its_line() {
    let log = load(b"time_s,I [A]\n0,1\n0,2\n0,3\n", None).unwrap();
    assert_eq!(log.sample_period_s, None);
    let p = log
        .problems
        .iter()
        .find(|p| p.message.contains("does not increase"))
        .unwrap();
    assert_eq!(p.line, 3);
    assert_eq!(
        log.period_unknown().as_deref(),
        Some("its time column \"time_s\" does not increase")
    );
}

#[test]
fn a_role_guess_rests_on_a_word_or_a_unit_and_says_which() {
    use cutlab::log::mapping::{Channel, Mapping};
    // A real mill export's names (a 49-column log): the current feedback is a current, not a feed.
    let log = load(
        b"Time,X_CurrentFeedback,X_ActualFeed,S_ActualSpeed,feed_current_rms_a,S_Drehzahl\n\
          0,1,2,3,4,5\n0.1,1,2,3,4,5\n",
        None,
    )
    .unwrap();
    let roles: Vec<(Option<Role>, &str)> = log
        .columns
        .iter()
        .map(|c| (c.role, c.role_reason.as_deref().unwrap_or("")))
        .collect();
    assert_eq!(
        roles,
        [
            (Some(Role::Time), "the word \"time\" in its name"),
            (Some(Role::RmsCurrent), "the word \"current\" in its name"),
            (Some(Role::Feed), "the word \"feed\" in its name"),
            (Some(Role::SpindleSpeed), "the word \"speed\" in its name"),
            (Some(Role::RmsCurrent), "the word \"current\" in its name"),
            (
                Some(Role::SpindleSpeed),
                "the word \"drehzahl\" in its name"
            ),
        ]
    );
    let mapping = Mapping::guess(&log);
    assert_eq!(
        mapping.channel_of("X_CurrentFeedback"),
        Some(Channel::FeedCurrent)
    );
    assert_eq!(mapping.channel_of("X_ActualFeed"), Some(Channel::Feed));
    // cutlab's own names: the feed drive's current by its word "feed"; a speed offset is no
    // programmed speed.
    let log = load(
        b"time_s,feed_current_rms_a,spindle_current_rms_a,S_Speed_Offset [rpm],programmed_feed_mm_min\n\
          0,1,2,3,4\n0.1,1,2,3,4\n",
        None,
    )
    .unwrap();
    let mapping = Mapping::guess(&log);
    assert_eq!(
        mapping.channel_of("feed_current_rms_a"),
        Some(Channel::FeedCurrent)
    );
    assert_eq!(
        mapping.channel_of("spindle_current_rms_a"),
        Some(Channel::SpindleCurrent)
    );
    assert_eq!(
        mapping.channel_of("S_Speed_Offset [rpm]"),
        Some(Channel::SpindleSpeed)
    );
    assert_eq!(
        mapping.channel_of("programmed_feed_mm_min"),
        Some(Channel::ProgrammedFeed)
    );
}

#[test]
fn statistics_by_label_take_one_pass_whatever_the_number_of_labels() {
    use cutlab::log::analysis::{analyse, AnalysisRequest};
    // 200 000 distinct labels: one pass is milliseconds; a pass per label was minutes.
    let mut text = String::from("t [s],I [A],Part\n");
    for i in 0..200_000 {
        text.push_str(&format!("{},{},p{i}\n", i as f64 * 0.001, i % 7));
    }
    let log = load(text.as_bytes(), None).unwrap();
    // Timed natively (wasm32-unknown-unknown has no clock to read).
    #[cfg(not(target_arch = "wasm32"))]
    let started = std::time::Instant::now();
    let a = analyse(
        &log,
        "I [A]",
        &AnalysisRequest {
            by: Some("Part".into()),
            ..AnalysisRequest::default()
        },
    )
    .unwrap();
    assert_eq!(a.by_label.len(), 200_000);
    assert_eq!(a.by_label[9].stats.mean, Some(2.0));
    #[cfg(not(target_arch = "wasm32"))]
    assert!(
        started.elapsed().as_secs_f64() < 10.0,
        "{:?}",
        started.elapsed()
    );
}

#[test]
fn the_damaged_sample_accounts_for_each_of_its_fifteen_lines() {
    let log = load(DAMAGED, None).unwrap();
    let a = &log.account;
    assert_eq!(
        (
            a.lines,
            a.preamble_lines,
            a.header_lines,
            a.blank_lines,
            a.row_lines
        ),
        (15, 2, 1, 1, 11)
    );
    assert_eq!(log.rows, 11);
    assert_eq!(
        (
            a.empty_rows,
            a.short_cells,
            a.extra_cells,
            a.text_cells,
            a.not_finite_cells
        ),
        (1, 1, 1, 1, 2)
    );
    // Minutes, read as seconds; the current feedback is a current, the feed a feed.
    assert_eq!(log.sample_period_s, Some(0.06));
    let roles: Vec<Option<Role>> = log.columns.iter().map(|c| c.role).collect();
    assert_eq!(
        roles,
        [
            Some(Role::Time),
            Some(Role::RmsCurrent),
            Some(Role::Feed),
            Some(Role::Label)
        ]
    );
    assert_eq!(log.account.unread().len(), 8);
}

#[test]
fn a_file_without_data_rows_is_refused_saying_what_it_holds() {
    let empty = load(b"", None).unwrap_err();
    assert_eq!(empty.line, 0);
    assert!(
        empty.to_string().starts_with("the file is empty"),
        "{empty}"
    );
    let header_only = load(b"a,b,c\n", None).unwrap_err();
    assert_eq!(
        header_only.to_string(),
        "line 1: no data rows: a header of 3 columns (\"a, b, c\") but no line of values after it"
    );
    // Chunked as the browser reads it: the same refusal.
    assert_eq!(load_in_chunks(b"a,b,c\n", 1).unwrap_err(), header_only);
    // One row is a log.
    assert_eq!(load(b"a,b,c\n1,2,3\n", None).unwrap().rows, 1);
}

/// `rows` rows at 1 kHz of a 50 Hz current of amplitude `amplitude_a` named `name`.
fn current_log(name: &str, rows: usize, current: impl Fn(f64) -> f64) -> String {
    let mut csv = format!("time_s,{name},force_n\n");
    for k in 0..rows {
        let t = k as f64 * 1e-3;
        csv += &format!("{t:.3},{:.4},150\n", current(t));
    }
    csv
}

#[test]
fn a_current_that_swings_negative_is_guessed_a_phase_current_not_an_rms() {
    let sine = current_log("spindle_current_a", 400, |t| {
        10.0 * (2.0 * std::f64::consts::PI * 50.0 * t).sin()
    });
    let log = load(sine.as_bytes(), None).unwrap();
    let column = &log.columns[1];
    assert_eq!(column.role, Some(Role::PhaseCurrent));
    let why = column.role_reason.as_deref().unwrap();
    assert!(why.contains("the word \"current\""), "{why}");
    assert!(why.contains("swings down to -10"), "{why}");
    assert!(why.contains("an RMS is never negative"), "{why}");
    // An RMS value with a little noise around an offset near zero stays an RMS.
    let rms = current_log("spindle_current_a", 400, |t| {
        0.5 + 5.0 * t - 0.6 * (t * 1e3 % 2.0)
    });
    let log = load(rms.as_bytes(), None).unwrap();
    assert_eq!(log.columns[1].role, Some(Role::RmsCurrent));
}
