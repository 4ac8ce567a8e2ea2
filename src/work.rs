//! Long computations done in pieces: one interface for the teach cut, the closed loop, a lab run,
//! the reference search and an open-loop recording.
//!
//! A browser cannot block its only thread for the seconds a full cut takes, and a real machine
//! delivers its samples as they come. So every long job in cutlab is a [`Work`]: it advances by a
//! budget of units (control periods for a loop, periods or samples for a recording), says how far
//! it has got, and hands over its output once done. The browser's runner slices any `Work` across
//! frames with a progress bar and a Cancel button; the command line, the tests and the browser's
//! computation workers (which take closed-loop runs off the page's thread) call
//! [`Work::run_to_end`] or advance it in one go.

use std::fmt;

/// How far a piece of work has got, for a progress bar.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// What it is doing now, for a person ("Teach cut", "Closed loop", "Reference run 2 of 9 …").
    /// It changes only where the work changes kind: the browser's runner starts a new stage in
    /// a chunk of its own, since the pace of the last stage says nothing of the next one's.
    pub stage: String,
    /// Rough fraction of the whole done, 0–1.
    pub fraction: f64,
}

impl Progress {
    /// `stage` at `fraction` (clamped to 0–1; NaN reads as 0).
    pub fn new(stage: impl Into<String>, fraction: f64) -> Self {
        Self {
            stage: stage.into(),
            fraction: if fraction.is_nan() {
                0.0
            } else {
                fraction.clamp(0.0, 1.0)
            },
        }
    }
}

/// Work that can be done a piece at a time.
///
/// `advance` may be called any number of times with any budget; calling it after the work is
/// done does nothing and returns `Ok(true)`. The output is the same whatever budgets were used:
/// a budget only says where the work may pause.
pub trait Work {
    /// What the finished work gives.
    type Output;
    /// Why it could not be done; shown to a person as is.
    type Error: fmt::Display;

    /// Does at most `budget` units of work; returns true once done.
    fn advance(&mut self, budget: usize) -> Result<bool, Self::Error>;

    /// What it is doing and how far it has got.
    fn progress(&self) -> Progress;

    /// The output, once [`Work::advance`] has returned true. Called before that, or a second
    /// time, it returns an error.
    fn finish(&mut self) -> Result<Self::Output, Self::Error>;

    /// Does all the work at once.
    fn run_to_end(mut self) -> Result<Self::Output, Self::Error>
    where
        Self: Sized,
    {
        while !self.advance(RUN_TO_END_BUDGET)? {}
        self.finish()
    }
}

/// The budget [`Work::run_to_end`] advances by: large, since nothing waits between pieces.
const RUN_TO_END_BUDGET: usize = 10_000;

/// `f` over `items` on every core: natively, one thread per core, each taking the next item
/// not yet started as it becomes free (so a long item does not hold back the short ones queued
/// behind it); in wasm, in order on the one thread. The results come in `items`' order either
/// way, so the output does not depend on the number of cores.
///
/// ```
/// use cutlab::work::parallel_map;
/// let squares = parallel_map(&[1, 2, 3, 4, 5], |x| x * x);
/// assert_eq!(squares, vec![1, 4, 9, 16, 25]);
/// ```
///
/// # Panics
///
/// If `f` panics on an item (a bug), the panic is carried to the caller once the other threads
/// have stopped.
pub fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    parallel_map_reporting(items, available_threads(), f, |_, _| {})
}

/// The threads this machine runs at once (1 in wasm, or if the system will not say).
pub fn available_threads() -> usize {
    #[cfg(not(target_arch = "wasm32"))]
    return std::thread::available_parallelism().map_or(1, |n| n.get());
    #[cfg(target_arch = "wasm32")]
    1
}

/// `f` over `items` on up to `threads` threads natively (each thread takes the next item as soon
/// as it is free, so one slow item does not hold the others back), in order in wasm. `done(i,
/// &result)` is called on the calling thread as each result comes in, in the order they finish;
/// the results are returned in `items`' order whatever the threads.
pub fn parallel_map_reporting<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
    mut done: impl FnMut(usize, &R),
) -> Vec<R> {
    // The browser's one thread runs the items in order.
    #[cfg(target_arch = "wasm32")]
    let _ = threads;
    #[cfg(not(target_arch = "wasm32"))]
    if threads > 1 && items.len() > 1 {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let next = AtomicUsize::new(0);
        let mut slots: Vec<Option<R>> = std::iter::repeat_with(|| None).take(items.len()).collect();
        std::thread::scope(|scope| {
            let (sender, results) = std::sync::mpsc::channel();
            for _ in 0..threads.min(items.len()) {
                let (sender, next, f) = (sender.clone(), &next, &f);
                scope.spawn(move || loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    if sender.send((i, f(item))).is_err() {
                        break;
                    }
                });
            }
            // The loop below ends once every thread has finished (or panicked: the scope then
            // passes the panic on).
            drop(sender);
            for (i, result) in results {
                done(i, &result);
                slots[i] = Some(result);
            }
        });
        return slots.into_iter().flatten().collect();
    }
    items
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let result = f(item);
            done(i, &result);
            result
        })
        .collect()
}

/// Jobs handed out as they become known, run on up to `threads` threads natively (a queue the
/// threads take from in order), in turn on the calling thread in wasm or with one thread.
///
/// `feed` is called on the calling thread: first with `None`, then with each finished job and
/// its result, in the order they finish. It is told how many threads are idle (none is counted
/// idle while jobs wait in the queue) and returns the jobs to queue; the queue ends once nothing
/// is queued or running after a call. A tuning's search feeds its next point's runs this way,
/// and runs ahead of it into the idle threads ([`crate::tuning::plan`]).
pub fn job_queue<J: Send, R: Send>(
    threads: usize,
    run: impl Fn(&J) -> R + Sync,
    mut feed: impl FnMut(Option<(J, R)>, usize) -> Vec<J>,
) {
    #[cfg(not(target_arch = "wasm32"))]
    if threads > 1 {
        use std::sync::{mpsc, Mutex};
        let (queue, taken) = mpsc::channel::<J>();
        let taken = Mutex::new(taken);
        std::thread::scope(|scope| {
            let queue = queue;
            let (finished, results) = mpsc::channel::<(J, R)>();
            for _ in 0..threads {
                let (taken, finished, run) = (&taken, finished.clone(), &run);
                scope.spawn(move || loop {
                    // One thread waits on the queue at a time; the others wait for the lock.
                    let job = match taken.lock() {
                        Ok(receiver) => receiver.recv(),
                        Err(_) => break,
                    };
                    let Ok(job) = job else { break };
                    let result = run(&job);
                    if finished.send((job, result)).is_err() {
                        break;
                    }
                });
            }
            drop(finished);
            let mut out = 0;
            let mut last = None;
            loop {
                for job in feed(last.take(), threads.saturating_sub(out)) {
                    if queue.send(job).is_ok() {
                        out += 1;
                    }
                }
                if out == 0 {
                    break;
                }
                // A thread that panicked ends the queue; the scope then passes the panic on.
                let Ok(done) = results.recv() else { break };
                out -= 1;
                last = Some(done);
            }
            // The threads end once the queue's sender is gone.
            drop(queue);
        });
        return;
    }
    let _ = threads;
    let mut queue = std::collections::VecDeque::new();
    let mut last = None;
    loop {
        let idle = usize::from(queue.is_empty());
        queue.extend(feed(last.take(), idle));
        let Some(job) = queue.pop_front() else { break };
        let result = run(&job);
        last = Some((job, result));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts to a number, `budget` at a time.
    struct CountTo {
        target: usize,
        count: usize,
        taken: bool,
    }

    impl Work for CountTo {
        type Output = usize;
        type Error = String;

        fn advance(&mut self, budget: usize) -> Result<bool, String> {
            self.count = (self.count + budget).min(self.target);
            Ok(self.count == self.target)
        }

        fn progress(&self) -> Progress {
            Progress::new("counting", self.count as f64 / self.target as f64)
        }

        fn finish(&mut self) -> Result<usize, String> {
            if self.count < self.target || self.taken {
                return Err("not done".into());
            }
            self.taken = true;
            Ok(self.count)
        }
    }

    #[test]
    fn parallel_map_keeps_the_order_of_uneven_items() {
        // Items of very different cost finish out of order; the results must not.
        let items: Vec<u64> = (0..23)
            .map(|i| if i % 5 == 0 { 200_000 } else { 10 })
            .collect();
        let sums = parallel_map(&items, |&n| (0..n).fold(0u64, |a, k| a.wrapping_add(k * k)));
        let expected: Vec<u64> = items
            .iter()
            .map(|&n| (0..n).fold(0u64, |a, k| a.wrapping_add(k * k)))
            .collect();
        assert_eq!(sums, expected);
        assert!(parallel_map(&[] as &[u8], |x| *x).is_empty());
    }

    #[test]
    fn run_to_end_gives_the_output_and_finish_refuses_early_or_twice() {
        let work = CountTo {
            target: 25_000,
            count: 0,
            taken: false,
        };
        assert_eq!(work.run_to_end(), Ok(25_000));
        let mut early = CountTo {
            target: 3,
            count: 0,
            taken: false,
        };
        assert!(early.finish().is_err());
        assert_eq!(early.advance(2), Ok(false));
        assert!((early.progress().fraction - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(early.advance(2), Ok(true));
        assert_eq!(early.finish(), Ok(3));
        assert!(early.finish().is_err());
    }

    #[test]
    fn progress_is_clamped_and_nan_reads_as_nothing_done() {
        assert_eq!(Progress::new("x", 1.5).fraction, 1.0);
        assert_eq!(Progress::new("x", -0.5).fraction, 0.0);
        assert_eq!(Progress::new("x", f64::NAN).fraction, 0.0);
    }

    #[test]
    fn a_job_queue_runs_what_it_is_fed_until_nothing_is_left() {
        // Each job n < 20 finished feeds n + 10 and n + 11; the results come back to the feed.
        for threads in [1, 2, 4] {
            let mut seen = Vec::new();
            let mut most_idle = 0;
            job_queue(
                threads,
                |n: &u32| n * 2,
                |finished, idle| {
                    most_idle = most_idle.max(idle);
                    match finished {
                        None => vec![0, 1],
                        Some((n, doubled)) => {
                            assert_eq!(doubled, n * 2);
                            seen.push(n);
                            if n < 20 {
                                vec![n + 10, n + 11]
                            } else {
                                Vec::new()
                            }
                        }
                    }
                },
            );
            seen.sort_unstable();
            let mut expected = vec![0, 1];
            let mut i = 0;
            while i < expected.len() {
                if expected[i] < 20 {
                    expected.extend([expected[i] + 10, expected[i] + 11]);
                }
                i += 1;
            }
            expected.sort_unstable();
            assert_eq!(seen, expected, "{threads} threads");
            assert_eq!(
                most_idle,
                if cfg!(target_arch = "wasm32") {
                    1
                } else {
                    threads
                }
            );
        }
    }
}
