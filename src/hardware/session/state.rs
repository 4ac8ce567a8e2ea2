//! What the page shows of a link: its state ([`LinkState`]), what the host does with the device
//! ([`Stage`]), and the events for the event log and the recording ([`SessionEvent`]).

/// The link's state, as the page shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkState {
    /// No device (before connecting, after disconnecting, or the handshake failed).
    Closed,
    /// Waiting for the device's Capabilities.
    Handshaking,
    /// The device answers; the host does not control it.
    Streaming,
    /// The host controls the override (a teach cut or the closed loop).
    Armed,
    /// Something went wrong; the override is held at the safe value where the device still
    /// listens. Stays until acknowledged.
    Alarm,
}

impl LinkState {
    /// Every state.
    pub const ALL: [LinkState; 5] = [
        LinkState::Closed,
        LinkState::Handshaking,
        LinkState::Streaming,
        LinkState::Armed,
        LinkState::Alarm,
    ];

    /// The word the page shows.
    pub fn name(self) -> &'static str {
        match self {
            LinkState::Closed => "closed",
            LinkState::Handshaking => "handshaking",
            LinkState::Streaming => "streaming",
            LinkState::Armed => "armed",
            LinkState::Alarm => "alarm",
        }
    }
}

/// What the host does with the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Nothing: the machine runs on its own dial.
    Idle,
    /// A teach cut under way.
    TeachCut,
    /// The closed loop under way.
    ClosedLoop,
    /// The safe override held until the part ends.
    HoldingSafe,
}

impl Stage {
    /// A short label (the recording's phase column).
    pub fn label(self) -> &'static str {
        match self {
            Stage::Idle => "not armed",
            Stage::TeachCut => "teach cut",
            Stage::ClosedLoop => "closed loop",
            Stage::HoldingSafe => "held at the safe override",
        }
    }
}

/// Something that happened, for the event log and the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionEvent {
    /// Device time since the session's first sample (0 before it).
    pub time_s: f64,
    /// What.
    pub text: String,
}
