//! What the envelope saw and did, for the event log: [`SensorFault`], the sensor faults it
//! recognises, and [`SafetyEvent`], each event with its time and a one-line description.

use super::chip_load::ChipLoadEnd;

/// A sensor fault the envelope recognises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SensorFault {
    /// A phase current is NaN or infinite.
    NonFinite,
    /// A phase current exceeds the plausible range.
    OutOfRange,
    /// Every phase current repeats exactly while the axes move.
    Stuck,
    /// Samples are missing (a time gap).
    MissingSamples,
}

impl SensorFault {
    /// A short description for the event log.
    pub fn describe(self) -> &'static str {
        match self {
            SensorFault::NonFinite => "a current reading is not a number",
            SensorFault::OutOfRange => "a current reading is out of range",
            SensorFault::Stuck => "the current readings are stuck",
            SensorFault::MissingSamples => "samples are missing",
        }
    }
}

/// Something the envelope did or saw, for the event log.
/// Serialised for a trace sent from a worker to the page (a NaN is written as null and read back
/// as NaN).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum SafetyEvent {
    /// The arming delay passed: the controller is now in charge.
    Armed {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
    },
    /// A sensor fault began; the override is held or falls back.
    FaultDetected {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// Which fault.
        fault: SensorFault,
    },
    /// The sensors have been healthy for the recovery time.
    FaultCleared {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
    },
    /// The estimated force stayed above the hard limit: feed hold is latched.
    Overload {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The force that tripped the alarm.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        force_n: f64,
    },
    /// The controller asked for a non-finite override (a law fed garbage, or one that diverged):
    /// the envelope holds the override until the requests are numbers again.
    ControllerFault {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
    },
    /// The tool was cutting before the loop armed: the controller enters the cut uncontrolled
    /// (a part program should approach in air until the arming delay has passed).
    CutBeforeArming {
        /// When the cut was first seen.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The estimated force then.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        force_n: f64,
    },
    /// The tool is in air and the controller asked for more than the entry override: the
    /// envelope holds the entry override until the estimate shows a cut again (once per stretch
    /// of air).
    AirCut {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The override held.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        entry_override_pct: f64,
    },
    /// The tool entered a cut: the override stays at the entry override until the cutter is
    /// engaged.
    EntryHold {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The override held at most.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        entry_override_pct: f64,
    },
    /// The cutter is engaged after an entry, or the load reached the target: the controller takes
    /// over.
    EntrySettled {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The estimated force it settled at.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        force_n: f64,
    },
    /// The chip-load window held the override (once per stretch that it holds at that end).
    ChipLoad {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The window's end that held.
        end: ChipLoadEnd,
        /// The feed per tooth there, mm.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        feed_per_tooth_mm: f64,
        /// The feed per tooth the machine runs at once the envelope has held it, mm: the
        /// window's end where the envelope's band reaches it, beyond it where even the band's
        /// end cannot (a programmed feed far too high, or too low, for the cutter).
        #[serde(
            default = "crate::estimation::nan",
            deserialize_with = "crate::estimation::null_as_nan"
        )]
        running_mm: f64,
    },
}

/// How far (a fraction) the feed per tooth the machine runs at may lie beyond the chip-load
/// window's end before an event says the window could not be kept: more than the override's
/// quantisation moves it.
const CHIP_LOAD_REACH: f64 = 0.02;

impl SafetyEvent {
    /// When the event happened.
    pub fn time_s(&self) -> f64 {
        match *self {
            SafetyEvent::Armed { time_s }
            | SafetyEvent::FaultDetected { time_s, .. }
            | SafetyEvent::FaultCleared { time_s }
            | SafetyEvent::Overload { time_s, .. }
            | SafetyEvent::CutBeforeArming { time_s, .. }
            | SafetyEvent::AirCut { time_s, .. }
            | SafetyEvent::EntryHold { time_s, .. }
            | SafetyEvent::EntrySettled { time_s, .. }
            | SafetyEvent::ChipLoad { time_s, .. }
            | SafetyEvent::ControllerFault { time_s } => time_s,
        }
    }

    /// A one-line description.
    pub fn describe(&self) -> String {
        match *self {
            SafetyEvent::Armed { .. } => "armed: the controller now sets the override".into(),
            SafetyEvent::FaultDetected { fault, .. } => {
                format!("sensor fault: {}; override held", fault.describe())
            }
            SafetyEvent::FaultCleared { .. } => "sensor fault cleared".into(),
            SafetyEvent::Overload { force_n, .. } => {
                format!("overload: an estimated {force_n:.0} N above the hard limit; feed hold")
            }
            SafetyEvent::ControllerFault { .. } => {
                "controller fault: it asked for a non-finite override; override held".into()
            }
            SafetyEvent::CutBeforeArming { force_n, .. } => format!(
                "warning: cutting (an estimated {force_n:.0} N) before the loop armed; the controller enters \
                 the cut uncontrolled (approach in air until the arming delay has passed)"
            ),
            SafetyEvent::AirCut {
                entry_override_pct, ..
            } => format!(
                "air cut: override held at {entry_override_pct:.0} % until the tool enters the cut"
            ),
            SafetyEvent::EntryHold {
                entry_override_pct, ..
            } => format!(
                "entry: the tool entered the cut; override held at {entry_override_pct:.0} % \
                 until the cutter is engaged"
            ),
            SafetyEvent::EntrySettled { force_n, .. } => format!(
                "entry: the cutter is in the cut at {force_n:.0} N; the controller takes over"
            ),
            SafetyEvent::ChipLoad {
                end: ChipLoadEnd::Highest,
                feed_per_tooth_mm,
                running_mm,
                ..
            } if running_mm > feed_per_tooth_mm * (1.0 + CHIP_LOAD_REACH) => format!(
                "chip load: even the lowest override the envelope allows runs {running_mm:.3} mm \
                 per tooth, above the {feed_per_tooth_mm:.3} mm the edge takes: the programmed \
                 feed is too high for this cutter"
            ),
            SafetyEvent::ChipLoad {
                end: ChipLoadEnd::Lowest,
                feed_per_tooth_mm,
                running_mm,
                ..
            } if running_mm < feed_per_tooth_mm * (1.0 - CHIP_LOAD_REACH) => format!(
                "chip load: even the highest override the envelope allows runs {running_mm:.3} mm \
                 per tooth, below the {feed_per_tooth_mm:.3} mm under which the edge rubs: the \
                 programmed feed is too low for this cutter"
            ),
            SafetyEvent::ChipLoad {
                end,
                feed_per_tooth_mm,
                ..
            } => match end {
                ChipLoadEnd::Highest => format!(
                    "chip load: override held so the feed per tooth stays at most \
                     {feed_per_tooth_mm:.3} mm"
                ),
                ChipLoadEnd::Lowest => format!(
                    "chip load: override held so the feed per tooth stays at least \
                     {feed_per_tooth_mm:.3} mm (below, the edge rubs)"
                ),
            },
        }
    }
}
