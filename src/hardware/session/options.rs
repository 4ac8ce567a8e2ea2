//! The host's settings ([`SessionOptions`]): its watchdog, the handshake's time limit and the
//! safe override.

use crate::plant::cnc::MAX_OVERRIDE_PCT;

/// The host's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionOptions {
    /// The host's watchdog, wall seconds: no sample for this long while a part runs under the
    /// host, or no frame at all while connected, is an alarm.
    pub link_timeout_s: f64,
    /// How long the device may take to answer the Hello.
    pub handshake_timeout_s: f64,
    /// The override commanded on Disarm, Escape and alarms; `None`: the device's own fallback.
    pub safe_override_pct: Option<f64>,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            link_timeout_s: 2.0,
            handshake_timeout_s: 10.0,
            safe_override_pct: None,
        }
    }
}

impl SessionOptions {
    /// Options with a host watchdog of `link_timeout_s` and a safe override (`None`: the
    /// device's fallback); the handshake may take five times the watchdog, as `cutlab host`'s.
    ///
    /// ```
    /// use cutlab::hardware::session::SessionOptions;
    /// assert_eq!(SessionOptions::new(2.0, None).unwrap().handshake_timeout_s, 10.0);
    /// assert!(SessionOptions::new(2.0, Some(-5.0)).is_err());
    /// ```
    pub fn new(link_timeout_s: f64, safe_override_pct: Option<f64>) -> Result<Self, String> {
        let link_timeout_s = crate::protocol::host::check_link_timeout_s(link_timeout_s)?;
        if let Some(pct) = safe_override_pct {
            if !(0.0..=MAX_OVERRIDE_PCT).contains(&pct) {
                return Err(format!(
                    "the safe override must be 0 to {MAX_OVERRIDE_PCT} %, not {} %",
                    crate::input::readable(pct)
                ));
            }
        }
        Ok(Self {
            link_timeout_s,
            handshake_timeout_s: 5.0 * link_timeout_s,
            safe_override_pct,
        })
    }
}
