//! What the emulator reports beside its frames: its counts ([`DeviceStats`]), why it holds the
//! feed ([`HoldCause`]), and one [`DeviceTraceRow`] per sample for `cutlab device --trace`.

/// What the emulator counted, for its diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DeviceStats {
    /// Frames sent (before injection).
    pub frames_sent: u64,
    /// Frames dropped by injection, either way.
    pub frames_dropped: u64,
    /// Frames corrupted by injection, either way.
    pub frames_corrupted: u64,
    /// Bytes discarded by a stall or while unplugged.
    pub bytes_discarded: u64,
    /// Valid frames received.
    pub frames_received: u64,
    /// Watchdog firings.
    pub watchdog_fallbacks: u64,
    /// Parts started.
    pub parts: u64,
}

/// Why the device holds the feed, latched until the operator resets it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HoldCause {
    /// The host asked for a feed hold (the safety envelope's overload).
    Host,
    /// The device read an over-current (a crash, a broken tool).
    OverCurrent,
    /// The watchdog's fallback lasted its time limit.
    FallbackLimit,
}

impl HoldCause {
    /// In words, for diagnostics and the trace.
    pub fn name(self) -> &'static str {
        match self {
            HoldCause::Host => "host feed hold",
            HoldCause::OverCurrent => "over-current",
            HoldCause::FallbackLimit => "fallback time limit",
        }
    }
}

/// What the emulated bridge applied at one sample: what `cutlab device --trace` writes, so every
/// fault path can be checked from outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceTraceRow {
    /// Device time at the end of the sample.
    pub time_s: f64,
    /// The part (1 = the first).
    pub part: u64,
    /// The sample's sequence number.
    pub seq: u32,
    /// The host holds the override (armed, not in fallback).
    pub armed: bool,
    /// The watchdog's fallback is applied.
    pub fallback: bool,
    /// The feed is held (any cause).
    pub feed_hold: bool,
    /// The latched hold's cause, if the hold is latched.
    pub hold_latched: Option<HoldCause>,
    /// The override the bridge outputs.
    pub bridge_override_pct: f64,
    /// The override the CNC applies (it differs from the bridge's when the override is stuck).
    pub cnc_override_pct: f64,
    /// The block's programmed feed.
    pub programmed_feed_mm_min: f64,
    /// The actual feed.
    pub feed_mm_min: f64,
    /// Faults active ([`fault_flag`] bits).
    ///
    /// [`fault_flag`]: crate::protocol::frame::fault_flag
    pub faults: u8,
}

impl DeviceTraceRow {
    /// The CSV header of [`DeviceTraceRow::csv_line`].
    pub const CSV_HEADER: &'static str = "time_s,part,seq,armed,fallback,feed_hold,hold_latched,\
bridge_override_pct,cnc_override_pct,programmed_feed_mm_min,feed_mm_min,faults";

    /// The row as a CSV line (no newline).
    pub fn csv_line(&self) -> String {
        format!(
            "{:.4},{},{},{},{},{},{},{},{},{},{},{}",
            self.time_s,
            self.part,
            self.seq,
            u8::from(self.armed),
            u8::from(self.fallback),
            u8::from(self.feed_hold),
            self.hold_latched.map_or("", HoldCause::name),
            self.bridge_override_pct,
            self.cnc_override_pct,
            self.programmed_feed_mm_min,
            self.feed_mm_min,
            self.faults
        )
    }
}
