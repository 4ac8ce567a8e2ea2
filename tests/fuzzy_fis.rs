//! MATLAB's FIS format: hostile and mutated files are refused at their line, never panic; what
//! loads writes back as itself. (The corpus checks are in `tests/fuzzy_corpus.rs`.)
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use cutlab::control::fuzzy::fis::{parse, write};
use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
use cutlab::control::fuzzy::{engine::Defuzzifier, fll, Format};
use cutlab::rng::Rng;

/// A two-input engine in MATLAB's format with most of its features: every MATLAB membership
/// function, hedges, `or`, weights.
const BASE: &str = "% written by hand for the tests
[System]
Name='mixer'
Type='mamdani'
Version=2.0
NumInputs=2
NumOutputs=1
NumRules=5
AndMethod='min'
OrMethod='max'
ImpMethod='prod'
AggMethod='probor'
DefuzzMethod='centroid'

[Input1]
Name='E'
Range=[-6 6]
NumMFs=4
MF1='N':'trapmf',[-7 -6 -3 0]
MF2='Z':'gaussmf',[1.5 0]
MF3='P':'gbellmf',[3 2 6]
MF4='W':'pimf',[-2 -1 1 2]

[Input2]
Name='EC'
Range=[-6 6]
NumMFs=3
MF1='N':'sigmf',[-2 -2]
MF2='Z':'gauss2mf',[1 -0.5 1 0.5]
MF3='P':'dsigmf',[3 1 3 5]

[Output1]
Name='U'
Range=[-6 6]
NumMFs=4
MF1='down':'zmf',[-6 -1]
MF2='hold':'trimf',[-2 0 2]
MF3='up':'smf',[1 6]
MF4='bump':'psigmf',[4 -1 -4 1]

[Rules]
1 1, 1 (1) : 1
2 0, 2 (0.5) : 1
3.2 -3, 3 (1) : 2
-2.3 2.05, 4 (1) : 1
4.01 0.99, 2 (1) : 1
";

#[test]
fn the_base_file_reads_and_evaluates_inside_the_universe() {
    let mut engine = parse(BASE).unwrap();
    assert_eq!(engine.rules().len(), 5);
    assert_eq!(
        engine.rule_text(2),
        "if E is very P or EC is not P then U is up"
    );
    assert_eq!(
        engine.rule_text(3),
        "if E is not extremely Z and EC is somewhat Z then U is bump"
    );
    assert_eq!(
        engine.rule_text(4),
        "if E is seldom W and EC is any then U is hold"
    );
    let mut out = [0.0];
    for (e, ec) in [(-5.0, -5.0), (0.0, 0.0), (4.0, 3.0)] {
        engine.evaluate(&[e, ec], &mut out);
        assert!((-6.0..=6.0).contains(&out[0]), "({e}, {ec}) → {}", out[0]);
    }
    // The same engine through FLL and back evaluates identically.
    let mut via_fll = fll::parse(&fll::write(&engine)).unwrap();
    let mut again = [0.0];
    via_fll.evaluate(&[1.0, -2.0], &mut again);
    engine.evaluate(&[1.0, -2.0], &mut out);
    assert_eq!(out[0].to_bits(), again[0].to_bits());
    assert_eq!(Format::of("mixer.txt", BASE), Format::Fis);
}

#[test]
fn what_fis_cannot_say_is_refused_saying_so() {
    // Paper 002's inputs lock their range, which FIS has no key for.
    let paper = paper_002_engine(&RuleBase::Dynamics.table(), Defuzzifier::Centroid).unwrap();
    let e = write(&paper).unwrap_err().to_string();
    assert_eq!(e, "FIS cannot express this engine: input E locks its range (a value outside it is taken at its nearest end), which FIS cannot say; write it as FLL");
    let text = fll::write(&paper).replace("lock-range: true", "lock-range: false");
    let unlocked = fll::parse(&text).unwrap();
    let back = parse(&write(&unlocked).unwrap()).unwrap();
    assert_eq!(back.rules(), unlocked.rules());
    // An `and` inside an `or`.
    let mixed = text.replacen(
        "rule: if E is NB and EC is NB then U is NB",
        "rule: if (E is NB or EC is NS) and EC is NB then U is NB",
        1,
    );
    let e = write(&fll::parse(&mixed).unwrap()).unwrap_err().to_string();
    assert!(e.ends_with("rule 1 mixes \"and\" and \"or\""), "{e}");
}

/// A word to put in place of one in a FIS line.
fn hostile_word(rng: &mut Rng) -> &'static str {
    const WORDS: [&str; 20] = [
        "NaN", "inf", "-inf", "1e309", "-0", "1e-320", "", "x", "[", "]", "(", ")", ":", ",", "'",
        "=", "trimf", "9.99", "-1.5", "é∂",
    ];
    WORDS[(rng.next_u64() % WORDS.len() as u64) as usize]
}

#[test]
fn random_and_mutated_fis_loads_every_rule_and_term_or_is_refused_at_its_line() {
    let original: Vec<String> = BASE.lines().map(String::from).collect();
    let mut rng = Rng::seed_from(33);
    let (mut loaded, mut refused) = (0, 0);
    for round in 0..3000 {
        let mut doc = original.clone();
        for _ in 0..1 + rng.next_u64() % 3 {
            let at = (rng.next_u64() % doc.len().max(1) as u64) as usize;
            if doc.is_empty() {
                break;
            }
            match rng.next_u64() % 6 {
                0 => {
                    doc.remove(at);
                }
                1 => {
                    let line = doc[at].clone();
                    doc.insert(at, line);
                }
                2 | 3 => {
                    let mut words: Vec<String> = doc[at].split(' ').map(String::from).collect();
                    let w = (rng.next_u64() % words.len() as u64) as usize;
                    words[w] = hostile_word(&mut rng).to_string();
                    doc[at] = words.join(" ");
                }
                4 => {
                    let cut = (rng.next_u64() % (doc[at].len() as u64 + 1)) as usize;
                    let cut = (0..=cut)
                        .rev()
                        .find(|&c| doc[at].is_char_boundary(c))
                        .unwrap();
                    doc[at].truncate(cut);
                }
                _ => {
                    let other = original[(rng.next_u64() % original.len() as u64) as usize].clone();
                    doc.insert(at, other);
                }
            }
        }
        let text = doc.join("\n");
        match parse(&text) {
            Ok(mut engine) => {
                loaded += 1;
                // Every rule line of the file is a rule of the engine: none dropped.
                let mut in_rules = false;
                let mut rules = 0;
                for l in text.lines().map(str::trim) {
                    if l.starts_with('[') {
                        in_rules = l == "[Rules]";
                    } else if in_rules && !(l.is_empty() || l.starts_with('%')) {
                        rules += 1;
                    }
                }
                assert_eq!(engine.rules().len(), rules, "round {round}\n{text}");
                // It writes back as itself (when FIS can say it), and evaluates its ranges.
                if let Ok(again) = write(&engine) {
                    let back = parse(&again).unwrap();
                    assert_eq!(back.rules(), engine.rules(), "round {round}");
                    assert_eq!(back.inputs(), engine.inputs(), "round {round}");
                }
                let inputs: Vec<f64> = engine
                    .inputs()
                    .iter()
                    .map(|v| v.min + (v.max - v.min) * rng.uniform())
                    .collect();
                let mut outputs = vec![0.0; engine.outputs().len()];
                engine.evaluate(&inputs, &mut outputs);
            }
            Err(e) => {
                refused += 1;
                let e = e.to_string();
                assert!(!e.contains('\n') && e.len() < 400, "round {round}: {e}");
                if let Some(line) = e.strip_prefix("line ").and_then(|r| r.split(':').next()) {
                    let line: usize = line.parse().unwrap();
                    assert!((1..=doc.len()).contains(&line), "round {round}: {e}");
                }
            }
        }
    }
    assert!(
        loaded > 300 && refused > 500,
        "{loaded} loaded, {refused} refused"
    );
}

/// A file whose `[Rules]` section is empty, or missing, is refused at load as an FLL file without
/// rules is: the engine would hold its output at its default whatever the inputs, a fixed feed
/// without a word. A missing variable is still named first.
#[test]
fn a_file_without_rules_is_refused_saying_where() {
    let rules_at = BASE.find("[Rules]").unwrap();
    let rules_line = BASE[..rules_at].lines().count() + 1;
    let empty = format!("{}[Rules]\n", &BASE[..rules_at]);
    let e = parse(&empty).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!(
            "line {rules_line}: the [Rules] section is empty: a fuzzy engine without rules holds \
             every output at its default"
        )),
        "{e}"
    );
    let missing = parse(&BASE[..rules_at]).unwrap_err().to_string();
    assert!(
        missing.starts_with("the file has no [Rules] section: a fuzzy engine without rules"),
        "{missing}"
    );
    assert!(parse(BASE).is_ok());
}
