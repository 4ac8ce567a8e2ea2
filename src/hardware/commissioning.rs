//! The commissioning procedure of docs/hardware.md §10, as the checks the Hardware page names
//! before the first Arm on a device it has not seen commissioned: one definition, which the
//! page lists and a test finds, check by check, in the document.

/// The highest override of reduce-only limits: the loop can only slow the programmed feed. The
/// Hardware page starts from it on a real port, and the first cuts run at it (docs/hardware.md
/// §7, §10).
pub const REDUCE_ONLY_MAX_OVERRIDE_PCT: f64 = 100.0;

/// Where a browser remembers the devices whose commissioning the engineer confirmed (their
/// identities, one a line): the first Arm on any other names every check first.
pub const COMMISSIONED_DEVICES_KEY: &str = "cutlab-commissioned-devices";

/// Whether `device_id` is among the `stored` identities (one a line).
///
/// ```
/// use cutlab::hardware::commissioning::{commissioned, with_commissioned};
/// let stored = with_commissioned(None, "bridge-7");
/// assert!(commissioned(Some(&stored), "bridge-7") && !commissioned(Some(&stored), "bridge-8"));
/// assert_eq!(with_commissioned(Some(&stored), "bridge-7"), stored);
/// ```
pub fn commissioned(stored: Option<&str>, device_id: &str) -> bool {
    stored.is_some_and(|text| text.lines().any(|l| l == device_id))
}

/// The `stored` identities with `device_id` added.
pub fn with_commissioned(stored: Option<&str>, device_id: &str) -> String {
    if commissioned(stored, device_id) {
        return stored.unwrap_or_default().to_string();
    }
    let mut text = stored.unwrap_or_default().trim_end().to_string();
    if !text.is_empty() {
        text.push('\n');
    }
    text.push_str(device_id);
    text
}

/// One check of the commissioning procedure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Check {
    /// A short key (stored with the device's identity once every check is confirmed).
    pub key: &'static str,
    /// What the engineer checks, in one sentence: the same words as docs/hardware.md §10.
    pub text: &'static str,
}

/// The checks, in the order they are made.
pub const CHECKS: [Check; 10] = [
    Check {
        key: "backup",
        text: "The ladder and the control's parameters are backed up, and the backup read back.",
    },
    Check {
        key: "lockout",
        text:
            "Every change in the cabinet was made locked out and tagged out, the DC link checked \
               discharged with a rated meter, by a qualified electrician.",
    },
    Check {
        key: "pmc-bits",
        text: "Every bridge output was toggled on the bench and seen on the PMC diagnosis screen, \
               on the right address, and nothing else moved.",
    },
    Check {
        key: "dead-bridge",
        text: "With the bridge unpowered, reset and its firmware halted, the machine's own dial \
               sets the override (relays or enable dropped), never a code of the bridge.",
    },
    Check {
        key: "watchdog",
        text: "Stopping the host gives the fallback within the watchdog timeout, never above the \
               override applied, and a latched feed hold after the fallback's time limit.",
    },
    Check {
        key: "feed-hold",
        text: "The feed-hold contact stops a running axis, G00 included, and the hold stays \
               through a link loss and a host restart until the reset at the machine.",
    },
    Check {
        key: "sensors",
        text: "Each current channel reads a known current on the bench (N turns through the \
               transducer), an unplugged transducer raises the sensor fault, and the three phases \
               sum to zero in a run.",
    },
    Check {
        key: "override-seen",
        text: "In an air cut, each override the host commands shows on the CNC screen and in the \
               actual feed, and a selector left on the dial raises the stuck-override alarm.",
    },
    Check {
        key: "reduce-only",
        text: "The first cuts run reduce-only: the bridge's highest override 100 %, the teach cut \
               inside it, a conservative current target.",
    },
    Check {
        key: "risk",
        text: "The risk assessment is written and signed, and the operator knows the loop is not \
               a safety function: the E-stop and feed hold within reach.",
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_check_has_its_own_key_and_one_sentence() {
        for (i, a) in CHECKS.iter().enumerate() {
            assert!(
                a.text.ends_with('.') && a.text.matches(". ").count() == 0,
                "{a:?}"
            );
            assert!(CHECKS[i + 1..].iter().all(|b| b.key != a.key), "{a:?}");
        }
    }
}
