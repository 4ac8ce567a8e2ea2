//! The `cutlab` command line. All logic lives in `cutlab::cli`; this only binds the process's
//! streams and turns an error into one line on stderr and a non-zero exit.

use std::io::{self, Write};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let stdin = io::stdin();
    let mut stdin = stdin.lock();
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
