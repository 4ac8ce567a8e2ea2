//! "Allocation-free per step" — the plant's, the filters' and the fuzzy engine's promise —
//! checked by counting: `allocation_counter::measure` counts the heap allocations of this thread
//! while the closure runs, and stepping after construction must make none.
#![cfg(not(target_arch = "wasm32"))]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use cutlab::control::fuzzy::engine::Defuzzifier;
use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
use cutlab::machine::{Machine, OverrideCommand};
use cutlab::plant::Preset;
use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use cutlab::signal::filter::SosFilterBank;

#[test]
fn the_counter_sees_an_allocation() {
    // Without this, a zero count could mean a counter that is not installed.
    let info = allocation_counter::measure(|| {
        std::hint::black_box(vec![1u8; 64]);
    });
    assert!(info.count_total >= 1);
}

#[test]
fn stepping_every_preset_machine_allocates_nothing() {
    let command = OverrideCommand {
        override_pct: 100.0,
        feed_hold: false,
    };
    for preset in Preset::ALL {
        let mut machine = preset.machine(7).unwrap();
        // Past the spindle start and into the cut.
        for _ in 0..20_000 {
            machine.step(command);
        }
        let info = allocation_counter::measure(|| {
            for _ in 0..50_000 {
                std::hint::black_box(machine.step(command));
            }
        });
        assert_eq!(
            info.count_total,
            0,
            "{}: {} allocations in 50 000 steps",
            preset.name(),
            info.count_total
        );
    }
}

#[test]
fn filtering_and_fuzzy_inference_allocate_nothing() {
    let sos = butter(&ButterworthSpec {
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: Cutoff::Single(50.0),
        sample_rate_hz: 10_000.0,
    })
    .unwrap();
    let mut bank = SosFilterBank::new(&sos, 3).unwrap();
    let mut block = vec![0.25; 3 * 4096];
    let mut engine = paper_002_engine(&RuleBase::Dynamics.table(), Defuzzifier::Centroid).unwrap();
    let mut out = [0.0];
    let info = allocation_counter::measure(|| {
        bank.process_slice(&mut block);
        for i in 0..1000 {
            let e = -6.0 + 12.0 * f64::from(i) / 1000.0;
            engine.evaluate(&[e, -0.5 * e], &mut out);
        }
    });
    assert_eq!(info.count_total, 0);
}

#[test]
fn an_engine_with_many_output_terms_reserves_memory_linear_in_them() {
    use cutlab::control::fuzzy::engine::{
        Defuzzifier, Engine, InputVariable, Norm, OutputVariable, Rule, SNorm, Term, WeightedKind,
    };
    use cutlab::control::fuzzy::membership::Shape;
    // 10 000 output terms once reserved their pairwise crossings: about 25 GB.
    let terms = |n: usize| -> Vec<Term> {
        (0..n)
            .map(|i| Term {
                name: format!("t{i}"),
                shape: Shape::Triangle {
                    a: i as f64,
                    b: i as f64 + 0.5,
                    c: i as f64 + 1.0,
                },
            })
            .collect()
    };
    let n = 10_000;
    let input = InputVariable {
        name: "x".into(),
        min: 0.0,
        max: n as f64 + 1.0,
        lock_range: true,
        terms: terms(n),
    };
    let output = OutputVariable {
        name: "y".into(),
        min: 0.0,
        max: n as f64 + 1.0,
        lock_range: false,
        terms: terms(n),
        defuzzifier: Defuzzifier::Centroid,
        default_value: 0.0,
        lock_previous: false,
        aggregation: Some(SNorm::Maximum),
        resolution: 100,
        weighted_kind: WeightedKind::Automatic,
    };
    let rules: Vec<Rule> = (0..n)
        .map(|i| Rule::all_of(&[(0, i)], &[(0, i)], 1.0).unwrap())
        .collect();
    let info = allocation_counter::measure(|| {
        let engine = Engine::new(
            "big",
            vec![input],
            vec![output],
            rules,
            Norm::Minimum,
            Norm::Minimum,
        );
        assert!(engine.is_ok());
    });
    // A few kilobytes per term, not n² crossings.
    assert!(
        info.bytes_max < 4_000 * n as u64,
        "{} bytes for {n} terms",
        info.bytes_max
    );
}

/// An FLL engine whose output has `n` terms, with one rule naming each.
fn fll_with_terms_and_rules(n: usize) -> String {
    use std::fmt::Write as _;
    let mut text = String::from(
        "Engine: many\nInputVariable: x\n  range: 0 1\n  term: a Triangle 0 0.5 1\n\
         OutputVariable: y\n",
    );
    let _ = writeln!(text, "  range: 0 {}", n + 1);
    for i in 0..n {
        let _ = writeln!(text, "  term: t{i} Triangle {i} {i}.5 {}", i + 1);
    }
    text.push_str("RuleBlock: rules\n");
    for i in 0..n {
        let _ = writeln!(text, "  rule: if x is a then y is t{i}");
    }
    text
}

#[test]
fn parsing_many_terms_and_rules_allocates_linearly_in_them() {
    use cutlab::control::fuzzy::fll::parse;
    // Each rule's look-up once listed every variable's terms: rules × terms bytes, 6.4 GB for
    // 20 000 of each (and 80 000 took 100 GB of allocations, 21 s).
    let measure = |n: usize| {
        let text = fll_with_terms_and_rules(n);
        let info = allocation_counter::measure(|| {
            assert!(parse(&text).is_ok());
        });
        (info.bytes_total, info.count_total)
    };
    let n = 20_000;
    let (bytes, count) = measure(n);
    let (bytes_twice, count_twice) = measure(2 * n);
    // A few hundred bytes and a handful of allocations per line, whatever the size.
    for (lines, bytes, count) in [(2 * n, bytes, count), (4 * n, bytes_twice, count_twice)] {
        assert!(
            bytes < 2_000 * lines as u64,
            "{bytes} bytes for {lines} lines"
        );
        assert!(
            count < 20 * lines as u64,
            "{count} allocations for {lines} lines"
        );
    }
    // Twice the terms and rules, about twice the work: n² would make it four times.
    assert!(bytes_twice < 5 * bytes / 2, "{bytes} → {bytes_twice} bytes");
    assert!(
        count_twice < 5 * count / 2,
        "{count} → {count_twice} allocations"
    );
}
