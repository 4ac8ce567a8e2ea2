//! The `cutlab` command line. All logic lives in `cutlab::cli`; this only binds the process's
//! streams and turns an error into one line on stderr and a non-zero exit.

use std::io::{self, Write};
use std::process::ExitCode;

fn main() -> ExitCode {
    // args_os: an argument that is not UTF-8 (a Latin-1 file name) is an error, not a panic.
    let args: Result<Vec<String>, _> = std::env::args_os()
        .skip(1)
        .map(|a| a.into_string())
        .collect();
    let args = match args {
        Ok(args) => args,
        Err(bad) => {
            let _ = writeln!(
                io::stderr(),
                "cutlab: error: argument {bad:?} is not valid UTF-8"
            );
            return ExitCode::FAILURE;
        }
    };
    // Not locked for the whole run: `cutlab device` reads stdin on a thread of its own.
    let mut stdin = io::BufReader::new(io::stdin());
    let stdout = io::stdout();
    let mut stdout = io::BufWriter::new(stdout.lock());
    let result = cutlab::cli::run(
        &args,
        &mut cutlab::cli::Io {
            stdin: &mut stdin,
            stdout: &mut stdout,
        },
    );
    let flushed = stdout.flush();
    match (result, flushed) {
        (Ok(()), Ok(())) => ExitCode::SUCCESS,
        // A closed pipe (`cutlab … | head`) is not an error worth reporting.
        (Err(e), _) if e.0.contains("Broken pipe") => ExitCode::SUCCESS,
        (Ok(()), Err(e)) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        (Err(e), _) => {
            let _ = writeln!(io::stderr(), "cutlab: error: {e}");
            ExitCode::FAILURE
        }
        (Ok(()), Err(e)) => {
            let _ = writeln!(io::stderr(), "cutlab: error: cannot write output: {e}");
            ExitCode::FAILURE
        }
    }
}
