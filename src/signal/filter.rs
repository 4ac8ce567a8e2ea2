//! Running a biquad cascade over samples: transposed direct form II, as `scipy.signal.sosfilt`.
//!
//! Each section keeps two state values and computes, per sample,
//!
//! ```text
//! y  = b0·x + s0
//! s0 = (b1·x + s1) − a1·y
//! s1 = b2·x − a2·y
//! ```
//!
//! (scipy evaluates the middle line as `b1·x − a1·y + s1`; the grouping here puts the state
//! addition off the recurrence's critical path, which differs from scipy's result only in the
//! last bits and makes the loop about a third faster.)
//!
//! Two processors share that arithmetic:
//!
//! - [`SosFilter`] filters one channel;
//! - [`SosFilterBank`] filters several interleaved channels (the three phase currents `u v w u v
//!   w …`) with one state per channel. It remembers which channel the next sample belongs to, so
//!   a stream can be fed in pieces of any length.
//!
//! `process_slice` gives exactly the bits of calling `process` on every sample (tests check it,
//! and a digest test checks the bits are the same in wasm). It is faster because it keeps the
//! state of up to eight sections in registers and lets one vector operation do the work of two
//! or four: in the bank, the channels side by side in lanes (coefficients broadcast once, at
//! construction; for three or four channels the kernel is compiled a second time for AVX2 and
//! chosen at run time when the processor has it); on one channel, the sections skewed by one
//! sample each, so that every section's input is already known and two sections advance per
//! operation. See docs/benchmarks.md for the throughput against scipy.
//!
//! NaN or ±∞ in a sample enters the state: every later output of that channel is NaN until
//! [`SosFilter::reset`] or [`SosFilter::set_steady_state`]. Long runs of exact zeros after a
//! signal let the state decay into subnormal numbers, which some processors handle slowly; the
//! values stay correct.

use std::fmt;

use super::sos::{Biquad, Sos};

/// Sections whose state a slice kernel keeps in registers at once.
#[cfg(not(target_arch = "wasm32"))]
const MAX_GROUP: usize = 8;
/// On one channel, groups of at least this many sections use the skewed kernel; below it the
/// scalar loop is latency-bound anyway and the skew's start-up costs more than it gains.
#[cfg(not(target_arch = "wasm32"))]
const SKEW_MIN_SECTIONS: usize = 4;
/// Frames processed per section group before moving to the next group, when a cascade has more
/// sections than one group: small enough that the block stays in the L1 cache.
const BLOCK_FRAMES: usize = 256;

/// One channel of a biquad cascade with its state.
///
/// ```
/// use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
/// use cutlab::signal::filter::SosFilter;
/// let sos = butter(&ButterworthSpec {
///     kind: FilterKind::Lowpass,
///     order: 4,
///     cutoff_hz: Cutoff::Single(50.0),
///     sample_rate_hz: 10_000.0,
/// })
/// .unwrap();
/// let mut filter = SosFilter::new(&sos);
/// // A constant input settles at the DC gain (1 for a low-pass).
/// let mut y = 0.0;
/// for _ in 0..5_000 {
///     y = filter.process(2.0);
/// }
/// assert!((y - 2.0).abs() < 1e-9);
///
/// // The slice form gives exactly the same bits as sample by sample.
/// let mut block = vec![2.0; 100];
/// let mut again = filter.clone();
/// filter.process_slice(&mut block);
/// assert_eq!(block[99], (0..100).map(|_| again.process(2.0)).last().unwrap());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SosFilter {
    sections: Vec<Biquad>,
    /// `[s0, s1]` of each section, flattened: `state[2k]`, `state[2k + 1]`.
    state: Vec<f64>,
    /// The settled state for a constant input of 1 (scipy's `sosfilt_zi`), kept so that
    /// `set_steady_state` does not allocate.
    unit_steady_state: Vec<[f64; 2]>,
    tables: LaneTables,
}

impl SosFilter {
    /// A filter running `sos`, starting from rest (zero state).
    pub fn new(sos: &Sos) -> Self {
        let sections = sos.sections().to_vec();
        let state = vec![0.0; 2 * sections.len()];
        Self {
            tables: LaneTables::new(&sections, 1),
            sections,
            state,
            unit_steady_state: sos.steady_state(),
        }
    }

    /// Filters one sample.
    #[inline]
    pub fn process(&mut self, x: f64) -> f64 {
        let mut value = x;
        for (s, state) in self.sections.iter().zip(self.state.chunks_exact_mut(2)) {
            let y = s.b0 * value + state[0];
            state[0] = (s.b1 * value + state[1]) - s.a1 * y;
            state[1] = s.b2 * value - s.a2 * y;
            value = y;
        }
        value
    }

    /// Filters `samples` in place; the same bits as [`process`](Self::process) on each.
    pub fn process_slice(&mut self, samples: &mut [f64]) {
        let (frames, _) = samples.as_chunks_mut::<1>();
        run_cascade::<1, 1>(&self.tables.one, &mut self.state, frames);
    }

    /// Filters a copy of `input` (a convenience for whole logs; allocates the result).
    pub fn filter(&mut self, input: &[f64]) -> Vec<f64> {
        let mut output = input.to_vec();
        self.process_slice(&mut output);
        output
    }

    /// Back to rest: zero state, as when constructed.
    pub fn reset(&mut self) {
        self.state.fill(0.0);
    }

    /// Sets the state a constant input `x0` would have settled to, so that filtering a signal
    /// starting near `x0` has no start-up transient (scipy's `sosfilt_zi(sos) * x0`).
    ///
    /// ```
    /// use cutlab::signal::sos::Sos;
    /// use cutlab::signal::filter::SosFilter;
    /// let sos = Sos::from_rows(&[[0.25, 0.5, 0.25, 1.0, -0.2, 0.1]]).unwrap();
    /// let mut filter = SosFilter::new(&sos);
    /// filter.set_steady_state(4.0);
    /// assert!((filter.process(4.0) - 4.0 * sos.dc_gain()).abs() < 1e-12);
    /// ```
    pub fn set_steady_state(&mut self, x0: f64) {
        for (state, z) in self.state.chunks_exact_mut(2).zip(&self.unit_steady_state) {
            state[0] = z[0] * x0;
            state[1] = z[1] * x0;
        }
    }

    /// The state `[s0, s1]` of each section, in order, for inspection.
    pub fn state(&self) -> Vec<[f64; 2]> {
        self.state.chunks_exact(2).map(|s| [s[0], s[1]]).collect()
    }

    /// The sections this filter runs.
    pub fn sections(&self) -> &[Biquad] {
        &self.sections
    }
}

/// A channel count of zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NoChannels;

impl fmt::Display for NoChannels {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the number of channels must be at least 1")
    }
}

impl std::error::Error for NoChannels {}

/// The same cascade on several interleaved channels, each with its own state.
///
/// Samples arrive interleaved (`u0 v0 w0 u1 v1 w1 …`); the bank remembers which channel the next
/// sample belongs to, so a stream may be cut anywhere, even inside a frame.
///
/// ```
/// use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
/// use cutlab::signal::filter::{SosFilter, SosFilterBank};
/// let sos = butter(&ButterworthSpec {
///     kind: FilterKind::Lowpass,
///     order: 10,
///     cutoff_hz: Cutoff::Single(50.0),
///     sample_rate_hz: 10_000.0,
/// })
/// .unwrap();
/// let mut bank = SosFilterBank::new(&sos, 3).unwrap();
/// // Three phase currents, interleaved.
/// let mut interleaved: Vec<f64> = (0..300).map(|i| ((i % 3) as f64 - 1.0) * 5.0).collect();
/// let phase_v: Vec<f64> = interleaved.iter().skip(1).step_by(3).copied().collect();
/// bank.process_slice(&mut interleaved);
/// // Channel 1 equals filtering phase v on its own.
/// let alone = SosFilter::new(&sos).filter(&phase_v);
/// assert_eq!(interleaved[3 * 99 + 1], alone[99]);
/// assert_eq!(bank.next_channel(), 0);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SosFilterBank {
    sections: Vec<Biquad>,
    unit_steady_state: Vec<[f64; 2]>,
    tables: LaneTables,
    channels: usize,
    /// Section `k`, state value `w` (0 or 1), channel `c` at `(2k + w)·channels + c`.
    state: Vec<f64>,
    next_channel: usize,
}

impl SosFilterBank {
    /// A bank of `channels` filters running `sos`, all at rest.
    pub fn new(sos: &Sos, channels: usize) -> Result<Self, NoChannels> {
        if channels == 0 {
            return Err(NoChannels);
        }
        let sections = sos.sections().to_vec();
        let state = vec![0.0; 2 * sections.len() * channels];
        Ok(Self {
            tables: LaneTables::new(&sections, channels),
            sections,
            unit_steady_state: sos.steady_state(),
            channels,
            state,
            next_channel: 0,
        })
    }

    /// The number of channels.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The channel the next sample belongs to (0 at a frame boundary).
    pub fn next_channel(&self) -> usize {
        self.next_channel
    }

    /// Filters the next sample of the interleaved stream.
    #[inline]
    pub fn process(&mut self, x: f64) -> f64 {
        let c = self.next_channel;
        let n = self.channels;
        let mut value = x;
        for (k, s) in self.sections.iter().enumerate() {
            let i0 = 2 * k * n + c;
            let i1 = i0 + n;
            let y = s.b0 * value + self.state[i0];
            self.state[i0] = (s.b1 * value + self.state[i1]) - s.a1 * y;
            self.state[i1] = s.b2 * value - s.a2 * y;
            value = y;
        }
        self.next_channel = if c + 1 == n { 0 } else { c + 1 };
        value
    }

    /// Filters the interleaved `samples` in place; the same bits as [`process`](Self::process)
    /// on each.
    pub fn process_slice(&mut self, samples: &mut [f64]) {
        let mut rest = samples;
        // Finish a frame a previous call left open.
        while self.next_channel != 0 {
            let Some((first, tail)) = rest.split_first_mut() else {
                return;
            };
            *first = self.process(*first);
            rest = tail;
        }
        let whole = rest.len() - rest.len() % self.channels;
        let (frames, partial) = rest.split_at_mut(whole);
        let (state, tables) = (&mut self.state, &self.tables);
        match self.channels {
            1 => run_cascade::<1, 1>(&tables.one, state, frames.as_chunks_mut().0),
            2 => run_cascade::<2, 2>(&tables.two, state, frames.as_chunks_mut().0),
            3 => widest_vectors(
                #[inline(always)]
                || run_cascade::<3, 4>(&tables.four, state, frames.as_chunks_mut().0),
            ),
            4 => widest_vectors(
                #[inline(always)]
                || run_cascade::<4, 4>(&tables.four, state, frames.as_chunks_mut().0),
            ),
            _ => {
                for x in frames.iter_mut() {
                    *x = self.process(*x);
                }
            }
        }
        for x in partial {
            *x = self.process(*x);
        }
    }

    /// Back to rest: zero state, next sample is channel 0.
    pub fn reset(&mut self) {
        self.state.fill(0.0);
        self.next_channel = 0;
    }

    /// Sets each channel's state to what a constant input equal to `first_frame[c]` would have
    /// settled to (scipy's `sosfilt_zi(sos) * x0` per channel); the next sample is channel 0.
    ///
    /// # Panics
    ///
    /// If `first_frame.len()` differs from the number of channels (a bug in the caller).
    pub fn set_steady_state(&mut self, first_frame: &[f64]) {
        assert_eq!(
            first_frame.len(),
            self.channels,
            "one starting value per channel"
        );
        let n = self.channels;
        for (k, z) in self.unit_steady_state.iter().enumerate() {
            for (c, &x0) in first_frame.iter().enumerate() {
                self.state[2 * k * n + c] = z[0] * x0;
                self.state[(2 * k + 1) * n + c] = z[1] * x0;
            }
        }
        self.next_channel = 0;
    }
}

/// One section's coefficients `[b0, b1, b2, a1, a2]`, each repeated across `L` lanes, so a
/// kernel multiplies a whole lane vector by a coefficient straight from memory (SSE2 has no
/// broadcast-from-memory multiply; without this table every use would cost a shuffle).
type Lanes<const L: usize> = [[f64; L]; 5];

/// The coefficient tables the slice kernels read, built once at construction.
#[derive(Debug, Clone, PartialEq, Default)]
struct LaneTables {
    one: Vec<Lanes<1>>,
    two: Vec<Lanes<2>>,
    four: Vec<Lanes<4>>,
}

impl LaneTables {
    /// The table(s) a kernel for `channels` channels uses: one lane for one channel, two for two,
    /// four (one idle for three channels) for three or four; none beyond, where the bank runs
    /// sample by sample.
    fn new(sections: &[Biquad], channels: usize) -> Self {
        fn table<const L: usize>(sections: &[Biquad]) -> Vec<Lanes<L>> {
            sections
                .iter()
                .map(|s| [s.b0, s.b1, s.b2, s.a1, s.a2].map(|c| [c; L]))
                .collect()
        }
        match channels {
            1 => Self {
                one: table(sections),
                ..Self::default()
            },
            2 => Self {
                two: table(sections),
                ..Self::default()
            },
            3 | 4 => Self {
                four: table(sections),
                ..Self::default()
            },
            _ => Self::default(),
        }
    }
}

/// Runs `work` compiled for the widest vector instructions this processor has, chosen at run
/// time: on x86-64 with AVX2 a four-lane kernel is one instruction per operation instead of two.
/// Bits are unchanged: the same IEEE multiplications and additions, never fused.
#[inline(always)]
fn widest_vectors<R>(work: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        pulp::Arch::new().dispatch(work)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        work()
    }
}

/// Runs every section over `frames` of `C` channels held in `L ≥ C` lanes, one section at a time
/// over each block.
///
/// In wasm (no vector registers to hold a group's state, and every kernel size is code the
/// browser downloads: the sized kernels below cost ~50 KB there), the sections go one at a time
/// over each block instead: the same arithmetic on the same values, so the same bits.
#[cfg(target_arch = "wasm32")]
#[inline(always)]
fn run_cascade<const C: usize, const L: usize>(
    table: &[Lanes<L>],
    state: &mut [f64],
    frames: &mut [[f64; C]],
) {
    for block in frames.chunks_mut(BLOCK_FRAMES) {
        for (k, lanes) in table.iter().enumerate() {
            let Some(s) = state.get_mut(2 * k * C..2 * (k + 1) * C) else {
                continue;
            };
            // The channels side by side in one pass: each channel's section is a recurrence
            // whose every step waits for the one before (a multiplication and two additions),
            // so one channel at a time leaves the processor idle; C independent recurrences
            // overlap. Per channel the operations and their order are those of `process`.
            let mut q = [[0.0; 5]; C];
            let mut sk = [[0.0; 2]; C];
            for c in 0..C {
                q[c] = [
                    lanes[0][c],
                    lanes[1][c],
                    lanes[2][c],
                    lanes[3][c],
                    lanes[4][c],
                ];
                sk[c] = [s[c], s[C + c]];
            }
            for frame in block.iter_mut() {
                for c in 0..C {
                    frame[c] = section_step(&q[c], &mut sk[c], frame[c]);
                }
            }
            for c in 0..C {
                s[c] = sk[c][0];
                s[C + c] = sk[c][1];
            }
        }
    }
}

/// Runs every section over `frames` of `C` channels held in `L ≥ C` lanes. With more sections
/// than one register group holds, goes block by block so each block stays in cache while the
/// groups pass over it.
#[cfg(not(target_arch = "wasm32"))]
#[inline(always)]
fn run_cascade<const C: usize, const L: usize>(
    table: &[Lanes<L>],
    state: &mut [f64],
    frames: &mut [[f64; C]],
) {
    let groups = table.len().div_ceil(MAX_GROUP);
    if groups <= 1 {
        run_group::<C, L>(table, state, frames);
        return;
    }
    for block in frames.chunks_mut(BLOCK_FRAMES) {
        let mut start = 0;
        for g in 0..groups {
            // Balanced groups (20 sections → 6, 7, 7) so none runs alone, latency-bound.
            let len = (table.len() - start) / (groups - g);
            let end = start + len;
            run_group::<C, L>(
                &table[start..end],
                &mut state[2 * start * C..2 * end * C],
                block,
            );
            start = end;
        }
    }
}

/// Dispatches a group of up to [`MAX_GROUP`] sections to the kernel compiled for its size: on one
/// channel with enough sections and samples, the skewed two-lane kernel; otherwise the lane
/// kernel.
#[cfg(not(target_arch = "wasm32"))]
#[inline(always)]
fn run_group<const C: usize, const L: usize>(
    table: &[Lanes<L>],
    state: &mut [f64],
    frames: &mut [[f64; C]],
) {
    if C == 1 && table.len() >= SKEW_MIN_SECTIONS && frames.len() >= 4 * table.len() {
        match table.len() {
            4 => return skewed::<4, 2, C, L>(table, state, frames),
            5 => return skewed::<5, 3, C, L>(table, state, frames),
            6 => return skewed::<6, 3, C, L>(table, state, frames),
            7 => return skewed::<7, 4, C, L>(table, state, frames),
            8 => return skewed::<8, 4, C, L>(table, state, frames),
            _ => {}
        }
    }
    match table.len() {
        1 => kernel::<1, C, L>(table, state, frames),
        2 => kernel::<2, C, L>(table, state, frames),
        3 => kernel::<3, C, L>(table, state, frames),
        4 => kernel::<4, C, L>(table, state, frames),
        5 => kernel::<5, C, L>(table, state, frames),
        6 => kernel::<6, C, L>(table, state, frames),
        7 => kernel::<7, C, L>(table, state, frames),
        8 => kernel::<8, C, L>(table, state, frames),
        _ => {
            // Not reached (groups hold 1..=MAX_GROUP sections); correct anyway, one at a time.
            for (k, section) in table.chunks(1).enumerate() {
                kernel::<1, C, L>(section, &mut state[2 * k * C..2 * (k + 1) * C], frames);
            }
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[inline(always)]
fn mul<const L: usize>(a: [f64; L], b: [f64; L]) -> [f64; L] {
    std::array::from_fn(|i| a[i] * b[i])
}

#[cfg(not(target_arch = "wasm32"))]
#[inline(always)]
fn add<const L: usize>(a: [f64; L], b: [f64; L]) -> [f64; L] {
    std::array::from_fn(|i| a[i] + b[i])
}

#[cfg(not(target_arch = "wasm32"))]
#[inline(always)]
fn sub<const L: usize>(a: [f64; L], b: [f64; L]) -> [f64; L] {
    std::array::from_fn(|i| a[i] - b[i])
}

/// `K` sections on `C` channels in `L` lanes, all state in local arrays (registers): the
/// processor overlaps the `K·C` independent recurrences sample after sample, and each operation
/// covers every channel at once. Idle lanes (`C < L`) carry zeros. Per lane, the arithmetic is
/// exactly that of `process`, so the bits agree.
#[cfg(not(target_arch = "wasm32"))]
#[inline(always)]
fn kernel<const K: usize, const C: usize, const L: usize>(
    table: &[Lanes<L>],
    state: &mut [f64],
    frames: &mut [[f64; C]],
) {
    const { assert!(C <= L, "a kernel needs a lane per channel") };
    let Ok(coefficients) = <&[Lanes<L>; K]>::try_from(table) else {
        return;
    };
    let at = |k: usize, w: usize, c: usize| (2 * k + w) * C + c;
    let load = |k: usize, w: usize| -> [f64; L] {
        std::array::from_fn(|c| {
            if c < C {
                state.get(at(k, w, c)).copied().unwrap_or(0.0)
            } else {
                0.0
            }
        })
    };
    let mut s: [[[f64; L]; 2]; K] = std::array::from_fn(|k| [load(k, 0), load(k, 1)]);
    for frame in frames.iter_mut() {
        let mut x: [f64; L] = std::array::from_fn(|c| if c < C { frame[c] } else { 0.0 });
        for (q, sk) in coefficients.iter().zip(s.iter_mut()) {
            let [b0, b1, b2, a1, a2] = *q;
            let y = add(mul(b0, x), sk[0]);
            sk[0] = sub(add(mul(b1, x), sk[1]), mul(a1, y));
            sk[1] = sub(mul(b2, x), mul(a2, y));
            x = y;
        }
        *frame = std::array::from_fn(|c| x[c]);
    }
    for (k, sk) in s.iter().enumerate() {
        for (w, values) in sk.iter().enumerate() {
            for (c, v) in values.iter().enumerate().take(C) {
                if let Some(slot) = state.get_mut(at(k, w, c)) {
                    *slot = *v;
                }
            }
        }
    }
}

/// One section's step on one value, exactly as [`SosFilter::process`] computes it.
#[inline(always)]
fn section_step(q: &[f64; 5], s: &mut [f64; 2], x: f64) -> f64 {
    let [b0, b1, b2, a1, a2] = *q;
    let y = b0 * x + s[0];
    s[0] = (b1 * x + s[1]) - a1 * y;
    s[1] = b2 * x - a2 * y;
    y
}

/// One channel through `K` sections held in `V = ⌈K/2⌉` two-lane vectors, section `k` running
/// `k` samples behind section 0.
///
/// On one channel the sections of a sample depend on each other, so a plain loop issues every
/// operation one lane wide and the scalar units are the limit (as for scipy's loop). Skewed by
/// one sample per section, every section's input is the previous section's output from the
/// *previous* step, so all `K` sections advance together, two per vector operation; the only
/// extra work is shifting the outputs by one lane. A triangle of scalar steps enters the skew at
/// the start and leaves it at the end, so each section still sees every sample once, in order:
/// the bits equal [`SosFilter::process`] on each sample.
#[cfg(not(target_arch = "wasm32"))]
fn skewed<const K: usize, const V: usize, const C: usize, const L: usize>(
    table: &[Lanes<L>],
    state: &mut [f64],
    frames: &mut [[f64; C]],
) {
    const { assert!(2 * V >= K && 2 * V < K + 2, "two sections per vector") };
    let n = frames.len();
    if C != 1 || table.len() != K || n < K {
        return kernel::<K, C, L>(table, state, frames);
    }
    let q: [[f64; 5]; K] = std::array::from_fn(|k| table[k].map(|lanes| lanes[0]));
    let mut s: [[f64; 2]; K] = std::array::from_fn(|k| {
        [
            state.get(2 * k).copied().unwrap_or(0.0),
            state.get(2 * k + 1).copied().unwrap_or(0.0),
        ]
    });
    // y[k]: the latest output of section k.
    let mut y = [0.0f64; K];

    // Enter the skew: at step t, sections k = t, t−1, …, 0 take samples 0, 1, …, t (highest
    // first, so section k reads section k−1's output of the previous step).
    for (t, frame) in frames.iter().take(K - 1).enumerate() {
        for k in (0..=t).rev() {
            let input = if k == 0 { frame[0] } else { y[k - 1] };
            y[k] = section_step(&q[k], &mut s[k], input);
        }
    }

    // Steady state: section k takes sample t − k, all at once. Vector v holds sections v (lane 0)
    // and v + V (lane 1), so each vector's input is the previous vector's output as it stands;
    // only vector 0 needs a shuffle (the new sample, and section V−1's output moving to lane 1).
    // An idle lane (odd K) has zero coefficients and its state never leaves the kernel.
    let section_of = |v: usize, h: usize| v + h * V;
    let lane = |k: usize, j: usize| if k < K { q[k][j] } else { 0.0 };
    let pair = |j: usize| -> [[f64; 2]; V] {
        std::array::from_fn(|v| [lane(section_of(v, 0), j), lane(section_of(v, 1), j)])
    };
    let (b0, b1, b2, a1, a2) = (pair(0), pair(1), pair(2), pair(3), pair(4));
    let held = |k: usize, w: usize| if k < K { s[k][w] } else { 0.0 };
    let out = |k: usize| if k < K { y[k] } else { 0.0 };
    let mut s0: [[f64; 2]; V] =
        std::array::from_fn(|v| [held(section_of(v, 0), 0), held(section_of(v, 1), 0)]);
    let mut s1: [[f64; 2]; V] =
        std::array::from_fn(|v| [held(section_of(v, 0), 1), held(section_of(v, 1), 1)]);
    let mut yv: [[f64; 2]; V] =
        std::array::from_fn(|v| [out(section_of(v, 0)), out(section_of(v, 1))]);
    // Section K−1 is lane 1 of vector K−1−V.
    let last = K - 1 - V;
    for t in K - 1..n {
        let x: [[f64; 2]; V] = std::array::from_fn(|v| {
            if v == 0 {
                [frames[t][0], yv[V - 1][0]]
            } else {
                yv[v - 1]
            }
        });
        for v in 0..V {
            let yy = add(mul(b0[v], x[v]), s0[v]);
            s0[v] = sub(add(mul(b1[v], x[v]), s1[v]), mul(a1[v], yy));
            s1[v] = sub(mul(b2[v], x[v]), mul(a2[v], yy));
            yv[v] = yy;
        }
        // Section K−1 has just finished sample t − (K−1), already read by section 0.
        frames[t + 1 - K][0] = yv[last][1];
    }
    for v in 0..V {
        for h in 0..2 {
            let k = section_of(v, h);
            if k < K {
                y[k] = yv[v][h];
                s[k] = [s0[v][h], s1[v][h]];
            }
        }
    }

    // Leave the skew: sections K−1, …, t−n+1 finish the last samples.
    for t in n..n + K - 1 {
        for k in (t + 1 - n..K).rev() {
            y[k] = section_step(&q[k], &mut s[k], y[k - 1]);
        }
        frames[t + 1 - K][0] = y[K - 1];
    }
    for (k, sk) in s.iter().enumerate() {
        for (w, value) in sk.iter().enumerate() {
            if let Some(slot) = state.get_mut(2 * k + w) {
                *slot = *value;
            }
        }
    }
}

/// Filters `input` with `sos` from rest: scipy's `sosfilt(sos, input)`.
///
/// ```
/// use cutlab::signal::sos::Sos;
/// use cutlab::signal::filter::sosfilt;
/// // y[n] = x[n] + 0.5·y[n−1]
/// let sos = Sos::from_rows(&[[1.0, 0.0, 0.0, 1.0, -0.5, 0.0]]).unwrap();
/// assert_eq!(sosfilt(&sos, &[1.0, 0.0, 0.0]), vec![1.0, 0.5, 0.25]);
/// ```
pub fn sosfilt(sos: &Sos, input: &[f64]) -> Vec<f64> {
    SosFilter::new(sos).filter(input)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn cascade(sections: usize) -> Sos {
        let rows: Vec<[f64; 6]> = (0..sections)
            .map(|k| {
                let r = 0.95 - 0.01 * k as f64;
                let theta = 0.05 + 0.02 * k as f64;
                [0.2, 0.3, 0.1, 1.0, -2.0 * r * theta.cos(), r * r]
            })
            .collect();
        Sos::from_rows(&rows).unwrap()
    }

    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = Rng::seed_from(seed);
        (0..n).map(|_| rng.normal()).collect()
    }

    #[test]
    fn slice_equals_per_sample_for_every_group_size() {
        for sections in 1..=20 {
            let sos = cascade(sections);
            let x = noise(1000, sections as u64);
            // Skewed and lane kernels, whole blocks and short tails, cut at an odd place.
            let mut one = SosFilter::new(&sos);
            let expected: Vec<f64> = x.iter().map(|&v| one.process(v)).collect();
            let mut many = SosFilter::new(&sos);
            let mut y = x.clone();
            // Uneven pieces, so block boundaries fall everywhere.
            let (a, b) = y.split_at_mut(333);
            many.process_slice(a);
            many.process_slice(b);
            assert_eq!(y, expected, "{sections} sections");
            assert_eq!(one, many);
        }
    }

    #[test]
    fn bank_equals_independent_filters_for_any_channel_count_and_any_cut() {
        let sos = cascade(5);
        for channels in 1..=6 {
            let frames = 301;
            let x = noise(channels * frames, 40 + channels as u64);
            let mut expected = x.clone();
            for c in 0..channels {
                let mut f = SosFilter::new(&sos);
                for i in 0..frames {
                    let j = i * channels + c;
                    expected[j] = f.process(x[j]);
                }
            }
            let mut bank = SosFilterBank::new(&sos, channels).unwrap();
            let mut y = x.clone();
            let (a, rest) = y.split_at_mut(7);
            let (b, c) = rest.split_at_mut(channels * 100 + 1);
            bank.process_slice(a);
            bank.process_slice(b);
            bank.process_slice(c);
            assert_eq!(y, expected, "{channels} channels");
            let mut per_sample = SosFilterBank::new(&sos, channels).unwrap();
            let z: Vec<f64> = x.iter().map(|&v| per_sample.process(v)).collect();
            assert_eq!(z, expected);
        }
    }

    #[test]
    fn bank_slice_equals_per_sample_for_every_group_size() {
        // The lane kernels for 2–4 channels (four lanes run with AVX2 where the processor has
        // it), on every section count, in one or several register groups, split mid-run.
        for channels in 2..=4 {
            for sections in 1..=20 {
                let sos = cascade(sections);
                for frames in [1, sections, 2 * sections + 1, 517] {
                    let x = noise(channels * frames, (100 * channels + sections) as u64);
                    let mut per_sample = SosFilterBank::new(&sos, channels).unwrap();
                    let expected: Vec<f64> = x.iter().map(|&v| per_sample.process(v)).collect();
                    let mut bank = SosFilterBank::new(&sos, channels).unwrap();
                    let mut y = x.clone();
                    let (a, b) = y.split_at_mut(channels * (frames / 3));
                    bank.process_slice(a);
                    bank.process_slice(b);
                    assert_eq!(
                        y, expected,
                        "{channels} channels, {sections} sections, {frames}"
                    );
                    assert_eq!(bank, per_sample);
                }
            }
        }
    }

    #[test]
    fn reset_restores_the_start() {
        let sos = cascade(3);
        let x = noise(50, 9);
        let mut f = SosFilter::new(&sos);
        let first = f.filter(&x);
        f.reset();
        assert_eq!(f.filter(&x), first);
        let mut bank = SosFilterBank::new(&sos, 2).unwrap();
        bank.process(1.0);
        bank.reset();
        assert_eq!(bank, SosFilterBank::new(&sos, 2).unwrap());
    }

    #[test]
    fn nan_poisons_until_reset() {
        let sos = cascade(2);
        let mut f = SosFilter::new(&sos);
        assert!(f.process(f64::NAN).is_nan());
        assert!(f.process(1.0).is_nan());
        f.reset();
        assert!(f.process(1.0).is_finite());
    }

    #[test]
    fn zero_channels_is_an_error() {
        assert_eq!(SosFilterBank::new(&cascade(1), 0), Err(NoChannels));
    }
}
