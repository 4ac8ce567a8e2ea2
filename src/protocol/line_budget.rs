//! What a device's stream asks of its serial line: the bytes of each frame on the wire, the
//! device's samples, heartbeats and acknowledgements a second, against its declared baud rate
//! and the headroom a line keeps (docs/protocol.md §1). Both hosts, `cutlab host` and the
//! Hardware page, refuse a device whose line cannot carry its stream before they arm it.

use super::frame::{feature, Capabilities, FrameType};

/// Bits on the line per byte: 8 data bits, a start and a stop bit (8N1).
pub const BITS_PER_BYTE: f64 = 10.0;

/// The share of a UART's baud rate the protocol may plan to use: the rest is headroom for
/// repeated commands, fault reports and the bursts a USB-serial adapter's latency timer makes.
pub const LINE_LOAD_LIMIT: f64 = 0.7;

/// Commands (and their Acks) a second the handshake's line budget allows for: one per control
/// period of 20 ms, half the shortest default period. A run whose period is set shorter asks for
/// more, which the hosts check before arming it ([`LineBudget::for_period`]).
pub const COMMANDS_PER_S: f64 = 50.0;

/// A frame's length on the wire: its payload, 4 bytes of CRC, 1 of COBS overhead (payload and
/// CRC fit one COBS group up to 254 bytes) and the two delimiters.
pub const fn wire_len(frame_type: FrameType) -> usize {
    frame_type.payload_len() + 4 + 1 + 2
}

/// What a device's stream asks of its line, against its declared baud rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineBudget {
    /// Bits per second both ways at the busiest: the device's samples (and SimTruth frames) and
    /// heartbeats, the host's commands and heartbeats, and the device's Acks.
    pub bits_per_s: f64,
    /// The device's declared baud rate (0: none).
    pub baud: u32,
    /// The commands a second it allows for: [`COMMANDS_PER_S`], or a run's one per period.
    pub commands_per_s: f64,
}

impl LineBudget {
    /// The budget of a device with `caps`.
    ///
    /// ```
    /// use cutlab::protocol::line_budget::LineBudget;
    /// # let mut caps = cutlab::protocol::device::DeviceEmulator::new(
    /// #     cutlab::protocol::device::DeviceConfig::new(cutlab::plant::Preset::KimStepDoc)).unwrap()
    /// #     .capabilities().clone();
    /// caps.features = 0; // a real bridge: no SimTruth
    /// caps.sample_rate_hz = 1000.0;
    /// caps.line_baud = 921_600;
    /// let b = LineBudget::of(&caps);
    /// assert!((b.bits_per_s - 520_700.0).abs() < 1.0 && b.fits());
    /// caps.line_baud = 115_200;
    /// assert!(!LineBudget::of(&caps).fits());
    /// ```
    pub fn of(caps: &Capabilities) -> Self {
        Self::with_commands(caps, COMMANDS_PER_S)
    }

    /// The budget of a device with `caps` running a loop of `control_period_s`: one command and
    /// its Ack a period, and never less than the handshake allowed for ([`COMMANDS_PER_S`]).
    ///
    /// ```
    /// use cutlab::protocol::line_budget::LineBudget;
    /// # let mut caps = cutlab::protocol::device::DeviceEmulator::new(
    /// #     cutlab::protocol::device::DeviceConfig::new(cutlab::plant::Preset::KimStepDoc)).unwrap()
    /// #     .capabilities().clone();
    /// caps.features = 0;
    /// caps.sample_rate_hz = 100.0;
    /// caps.line_baud = 115_200;
    /// assert!(LineBudget::for_period(&caps, 0.05).fits());
    /// assert_eq!(LineBudget::for_period(&caps, 0.05), LineBudget::of(&caps));
    /// // A 2 ms period's 500 Acks a second do not fit beside the samples.
    /// let fast = LineBudget::for_period(&caps, 0.002);
    /// assert!(!fast.fits() && fast.refusal().unwrap().contains("lengthen the control period"));
    /// ```
    pub fn for_period(caps: &Capabilities, control_period_s: f64) -> Self {
        // A period that is not a positive number allows for no rate at all: refused.
        let per_period = if control_period_s > 0.0 {
            1.0 / control_period_s
        } else {
            f64::INFINITY
        };
        Self::with_commands(caps, per_period.max(COMMANDS_PER_S))
    }

    fn with_commands(caps: &Capabilities, commands_per_s: f64) -> Self {
        let rate = f64::from(caps.sample_rate_hz);
        let sample = wire_len(FrameType::Sample) as f64
            + if caps.features & feature::SIM_TRUTH != 0 {
                wire_len(FrameType::SimTruth) as f64
            } else {
                0.0
            };
        let heartbeat = wire_len(FrameType::Heartbeat) as f64;
        let device_heartbeats_per_s = 1.0 / super::device::HEARTBEAT_INTERVAL_S;
        // Each way is its own wire; the device's way carries the most, and the Acks.
        let device_bytes_per_s = rate * sample
            + device_heartbeats_per_s * heartbeat
            + commands_per_s * wire_len(FrameType::Ack) as f64;
        Self {
            bits_per_s: device_bytes_per_s * BITS_PER_BYTE,
            baud: caps.line_baud,
            commands_per_s,
        }
    }

    /// Whether the stream fits the line with its headroom (a line without a baud rate fits).
    pub fn fits(&self) -> bool {
        self.baud == 0 || self.bits_per_s <= LINE_LOAD_LIMIT * f64::from(self.baud)
    }

    /// Why the line cannot carry the stream, if it cannot: the message a host refuses with.
    pub fn refusal(&self) -> Option<String> {
        (!self.fits()).then(|| {
            format!(
                "the device's line cannot carry its stream: {:.0} bit/s at the busiest is {:.0} % \
                 of its {} baud, above the {:.0} % a line may plan to use (docs/protocol.md §1): \
                 {}",
                self.bits_per_s,
                100.0 * self.bits_per_s / f64::from(self.baud),
                self.baud,
                100.0 * LINE_LOAD_LIMIT,
                if self.commands_per_s > COMMANDS_PER_S {
                    format!(
                        "its {:.0} commands a second (one per control period) are more than \
                         the {COMMANDS_PER_S:.0} the handshake allowed for; lengthen the control \
                         period, lower the sample rate or raise the baud rate",
                        self.commands_per_s
                    )
                } else {
                    "lower the sample rate or raise the baud rate".to_string()
                }
            )
        })
    }
}
