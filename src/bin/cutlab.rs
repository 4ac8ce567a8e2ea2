//! The `cutlab` command line. All logic lives in `cutlab::cli`; this only binds the process's
//! streams and turns an error into one line on stderr and a non-zero exit.

use std::io::{self, Write};
use std::process::ExitCode;

/// Standard output, remembering whether the reader at its other end went away: only a write
/// to stdout that met a closed pipe makes an error quiet, never an error that merely mentions a
/// broken pipe (a file named "Broken pipe.csv", a device that exited).
struct Stdout<W: Write> {
    inner: W,
    closed: bool,
}

impl<W: Write> Stdout<W> {
    fn watch<T>(&mut self, result: io::Result<T>) -> io::Result<T> {
        if let Err(e) = &result {
            if e.kind() == io::ErrorKind::BrokenPipe {
                self.closed = true;
            }
        }
        result
    }
}

impl<W: Write> Write for Stdout<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let result = self.inner.write(buf);
        self.watch(result)
    }

    fn flush(&mut self) -> io::Result<()> {
        let result = self.inner.flush();
        self.watch(result)
    }
}

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
    let mut stdout = Stdout {
        inner: io::BufWriter::new(stdout.lock()),
        closed: false,
    };
    let result = cutlab::cli::run(
        &args,
        &mut cutlab::cli::Io {
            stdin: &mut stdin,
            stdout: &mut stdout,
        },
    );
    let flushed = stdout.flush();
    match (result, flushed) {
        // The reader of our output went away (`cutlab … | head`): nothing worth reporting.
        _ if stdout.closed => ExitCode::SUCCESS,
        (Ok(()), Ok(())) => ExitCode::SUCCESS,
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
