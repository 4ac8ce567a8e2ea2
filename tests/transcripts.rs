//! Every terminal transcript in docs/ is what the tool prints today.
//!
//! A transcript is a ```` ```text ```` block whose first line is a shell command (`$ cutlab …`,
//! continued by a trailing `\`); the lines after a command, up to the next `$ ` line or the end of
//! the block, are what the command printed on stdout (progress and notes on stderr are not shown
//! in the docs, so they are not compared). A document's commands run in order, through `sh`, in
//! one scratch directory where `tests/`, `www/`, `docs/` and `scripts/` of the checkout are linked,
//! so a command reads the files the docs name and writes its outputs (`--save-calibration
//! export-calibration.json`) where a later command of the page finds them, as a reader following
//! the page would, and nothing lands in the checkout. `cutlab` is the binary
//! this test was built with.
//!
//! `cargo test --features cli --test transcripts` fails on a transcript whose output the tool no
//! longer prints, naming the document, the line and the first line that differs;
//! `CUTLAB_BLESS=1` (what `scripts/docs` runs) writes the tool's output into the documents
//! instead. A transcript going stale is how a worked example's prose came to read numbers the
//! tool no longer gives (docs/tuning.md, objective 3.35 against 2.91): after blessing, reread the
//! paragraph beside each changed transcript.
#![cfg(all(unix, feature = "cli"))]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// One command of a transcript and the output the document shows for it.
#[derive(Debug, PartialEq)]
struct Step {
    /// The command as a shell reads it (continuation lines kept, without the `$ `).
    command: String,
    /// The shown output, one string per line.
    output: Vec<String>,
    /// The document's lines (0-based, end exclusive) that hold the output.
    output_lines: std::ops::Range<usize>,
}

/// One transcript: its steps, and the document line (0-based) of its first command.
#[derive(Debug, PartialEq)]
struct Transcript {
    line: usize,
    steps: Vec<Step>,
}

/// The transcripts of a Markdown document.
fn transcripts(doc: &str) -> Vec<Transcript> {
    let lines: Vec<&str> = doc.lines().collect();
    let mut found = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let opens = lines[i].trim_end() == "```text";
        let first = lines.get(i + 1).copied().unwrap_or_default();
        if !(opens && first.starts_with("$ ")) {
            i += 1;
            continue;
        }
        let start = i + 1;
        let end = (start..lines.len())
            .find(|&k| lines[k].trim_end() == "```")
            .unwrap_or(lines.len());
        let mut steps = Vec::new();
        let mut k = start;
        while k < end {
            let mut command = lines[k].trim_start_matches("$ ").to_string();
            while command.ends_with('\\') && k + 1 < end {
                k += 1;
                command.push('\n');
                command.push_str(lines[k]);
            }
            k += 1;
            let from = k;
            while k < end && !lines[k].starts_with("$ ") {
                k += 1;
            }
            steps.push(Step {
                command,
                output: lines[from..k].iter().map(|l| l.to_string()).collect(),
                output_lines: from..k,
            });
        }
        found.push(Transcript { line: start, steps });
        i = end + 1;
    }
    found
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A scratch directory for one transcript, with the checkout's inputs linked in.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cutlab-transcript-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for linked in ["tests", "www", "docs", "scripts"] {
        std::os::unix::fs::symlink(root().join(linked), dir.join(linked)).unwrap();
    }
    dir
}

/// What `command` prints on stdout, run by `sh` in `dir` with this build's `cutlab` first on the
/// path. A failing command is a failed test unless the document shows it failing (it never does
/// today), so its stderr is returned as the error.
fn run(command: &str, dir: &Path) -> Result<Vec<String>, String> {
    let exe = PathBuf::from(env!("CARGO_BIN_EXE_cutlab"));
    let path = format!(
        "{}:{}",
        exe.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("sh")
        .arg("-c")
        .arg(command)
        .current_dir(dir)
        .env("PATH", path)
        .output()
        .unwrap();
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect())
}

/// The documents' transcripts rerun; with `bless`, the documents rewritten with what the tool
/// printed. Returns the differences found (before any rewrite).
fn check(bless: bool) -> Vec<String> {
    let mut problems = Vec::new();
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    for doc in docs {
        let name = doc.strip_prefix(root()).unwrap().display().to_string();
        let text = std::fs::read_to_string(&doc).unwrap();
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        // Replacements from the last line up, so earlier line numbers stay valid.
        let mut rewrites: Vec<(std::ops::Range<usize>, Vec<String>)> = Vec::new();
        let dir = scratch(&doc.file_stem().unwrap().to_string_lossy());
        for transcript in transcripts(&text) {
            for step in &transcript.steps {
                let printed = match run(&step.command, &dir) {
                    Ok(printed) => printed,
                    Err(stderr) => {
                        problems.push(format!(
                            "{name}:{}: `{}` failed: {}",
                            transcript.line + 1,
                            step.command,
                            stderr.trim()
                        ));
                        continue;
                    }
                };
                if printed != step.output {
                    let first = (0..printed.len().max(step.output.len()))
                        .find(|&k| printed.get(k) != step.output.get(k))
                        .unwrap_or(0);
                    problems.push(format!(
                        "{name}:{}: `{}` printed\n    {:?}\n  where the document shows (line {})\n    {:?}",
                        transcript.line + 1,
                        step.command.lines().next().unwrap_or_default(),
                        printed.get(first).map(String::as_str).unwrap_or("(nothing)"),
                        step.output_lines.start + first + 1,
                        step.output.get(first).map(String::as_str).unwrap_or("(nothing)"),
                    ));
                    rewrites.push((step.output_lines.clone(), printed));
                }
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
        if bless && !rewrites.is_empty() {
            for (range, printed) in rewrites.into_iter().rev() {
                lines.splice(range, printed);
            }
            let mut new = lines.join("\n");
            if text.ends_with('\n') {
                new.push('\n');
            }
            std::fs::write(&doc, new).unwrap();
            eprintln!("transcripts: wrote {name}");
        }
    }
    problems
}

#[test]
fn every_transcript_in_the_docs_is_what_the_tool_prints() {
    let bless = std::env::var_os("CUTLAB_BLESS").is_some();
    let found = check(bless);
    if bless {
        let left = check(false);
        assert!(left.is_empty(), "after blessing:\n{}", left.join("\n"));
        return;
    }
    assert!(
        found.is_empty(),
        "the docs show output the tool no longer prints (CUTLAB_BLESS=1 cargo test --features \
         cli --test transcripts, or scripts/docs, writes the tool's; then reread the prose beside \
         each changed transcript):\n{}",
        found.join("\n")
    );
}

#[test]
fn a_transcript_is_its_commands_and_the_lines_each_printed() {
    let doc = "Intro.\n\n```text\n$ cutlab a \\\n    --b\none\ntwo\n$ head -1 x\nthree\n```\n\n\
```text\nnot a transcript\n```\n```text\n$ cutlab quiet\n```\n";
    let found = transcripts(doc);
    assert_eq!(found.len(), 2);
    assert_eq!(found[0].line, 3);
    assert_eq!(found[0].steps[0].command, "cutlab a \\\n    --b");
    assert_eq!(found[0].steps[0].output, ["one", "two"]);
    assert_eq!(found[0].steps[0].output_lines, 5..7);
    assert_eq!(found[0].steps[1].command, "head -1 x");
    assert_eq!(found[0].steps[1].output, ["three"]);
    assert_eq!(found[1].steps[0].command, "cutlab quiet");
    assert!(found[1].steps[0].output.is_empty());
}
