//! `cutlab fuzzy eval` and `cutlab fuzzy export`: the fuzzy engine on FLL and FIS files.

use std::io::BufRead;

use super::args::{reject_extra, required};
use super::{CliError, Io};
use crate::control::fuzzy::engine::{Defuzzifier, Engine};
use crate::control::fuzzy::rules::{paper_002_engine, RuleBase};
use crate::control::fuzzy::{fis, fll, Format};

/// Evaluate a fuzzy engine given in fuzzylite's FLL or MATLAB's FIS format (one evaluation per
/// stdin line: the input values in the order the file declares them), or print an engine as FLL
/// or FIS.
pub(crate) const ABOUT: &str = "Evaluate a fuzzy engine given in fuzzylite's FLL or MATLAB's FIS \
format (one\nevaluation per stdin line: the input values in the order the file declares them), \
or print\npaper 002's engine or an engine file as FLL or FIS.";

/// The options of `cutlab fuzzy`: a subcommand (its help says what each does).
#[derive(Debug, clap::Args)]
pub struct FuzzyArgs {
    #[command(subcommand)]
    command: Option<FuzzyCommand>,
}

#[derive(Debug, clap::Subcommand)]
enum FuzzyCommand {
    /// Evaluate an FLL or FIS engine on each line of standard input
    ///
    /// Read one evaluation per line of standard input (input values separated by spaces, in the
    /// order the file declares its input variables) and print the output values,
    /// space-separated, at full precision. Blank lines and lines starting with # are skipped.
    #[command(verbatim_doc_comment)]
    Eval(EvalArgs),
    /// Print paper 002's engine (E, EC → U on [-6, 6], seven triangles each, 49 rules), or an
    /// engine file, as FLL or (--fis) FIS where FIS can express it (paper 002's engine locks its
    /// inputs' ranges, which only FLL can say)
    Export(ExportArgs),
}

#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    #[arg(
        long = "fll",
        help = "The engine, in fuzzylite's FLL format",
        value_name = "FILE",
        allow_hyphen_values = true
    )]
    fll: Option<String>,
    #[arg(
        long = "fis",
        help = "The engine, in MATLAB's FIS format",
        value_name = "FILE",
        allow_hyphen_values = true
    )]
    fis: Option<String>,
    /// Stray words: refused with a hint where such input goes.
    #[arg(hide = true)]
    extra: Vec<String>,
}

#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    #[arg(
        long = "rules",
        help = "Which of paper 002's rule tables",
        value_name = "experience|dynamics",
        allow_hyphen_values = true
    )]
    rules: Option<String>,
    #[arg(
        long = "engine",
        help = "An engine file to convert instead (FLL or FIS, by extension or content)",
        value_name = "FILE",
        allow_hyphen_values = true
    )]
    engine: Option<String>,
    #[arg(long = "fis", help = "Write MATLAB's FIS format instead of FLL")]
    fis: bool,
    #[arg(
        long = "defuzzifier",
        help = "How the output is defuzzified (default centroid)",
        value_name = "centroid|weighted-average|mean-of-maximum",
        allow_hyphen_values = true
    )]
    defuzzifier: Option<String>,
    /// Stray words: refused with a hint where such input goes.
    #[arg(hide = true)]
    extra: Vec<String>,
}

/// Runs `cutlab fuzzy`.
pub fn run(args: FuzzyArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    match args.command {
        Some(FuzzyCommand::Eval(a)) => eval(a, io),
        Some(FuzzyCommand::Export(a)) => export(a, io),
        None => super::print_help(io, &["fuzzy"]),
    }
}

fn eval(args: EvalArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    reject_extra(&args.extra, "the inputs come on standard input")?;
    let (path, format) = match (&args.fll, &args.fis) {
        (Some(p), None) => (p.clone(), Format::Fll),
        (None, Some(p)) => (p.clone(), Format::Fis),
        (Some(_), Some(_)) => {
            return Err(CliError::new(
                "give the engine once: --fll FILE or --fis FILE",
            ))
        }
        (None, None) => return Err(CliError::new("missing required option --fll or --fis")),
    };
    let text = std::fs::read_to_string(&path)
        .map_err(|e| CliError::new(format!("{path}: cannot read: {e}")))?;
    let mut engine = format
        .parse(&text)
        .map_err(|e| CliError::new(format!("{path}: {e}")))?;
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
                    "stdin line {}: cannot parse {} as a number",
                    index + 1,
                    crate::input::excerpt(word)
                ))
            })?;
            // NaN or ±∞ fires no rule: the engine would print its default as if it were an
            // answer.
            if !value.is_finite() {
                return Err(CliError::new(format!(
                    "stdin line {}: {word:?} is not a finite input",
                    index + 1
                )));
            }
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

fn export(args: ExportArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    reject_extra(&args.extra, "")?;
    let engine = match (&args.engine, &args.rules) {
        (Some(path), None) => {
            if args.defuzzifier.is_some() {
                return Err(CliError::new(
                    "--defuzzifier applies to paper 002's engine (--rules), not to --engine",
                ));
            }
            let text = std::fs::read_to_string(path)
                .map_err(|e| CliError::new(format!("{path}: cannot read: {e}")))?;
            Format::of(path, &text)
                .parse(&text)
                .map_err(|e| CliError::new(format!("{path}: {e}")))?
        }
        (None, _) => paper_002(&args)?,
        (Some(_), Some(_)) => {
            return Err(CliError::new(
                "export either paper 002's engine (--rules) or an engine file (--engine)",
            ))
        }
    };
    let text = if args.fis {
        fis::write(&engine).map_err(|e| CliError::new(e.to_string()))?
    } else {
        fll::write(&engine)
    };
    io.stdout.write_all(text.as_bytes())?;
    Ok(())
}

/// Paper 002's engine with the table and defuzzifier the options name.
fn paper_002(args: &ExportArgs) -> Result<Engine, CliError> {
    let rules: String = required("rules", &args.rules)?;
    let base = RuleBase::ALL
        .into_iter()
        .find(|b| b.name() == rules)
        .ok_or_else(|| {
            CliError::new(format!("--rules: {rules:?} is not experience or dynamics"))
        })?;
    let defuzzifier = match args.defuzzifier.as_deref().unwrap_or("centroid") {
        "centroid" => Defuzzifier::Centroid,
        "weighted-average" => Defuzzifier::WeightedAverage,
        "mean-of-maximum" => Defuzzifier::MeanOfMaximum,
        other => {
            return Err(CliError::new(format!(
                "--defuzzifier: {other:?} is not centroid, weighted-average or mean-of-maximum"
            )))
        }
    };
    paper_002_engine(&base.table(), defuzzifier).map_err(|e| CliError::new(e.to_string()))
}
