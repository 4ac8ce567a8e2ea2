//! `cutlab fuzzy eval` and `cutlab fuzzy export`: the fuzzy engine on FLL files.

use std::io::BufRead;

use super::{help_text_for, wants_help, CliError, Io, OptionSpec, Options};
use crate::control::fuzzy::engine::Defuzzifier;
use crate::control::fuzzy::fll::{parse, write};
use crate::control::fuzzy::rules::{paper_002_engine, RuleBase};

const EVAL_OPTIONS: &[OptionSpec] = &[OptionSpec::value(
    "fll",
    "FILE",
    "The engine, in fuzzylite's FLL format (Mamdani)",
)];

const EXPORT_OPTIONS: &[OptionSpec] = &[
    OptionSpec::value(
        "rules",
        "experience|dynamics",
        "Which of paper 002's rule tables",
    ),
    OptionSpec::value(
        "defuzzifier",
        "centroid|weighted-average|mean-of-maximum",
        "How the output is defuzzified (default centroid)",
    ),
];

/// Runs `cutlab fuzzy`.
pub fn run(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    match args.first().map(String::as_str) {
        Some("eval") => eval(&args[1..], io),
        Some("export") => export(&args[1..], io),
        None | Some("--help" | "-h") => help_text_for(
            io,
            "cutlab fuzzy eval --fll FILE | cutlab fuzzy export --rules experience|dynamics",
            "Evaluate a Mamdani engine given in fuzzylite's FLL format (one evaluation per stdin\n\
             line: the input values in the order the file declares them), or print paper 002's\n\
             engine as FLL.",
            &[],
        ),
        Some(other) => Err(CliError::new(format!(
            "unknown fuzzy subcommand {other:?}; use eval or export"
        ))),
    }
}

fn eval(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    if wants_help(args) {
        return help_text_for(
            io,
            "cutlab fuzzy eval --fll FILE < inputs.txt",
            "Read one evaluation per line of standard input (input values separated by spaces, in\n\
             the order the FLL file declares its input variables) and print the output values,\n\
             space-separated, at full precision. Blank lines and lines starting with # are skipped.",
            EVAL_OPTIONS,
        );
    }
    let options = Options::parse(args, EVAL_OPTIONS)?;
    options.reject_positionals("the inputs come on standard input")?;
    let path: String = options.require("fll")?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| CliError::new(format!("{path}: cannot read: {e}")))?;
    let mut engine = parse(&text).map_err(|e| CliError::new(format!("{path}: {e}")))?;
    let n_inputs = engine.inputs().len();
    let mut outputs = vec![0.0; engine.outputs().len()];
    let mut inputs = Vec::with_capacity(n_inputs);
    for (index, line) in io.stdin.lines().enumerate() {
        let line = line?;
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        inputs.clear();
        for word in trimmed.split_whitespace() {
            let value: f64 = word.parse().map_err(|_| {
                CliError::new(format!(
                    "stdin line {}: cannot parse {word:?} as a number",
                    index + 1
                ))
            })?;
            inputs.push(value);
        }
        if inputs.len() != n_inputs {
            return Err(CliError::new(format!(
                "stdin line {}: {} values, the engine has {n_inputs} inputs ({})",
                index + 1,
                inputs.len(),
                engine
                    .inputs()
                    .iter()
                    .map(|v| v.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        engine.evaluate(&inputs, &mut outputs);
        let line: Vec<String> = outputs.iter().map(|v| format!("{v:?}")).collect();
        writeln!(io.stdout, "{}", line.join(" "))?;
    }
    Ok(())
}

fn export(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    if wants_help(args) {
        return help_text_for(
            io,
            "cutlab fuzzy export --rules experience|dynamics [--defuzzifier NAME]",
            "Print paper 002's engine (E, EC → U on [-6, 6], seven triangles each, 49 rules) as FLL.",
            EXPORT_OPTIONS,
        );
    }
    let options = Options::parse(args, EXPORT_OPTIONS)?;
    options.reject_positionals("")?;
    let rules: String = options.require("rules")?;
    let base = RuleBase::ALL
        .into_iter()
        .find(|b| b.name() == rules)
        .ok_or_else(|| {
            CliError::new(format!("--rules: {rules:?} is not experience or dynamics"))
        })?;
    let defuzzifier = match options.text("defuzzifier").unwrap_or("centroid") {
        "centroid" => Defuzzifier::Centroid,
        "weighted-average" => Defuzzifier::WeightedAverage,
        "mean-of-maximum" => Defuzzifier::MeanOfMaximum,
        other => {
            return Err(CliError::new(format!(
                "--defuzzifier: {other:?} is not centroid, weighted-average or mean-of-maximum"
            )))
        }
    };
    let engine =
        paper_002_engine(&base.table(), defuzzifier).map_err(|e| CliError::new(e.to_string()))?;
    io.stdout.write_all(write(&engine).as_bytes())?;
    Ok(())
}
