//! What the native benchmarks share: their one option and their CPU clock (on a shared machine
//! the wall time includes waiting for a core).

/// `--repeats N` from the command line (3 without it); exits with `usage` on anything else.
pub fn repeats_from_args(usage: &str) -> usize {
    let mut args = std::env::args().skip(1);
    let mut repeats = 3usize;
    while let Some(arg) = args.next() {
        match (arg.as_str(), args.next().and_then(|v| v.parse().ok())) {
            ("--repeats", Some(n)) => repeats = n,
            _ => {
                eprintln!("usage: {usage}");
                std::process::exit(2);
            }
        }
    }
    repeats.max(1)
}

/// Seconds this thread has run on a processor (Linux's /proc/thread-self/schedstat; NaN
/// elsewhere).
pub fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}
