//! The calibrations of a page's last teach cuts, so an edit that leaves the teach cut as it was
//! (a controller parameter, the target, the envelope) re-runs only the loop.

use leptos::prelude::*;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::TeachKey;
use crate::closed_loop::precomputed::shipped_calibrations;
use crate::estimation::estimator::Calibration;
use crate::web::components::recent;

/// Known calibrations by teach cut, newest last; the teach cuts shipped with the code (the
/// default scenario's) are among them, so its first run starts with the closed loop. Those are
/// parsed when the first run asks for them, in the task that starts it, not while the page mounts.
#[derive(Clone, Copy)]
pub struct KeptCalibrations {
    known: StoredValue<Option<Vec<(TeachKey, Calibration)>>>,
    keep: usize,
}

impl KeptCalibrations {
    /// Keeps the calibrations of the last `keep` teach cuts.
    pub fn new(keep: usize) -> Self {
        Self {
            known: StoredValue::new(None),
            keep,
        }
    }

    /// Every known calibration, for a new run to reuse.
    pub fn known(&self) -> Vec<(TeachKey, Calibration)> {
        self.known
            .try_update_value(|known| known.get_or_insert_with(shipped_calibrations).clone())
            .unwrap_or_default()
    }

    /// Remembers the calibration of a finished run of `spec`, dropping the oldest beyond `keep`.
    pub fn remember(&self, spec: &RunSpec, calibration: &Calibration) {
        let Ok(key) = TeachKey::of(spec) else {
            return;
        };
        let keep = self.keep;
        self.known.update_value(|known| {
            let known = known.get_or_insert_with(shipped_calibrations);
            recent::remember(known, key, calibration.clone(), keep);
        });
    }
}
