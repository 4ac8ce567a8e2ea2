//! Helpers shared by the command-line tests: the CLI driven in-process.
// Each test binary uses a different subset of these helpers.
#![allow(dead_code)]

use cutlab::cli::{run, Io};

/// Runs the CLI on `args` with `stdin`; returns (result, stdout bytes).
pub fn cutlab_bytes(args: &[&str], stdin: &[u8]) -> (Result<(), String>, Vec<u8>) {
    let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    let mut input = stdin;
    let mut output = Vec::new();
    let result = run(
        &args,
        &mut Io {
            stdin: &mut input,
            stdout: &mut output,
        },
    );
    (result.map_err(|e| e.to_string()), output)
}

/// Runs the CLI on `args` with text on stdin; returns (result, stdout as text).
pub fn cutlab_text(args: &[&str], stdin: &str) -> (Result<(), String>, String) {
    let (result, out) = cutlab_bytes(args, stdin.as_bytes());
    (result, String::from_utf8_lossy(&out).into_owned())
}
