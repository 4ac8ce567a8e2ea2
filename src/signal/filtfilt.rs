//! Zero-phase filtering of logs: forward, then backward, as `scipy.signal.sosfiltfilt` with its
//! default padding.
//!
//! The magnitude response is squared and the phase cancels, so a peak stays where it was: right
//! for analysing a recorded cut, impossible in real time (the backward pass needs the future).
//!
//! scipy's default, reproduced here:
//!
//! 1. extend each end by `padlen = 3·(2·sections + 1 − min(#b2 = 0, #a2 = 0))` samples with the
//!    *odd* extension (a 180° rotation about the end point: `2·x[0] − x[i]`), which keeps the
//!    signal and its slope continuous;
//! 2. start the forward pass settled at the first extended sample (`sosfilt_zi · x₀`), filter;
//! 3. start the backward pass settled at the last forward output, filter the reversed result;
//! 4. drop the padding.
//!
//! A channel needs **more than** `padlen` samples (scipy raises the same error).
//!
//! Two forms: [`filtfilt`]/[`filtfilt_interleaved`] for a log in memory, and
//! [`filtfilt_stream`] for a stream of any length with bounded memory. The backward pass cannot
//! start before the stream ends, so the stream form writes the forward pass to a scratch store
//! (a temporary file in the CLI), filters it backward in place block by block, then copies it
//! out: memory stays bounded, disk holds `(samples + 2·padlen) · 8` bytes. Both forms give the
//! same bits. [`filter_stream`] is the causal counterpart, which needs no scratch.

use std::fmt;
use std::io::{self, Read, Seek, SeekFrom, Write};

use super::filter::SosFilterBank;
use super::sos::Sos;

/// Frames read, filtered and written at a time by the stream forms.
const STREAM_BLOCK_FRAMES: usize = 8192;

/// The most interleaved channels the stream forms take. Their buffers grow with the channel
/// count (64 KiB per channel); 256 covers any drive's currents and keeps a mistyped count an
/// error instead of an allocation failure.
pub const MAX_STREAM_CHANNELS: usize = 256;

/// Why zero-phase filtering of a log was refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FiltfiltError {
    /// A channel has no more samples than the padding (scipy's condition).
    TooShort {
        /// Samples per channel given.
        samples: usize,
        /// The padding each end needs.
        padlen: usize,
    },
    /// The channel count is zero.
    NoChannels,
    /// The interleaved input does not hold a whole number of frames.
    RaggedFrames {
        /// Samples given.
        samples: usize,
        /// Channels per frame.
        channels: usize,
    },
}

impl fmt::Display for FiltfiltError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooShort { samples, padlen } => write!(
                f,
                "zero-phase filtering needs more than {padlen} samples per channel (the default \
                 padding of scipy's sosfiltfilt for this filter), got {samples}"
            ),
            Self::NoChannels => f.write_str("the number of channels must be at least 1"),
            Self::RaggedFrames { samples, channels } => write!(
                f,
                "{samples} interleaved samples are not a whole number of {channels}-channel frames"
            ),
        }
    }
}

impl std::error::Error for FiltfiltError {}

/// Zero-phase filters one channel: `scipy.signal.sosfiltfilt(sos, input)`.
///
/// ```
/// use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
/// use cutlab::signal::filtfilt::filtfilt;
/// let sos = butter(&ButterworthSpec {
///     kind: FilterKind::Lowpass,
///     order: 4,
///     cutoff_hz: Cutoff::Single(100.0),
///     sample_rate_hz: 10_000.0,
/// })
/// .unwrap();
/// // A slow ramp passes unchanged and undelayed (a causal filter would lag behind it).
/// let ramp: Vec<f64> = (0..2000).map(|i| i as f64 * 1e-3).collect();
/// let y = filtfilt(&sos, &ramp).unwrap();
/// assert!((y[1000] - ramp[1000]).abs() < 1e-9);
/// // Too short for the padding: an error, as in scipy.
/// assert!(filtfilt(&sos, &ramp[..sos.filtfilt_padlen()]).is_err());
/// ```
pub fn filtfilt(sos: &Sos, input: &[f64]) -> Result<Vec<f64>, FiltfiltError> {
    filtfilt_interleaved(sos, input, 1)
}

/// Zero-phase filters `channels` interleaved channels (`sosfiltfilt` along each channel).
///
/// ```
/// use cutlab::signal::sos::Sos;
/// use cutlab::signal::filtfilt::{filtfilt, filtfilt_interleaved};
/// let sos = Sos::from_rows(&[[0.2, 0.2, 0.0, 1.0, -0.6, 0.0]]).unwrap();
/// let a: Vec<f64> = (0..50).map(|i| (i as f64).sin()).collect();
/// let b: Vec<f64> = (0..50).map(|i| (i as f64 * 0.3).cos()).collect();
/// let both: Vec<f64> = a.iter().zip(&b).flat_map(|(x, y)| [*x, *y]).collect();
/// let y = filtfilt_interleaved(&sos, &both, 2).unwrap();
/// assert_eq!(y[2 * 20 + 1], filtfilt(&sos, &b).unwrap()[20]);
/// ```
pub fn filtfilt_interleaved(
    sos: &Sos,
    input: &[f64],
    channels: usize,
) -> Result<Vec<f64>, FiltfiltError> {
    if channels == 0 {
        return Err(FiltfiltError::NoChannels);
    }
    if !input.len().is_multiple_of(channels) {
        return Err(FiltfiltError::RaggedFrames {
            samples: input.len(),
            channels,
        });
    }
    let frames = input.len() / channels;
    let padlen = sos.filtfilt_padlen();
    if frames <= padlen {
        return Err(FiltfiltError::TooShort {
            samples: frames,
            padlen,
        });
    }
    let c = channels;
    let frame = |i: usize| &input[i * c..(i + 1) * c];
    let mut extended = Vec::with_capacity((frames + 2 * padlen) * c);
    // Odd extension (a 180° rotation about each end point), as scipy's `odd_ext`.
    let first = frame(0);
    for i in (1..=padlen).rev() {
        extended.extend(first.iter().zip(frame(i)).map(|(x0, xi)| 2.0 * x0 - xi));
    }
    extended.extend_from_slice(input);
    let last = frame(frames - 1);
    for i in 1..=padlen {
        extended.extend(
            last.iter()
                .zip(frame(frames - 1 - i))
                .map(|(xn, xi)| 2.0 * xn - xi),
        );
    }

    let mut bank = SosFilterBank::new(sos, c).map_err(|_| FiltfiltError::NoChannels)?;
    bank.set_steady_state(&extended[..c]);
    bank.process_slice(&mut extended);
    reverse_frames(&mut extended, c);
    bank.reset();
    let last_forward = extended[..c].to_vec();
    bank.set_steady_state(&last_forward);
    bank.process_slice(&mut extended);
    reverse_frames(&mut extended, c);
    Ok(extended[padlen * c..(padlen + frames) * c].to_vec())
}

/// Reverses the order of the `channels`-wide frames of `samples`, keeping each frame's channel
/// order.
fn reverse_frames(samples: &mut [f64], channels: usize) {
    samples.reverse();
    for frame in samples.chunks_exact_mut(channels) {
        frame.reverse();
    }
}

/// Why a stream could not be filtered.
#[derive(Debug)]
pub enum StreamError {
    /// Reading the input, writing the output or using the scratch store failed.
    Io(io::Error),
    /// The input ended inside a frame: its length is not a multiple of 8 bytes × channels.
    PartialFrame {
        /// Bytes read in total.
        total_bytes: u64,
        /// Bytes per frame (8 × channels).
        frame_bytes: usize,
    },
    /// Zero-phase filtering of a stream with no more samples per channel than the padding.
    TooShort {
        /// Samples per channel read.
        samples: u64,
        /// The padding each end needs.
        padlen: usize,
    },
    /// The channel count is zero.
    NoChannels,
    /// More channels than [`MAX_STREAM_CHANNELS`].
    TooManyChannels(usize),
    /// A sample is NaN or infinite: it would make the filter's state non-finite for the rest of
    /// the stream, so the stream stops there.
    NonFinite {
        /// The frame (0-based) holding the sample.
        frame: u64,
        /// Its channel (0-based).
        channel: usize,
        /// Channels per frame.
        channels: usize,
        /// The value read.
        value: f64,
    },
}

impl fmt::Display for StreamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io(e) => write!(f, "I/O error: {e}"),
            Self::PartialFrame {
                total_bytes,
                frame_bytes,
            } => {
                let left_over = total_bytes % *frame_bytes as u64;
                write!(
                    f,
                    "input is {total_bytes} bytes, not a whole number of {frame_bytes}-byte frames \
                     ({} channel(s) × 8-byte f64): the last {left_over} byte(s), from byte offset \
                     {}, were not filtered",
                    frame_bytes / 8,
                    total_bytes - left_over
                )
            }
            Self::TooShort { samples, padlen } => write!(
                f,
                "zero-phase filtering needs more than {padlen} samples per channel (the default \
                 padding of scipy's sosfiltfilt for this filter), got {samples}"
            ),
            Self::NoChannels => f.write_str("the number of channels must be at least 1"),
            Self::TooManyChannels(channels) => write!(
                f,
                "{channels} channels is more than the {MAX_STREAM_CHANNELS} a stream can take"
            ),
            Self::NonFinite {
                frame,
                channel,
                channels,
                value,
            } => write!(
                f,
                "sample {value} at frame {frame}, channel {channel} (byte offset {}) is not a \
                 finite number: filtering stops there, since it would corrupt every later output",
                (frame * *channels as u64 + *channel as u64) * 8
            ),
        }
    }
}

impl std::error::Error for StreamError {}

impl From<io::Error> for StreamError {
    fn from(e: io::Error) -> Self {
        Self::Io(e)
    }
}

/// Reads whole frames of little-endian f64 from a byte stream.
struct FrameReader<'a, R: Read + ?Sized> {
    input: &'a mut R,
    bytes: Vec<u8>,
    pending: usize,
    total_bytes: u64,
    frame_bytes: usize,
    frames_read: u64,
}

impl<'a, R: Read + ?Sized> FrameReader<'a, R> {
    fn new(input: &'a mut R, channels: usize) -> Result<Self, StreamError> {
        if channels == 0 {
            return Err(StreamError::NoChannels);
        }
        if channels > MAX_STREAM_CHANNELS {
            return Err(StreamError::TooManyChannels(channels));
        }
        let frame_bytes = 8 * channels;
        Ok(Self {
            input,
            bytes: vec![0; STREAM_BLOCK_FRAMES * frame_bytes],
            pending: 0,
            total_bytes: 0,
            frame_bytes,
            frames_read: 0,
        })
    }

    /// Fills `out` (cleared first) with up to a block of whole frames; an empty `out` means the
    /// input has ended on a frame boundary.
    fn next_block(&mut self, out: &mut Vec<f64>) -> Result<(), StreamError> {
        out.clear();
        // Read until at least one whole frame is buffered or the input ends.
        while self.pending < self.frame_bytes {
            match self.input.read(&mut self.bytes[self.pending..]) {
                Ok(0) => {
                    if self.pending > 0 {
                        return Err(StreamError::PartialFrame {
                            total_bytes: self.total_bytes,
                            frame_bytes: self.frame_bytes,
                        });
                    }
                    return Ok(());
                }
                Ok(n) => {
                    self.pending += n;
                    self.total_bytes += n as u64;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
        let whole = self.pending - self.pending % self.frame_bytes;
        let (samples, _) = self.bytes[..whole].as_chunks::<8>();
        out.extend(samples.iter().map(|b| f64::from_le_bytes(*b)));
        self.bytes.copy_within(whole..self.pending, 0);
        self.pending -= whole;
        let channels = self.frame_bytes / 8;
        if let Some(at) = out.iter().position(|v| !v.is_finite()) {
            return Err(StreamError::NonFinite {
                frame: self.frames_read + (at / channels) as u64,
                channel: at % channels,
                channels,
                value: out[at],
            });
        }
        self.frames_read += (out.len() / channels) as u64;
        Ok(())
    }
}

fn write_samples(
    out: &mut (impl Write + ?Sized),
    samples: &[f64],
    bytes: &mut Vec<u8>,
) -> io::Result<()> {
    bytes.clear();
    bytes.extend(samples.iter().flat_map(|x| x.to_le_bytes()));
    out.write_all(bytes)
}

/// Causally filters a stream of interleaved little-endian f64 frames from `input` to `output`
/// (the same bits as [`SosFilterBank::process_slice`] on the whole), in constant memory.
/// Returns the number of frames.
///
/// ```
/// use cutlab::signal::filtfilt::filter_stream;
/// use cutlab::signal::sos::Sos;
/// let sos = Sos::from_rows(&[[1.0, 0.0, 0.0, 1.0, -0.5, 0.0]]).unwrap();
/// let input: Vec<u8> = [1.0f64, 0.0, 0.0].iter().flat_map(|x| x.to_le_bytes()).collect();
/// let mut output = Vec::new();
/// assert_eq!(filter_stream(&sos, 1, &mut input.as_slice(), &mut output).unwrap(), 3);
/// assert_eq!(f64::from_le_bytes(output[16..24].try_into().unwrap()), 0.25);
/// ```
pub fn filter_stream(
    sos: &Sos,
    channels: usize,
    input: &mut (impl Read + ?Sized),
    output: &mut (impl Write + ?Sized),
) -> Result<u64, StreamError> {
    let mut reader = FrameReader::new(input, channels)?;
    let mut bank = SosFilterBank::new(sos, channels).map_err(|_| StreamError::NoChannels)?;
    let mut block = Vec::with_capacity(STREAM_BLOCK_FRAMES * channels);
    let mut bytes = Vec::with_capacity(STREAM_BLOCK_FRAMES * channels * 8);
    let mut frames = 0u64;
    loop {
        reader.next_block(&mut block)?;
        if block.is_empty() {
            return Ok(frames);
        }
        bank.process_slice(&mut block);
        write_samples(output, &block, &mut bytes)?;
        frames += (block.len() / channels) as u64;
    }
}

/// Zero-phase filters a stream of interleaved little-endian f64 frames from `input` to
/// `output`, giving the same bits as [`filtfilt_interleaved`] on the whole input, with memory
/// bounded by a block whatever the length. `scratch` (an empty temporary file, or a
/// `Cursor<Vec<u8>>`) receives `(frames + 2·padlen) · channels · 8` bytes: the forward pass,
/// then filtered backward in place. Returns the number of frames.
///
/// ```
/// use std::io::Cursor;
/// use cutlab::signal::filtfilt::{filtfilt, filtfilt_stream};
/// use cutlab::signal::sos::Sos;
/// let sos = Sos::from_rows(&[[0.2, 0.2, 0.0, 1.0, -0.6, 0.0]]).unwrap();
/// let x: Vec<f64> = (0..100).map(|i| (i as f64 * 0.2).sin()).collect();
/// let input: Vec<u8> = x.iter().flat_map(|v| v.to_le_bytes()).collect();
/// let mut output = Vec::new();
/// let mut scratch = Cursor::new(Vec::new());
/// filtfilt_stream(&sos, 1, &mut input.as_slice(), &mut output, &mut scratch).unwrap();
/// let expected = filtfilt(&sos, &x).unwrap();
/// assert_eq!(f64::from_le_bytes(output[80..88].try_into().unwrap()), expected[10]);
/// ```
pub fn filtfilt_stream<S: Read + Write + Seek + ?Sized>(
    sos: &Sos,
    channels: usize,
    input: &mut (impl Read + ?Sized),
    output: &mut (impl Write + ?Sized),
    scratch: &mut S,
) -> Result<u64, StreamError> {
    let c = channels;
    let mut reader = FrameReader::new(input, c)?;
    let mut bank = SosFilterBank::new(sos, c).map_err(|_| StreamError::NoChannels)?;
    let padlen = sos.filtfilt_padlen();
    let mut block = Vec::with_capacity(STREAM_BLOCK_FRAMES * c);
    let mut bytes = Vec::with_capacity((STREAM_BLOCK_FRAMES + padlen + 1) * c * 8);

    // The first padlen + 1 frames make the left extension; keep whatever blocks it takes.
    let mut head: Vec<f64> = Vec::with_capacity((padlen + 1 + STREAM_BLOCK_FRAMES) * c);
    while head.len() < (padlen + 1) * c {
        reader.next_block(&mut block)?;
        if block.is_empty() {
            return Err(StreamError::TooShort {
                samples: (head.len() / c) as u64,
                padlen,
            });
        }
        head.extend_from_slice(&block);
    }

    // Forward pass, written to scratch. The last padlen + 1 raw frames are kept for the right
    // extension.
    scratch.seek(SeekFrom::Start(0))?;
    let frame = |data: &[f64], i: usize| data[i * c..(i + 1) * c].to_vec();
    let first = frame(&head, 0);
    let mut left: Vec<f64> = Vec::with_capacity(padlen * c);
    for i in (1..=padlen).rev() {
        left.extend(
            first
                .iter()
                .zip(frame(&head, i))
                .map(|(x0, xi)| 2.0 * x0 - xi),
        );
    }
    bank.set_steady_state(&left[..c]);
    bank.process_slice(&mut left);
    write_samples(scratch, &left, &mut bytes)?;

    let tail_len = (padlen + 1) * c;
    let mut tail: Vec<f64> = Vec::with_capacity(tail_len + STREAM_BLOCK_FRAMES * c + head.len());
    let mut frames = 0u64;
    let mut pending = head;
    loop {
        if pending.is_empty() {
            reader.next_block(&mut pending)?;
            if pending.is_empty() {
                break;
            }
        }
        tail.extend_from_slice(&pending);
        if tail.len() > tail_len {
            tail.drain(..tail.len() - tail_len);
        }
        frames += (pending.len() / c) as u64;
        bank.process_slice(&mut pending);
        write_samples(scratch, &pending, &mut bytes)?;
        pending.clear();
    }
    let tail_frames = tail.len() / c;
    let last = frame(&tail, tail_frames - 1);
    let mut right: Vec<f64> = Vec::with_capacity(padlen * c);
    for i in 1..=padlen {
        let earlier = frame(&tail, tail_frames - 1 - i);
        right.extend(last.iter().zip(earlier).map(|(xn, xi)| 2.0 * xn - xi));
    }
    bank.process_slice(&mut right);
    write_samples(scratch, &right, &mut bytes)?;
    let last_output = right[(padlen - 1) * c..].to_vec();

    // Backward pass, block by block from the end, in place.
    let total_frames = frames + 2 * padlen as u64;
    bank.reset();
    bank.set_steady_state(&last_output);
    let frame_bytes = (8 * c) as u64;
    let mut end = total_frames;
    let mut samples = Vec::with_capacity(STREAM_BLOCK_FRAMES * c);
    while end > 0 {
        let start = end.saturating_sub(STREAM_BLOCK_FRAMES as u64);
        let count = (end - start) as usize;
        bytes.resize(count * c * 8, 0);
        scratch.seek(SeekFrom::Start(start * frame_bytes))?;
        scratch.read_exact(&mut bytes)?;
        samples.clear();
        samples.extend(
            bytes
                .as_chunks::<8>()
                .0
                .iter()
                .map(|b| f64::from_le_bytes(*b)),
        );
        reverse_frames(&mut samples, c);
        bank.process_slice(&mut samples);
        reverse_frames(&mut samples, c);
        scratch.seek(SeekFrom::Start(start * frame_bytes))?;
        write_samples(scratch, &samples, &mut bytes)?;
        end = start;
    }

    // The result without its padding.
    scratch.seek(SeekFrom::Start(padlen as u64 * frame_bytes))?;
    let copied = io::copy(&mut scratch.take(frames * frame_bytes), output)?;
    if copied != frames * frame_bytes {
        return Err(StreamError::Io(io::Error::new(
            io::ErrorKind::UnexpectedEof,
            "the scratch store returned fewer bytes than were written to it",
        )));
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn sos() -> Sos {
        Sos::from_rows(&[
            [0.1, 0.2, 0.1, 1.0, -1.2, 0.5],
            [1.0, 1.0, 0.0, 1.0, -0.4, 0.0],
        ])
        .unwrap()
    }

    fn bytes(x: &[f64]) -> Vec<u8> {
        x.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    fn floats(b: &[u8]) -> Vec<f64> {
        b.as_chunks::<8>()
            .0
            .iter()
            .map(|c| f64::from_le_bytes(*c))
            .collect()
    }

    #[test]
    fn stream_equals_in_memory_for_lengths_around_the_block_size() {
        let sos = sos();
        let padlen = sos.filtfilt_padlen();
        for channels in [1, 3] {
            for frames in [
                padlen + 1,
                100,
                STREAM_BLOCK_FRAMES - 3,
                STREAM_BLOCK_FRAMES + 5,
            ] {
                let x: Vec<f64> = (0..frames * channels)
                    .map(|i| (i as f64 * 0.37).sin() + 0.01 * i as f64)
                    .collect();
                let expected = filtfilt_interleaved(&sos, &x, channels).unwrap();
                let mut out = Vec::new();
                let mut scratch = Cursor::new(Vec::new());
                let n = filtfilt_stream(
                    &sos,
                    channels,
                    &mut bytes(&x).as_slice(),
                    &mut out,
                    &mut scratch,
                )
                .unwrap();
                assert_eq!(n, frames as u64);
                assert_eq!(
                    floats(&out),
                    expected,
                    "{channels} channels, {frames} frames"
                );
            }
        }
    }

    #[test]
    fn short_and_ragged_inputs_are_errors_that_say_where() {
        let sos = sos();
        let padlen = sos.filtfilt_padlen();
        let x = vec![1.0; padlen];
        assert_eq!(
            filtfilt(&sos, &x),
            Err(FiltfiltError::TooShort {
                samples: padlen,
                padlen
            })
        );
        let e = filtfilt_stream(
            &sos,
            1,
            &mut bytes(&x).as_slice(),
            &mut Vec::new(),
            &mut Cursor::new(Vec::new()),
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("more than {padlen} samples")),
            "{e}"
        );
        let mut ragged = bytes(&[1.0; 6]);
        ragged.extend([0u8; 5]);
        let e = filter_stream(&sos, 3, &mut ragged.as_slice(), &mut Vec::new()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "input is 53 bytes, not a whole number of 24-byte frames (3 channel(s) × 8-byte f64): \
             the last 5 byte(s), from byte offset 48, were not filtered"
        );
        assert_eq!(
            filtfilt_interleaved(&sos, &[1.0; 7], 2),
            Err(FiltfiltError::RaggedFrames {
                samples: 7,
                channels: 2
            })
        );
    }

    #[test]
    fn non_finite_samples_and_absurd_channel_counts_are_refused_with_where() {
        let sos = sos();
        // Frame 9000 lies in the second block, so the frame count must carry across blocks.
        let mut x = vec![0.5; 3 * 10_000];
        x[3 * 9000 + 2] = f64::NAN;
        let e = filter_stream(&sos, 3, &mut bytes(&x).as_slice(), &mut Vec::new()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("sample NaN at frame 9000, channel 2 (byte offset 216016)"),
            "{e}"
        );
        let e = filtfilt_stream(
            &sos,
            1,
            &mut bytes(&[1.0, f64::INFINITY]).as_slice(),
            &mut Vec::new(),
            &mut Cursor::new(Vec::new()),
        )
        .unwrap_err();
        assert!(e.to_string().contains("frame 1, channel 0"), "{e}");
        let e = filter_stream(&sos, usize::MAX, &mut [0u8; 0].as_slice(), &mut Vec::new());
        assert!(matches!(e, Err(StreamError::TooManyChannels(_))));
        let e = filter_stream(&sos, 0, &mut [0u8; 0].as_slice(), &mut Vec::new());
        assert!(matches!(e, Err(StreamError::NoChannels)));
    }

    #[test]
    fn causal_stream_equals_the_bank_on_the_whole() {
        let sos = sos();
        let x: Vec<f64> = (0..3 * 10_000).map(|i| (i as f64 * 0.01).cos()).collect();
        let mut out = Vec::new();
        filter_stream(&sos, 3, &mut bytes(&x).as_slice(), &mut out).unwrap();
        let mut bank = SosFilterBank::new(&sos, 3).unwrap();
        let mut expected = x.clone();
        bank.process_slice(&mut expected);
        assert_eq!(floats(&out), expected);
    }
}
