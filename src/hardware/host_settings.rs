//! The host's own safety settings as one table: the host watchdog (`cutlab host
//! --link-timeout-s`, the Hardware page's Host watchdog) and the override a lost link falls back
//! to, parsed by [`parse_host`] into the session's options.

use super::session::SessionOptions;
use crate::input::table::{Kind, Reader, Row, RowError, Shown, Table};
use crate::plant::cnc::MAX_OVERRIDE_PCT;
use crate::protocol::host::{DEFAULT_LINK_TIMEOUT_S, LINK_TIMEOUT_RANGE_S};

/// Every setting of the host's own safety.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HostSetting {
    /// The host's watchdog: no sample for this long is a lost link.
    LinkTimeout,
    /// The override the host commands when it gives up (blank: the device's fallback).
    SafeOverride,
}

impl Table for HostSetting {
    const ROWS: &'static [Self] = &[HostSetting::SafeOverride, HostSetting::LinkTimeout];

    fn row(self) -> Row {
        match self {
            HostSetting::LinkTimeout => Row::new(
                "host_watchdog",
                "link-timeout-s",
                "Host watchdog",
                "s",
            )
            .takes(
                Kind::Number {
                    min: LINK_TIMEOUT_RANGE_S.0,
                    max: LINK_TIMEOUT_RANGE_S.1,
                },
                Shown::Number(DEFAULT_LINK_TIMEOUT_S),
            )
            .help(
                "the host's watchdog: no sample for this long (wall time) is a lost link; the \
                     handshake waits five times as long for a device to answer",
            ),
            HostSetting::SafeOverride => Row::new(
                "safe_override",
                "",
                "Safe override (blank: the device's fallback)",
                "%",
            )
            .takes(
                Kind::Number {
                    min: 0.0,
                    max: MAX_OVERRIDE_PCT,
                },
                Shown::Blank,
            )
            .help("the override the host commands when it disarms or loses the link"),
        }
    }
}

/// Parses the typed text of the host's settings (those not given take their defaults).
///
/// ```
/// use cutlab::hardware::host_settings::{parse_host, HostSetting};
/// let options = parse_host(&[(HostSetting::LinkTimeout, "1")]).unwrap();
/// assert_eq!((options.link_timeout_s, options.safe_override_pct), (1.0, None));
/// let e = parse_host(&[(HostSetting::LinkTimeout, "1e300")]).unwrap_err();
/// assert_eq!(e[0].for_cli(), "--link-timeout-s: 1e300 s is outside 0.1–60 s");
/// ```
pub fn parse_host<T: AsRef<str>>(
    texts: &[(HostSetting, T)],
) -> Result<SessionOptions, Vec<RowError<HostSetting>>> {
    let mut reader = Reader::new(texts);
    let link_timeout_s = reader.number(HostSetting::LinkTimeout);
    let safe_override_pct = reader.number(HostSetting::SafeOverride);
    // The rows' ranges are the options' own: they build.
    let options = link_timeout_s.and_then(|t| SessionOptions::new(t, safe_override_pct).ok());
    reader.finish(options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::table::check_table;

    #[test]
    fn the_table_holds_and_whatever_it_takes_makes_the_sessions_options() {
        assert_eq!(check_table::<HostSetting>(), Ok(()));
        for s in HostSetting::ROWS {
            let (min, max) = s.row().range().unwrap();
            for v in [min, max] {
                let text = format!("{v:e}");
                let options = parse_host(&[(*s, text.as_str())]);
                assert!(options.is_ok(), "{s:?} {v}: {options:?}");
            }
        }
        assert_eq!(
            parse_host::<&str>(&[]).unwrap(),
            SessionOptions::new(DEFAULT_LINK_TIMEOUT_S, None).unwrap()
        );
    }
}
