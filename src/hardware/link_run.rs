//! The closed loop over a native byte link (native only): `cutlab host`'s run — the teach cut on
//! the device's first part and the closed loop on its second, through the same [`LabRun`]
//! `cutlab sim` uses — on the parts a [`HostLink`] presents as machines.
//!
//! The transport ([`crate::protocol::link`]) knows frames, parts and watchdogs; what a run is —
//! the teach force, the calibration, the metrics of a run cut short — lives here, above it.

use std::cell::RefCell;
use std::rc::Rc;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::error::LoopError;
use crate::closed_loop::lab::{
    cut_model_teach_force, metrics_config, LabRun, RunMachines, RunResult,
};
use crate::closed_loop::metrics::compute;
use crate::closed_loop::teach_cut::TeachForce;
use crate::estimation::estimator::Calibration;
use crate::hardware::session::{check_line, check_measured};
use crate::protocol::host::{DeviceSummary, LinkEvent, LinkStats};
use crate::protocol::link::{HostAlarm, HostError, HostLink, LinkPart, TEACH_CUT_FELL_BACK};
use crate::work::Work;

/// A closed-loop run made over a link.
pub struct LinkRun {
    /// The run (its trace marked incomplete and its metrics recomputed when the link was lost).
    pub result: Result<RunResult, HostError>,
    /// What crossed the link.
    pub stats: LinkStats,
    /// What happened on it.
    pub events: Vec<LinkEvent>,
    /// Whether the host's watchdog (or an I/O error) ended it.
    pub link_lost: bool,
    /// The device fault that stopped the loop, if one did.
    pub alarm: Option<HostAlarm>,
    /// The device.
    pub device: DeviceSummary,
}

/// Runs `spec`'s teach cut and closed loop on the device at the other end of `link`, through the
/// same [`LabRun`] `cutlab sim` uses: the first part is the teach cut, the second the run. With
/// `calibration` (a saved calibration file) there is no teach cut: the first part is the run.
/// The teach cut takes its force from the simulation's truth when the device sends it, otherwise
/// from the model of the preset's cut ([`cut_model_teach_force`]); a program whose cut changes
/// along the path needs a calibration. `duration_s` stops the closed loop early.
///
/// A link lost or a device fault's alarm (docs/protocol.md §5) during the teach cut is an error
/// (no calibration, no run); during the run, the result holds the run up to there, its trace
/// marked incomplete, and [`LinkRun::link_lost`] or [`LinkRun::alarm`] says why.
pub fn run_on_link(
    link: HostLink,
    spec: &RunSpec,
    duration_s: Option<f64>,
    calibration: Option<Calibration>,
) -> LinkRun {
    let device = DeviceSummary::of(link.capabilities());
    if let Err(why) = check_measured(link.capabilities(), false)
        .and_then(|()| check_measured(link.capabilities(), calibration.is_some()))
        .and_then(|()| check_line(link.capabilities(), spec))
    {
        let mut link = link;
        link.finish();
        let session = link.session();
        return LinkRun {
            result: Err(HostError(why)),
            stats: session.stats(),
            events: session.events().to_vec(),
            link_lost: false,
            alarm: None,
            device,
        };
    }
    // The part the closed loop runs on: the second, after the teach cut's.
    let run_part = if calibration.is_some() { 1 } else { 2 };
    let teach_force = if device.sim_truth {
        Some(TeachForce::SimulationTruth)
    } else {
        cut_model_teach_force(spec.preset)
    };
    let link = Rc::new(RefCell::new(link));
    let part = || Box::new(LinkPart::new(Rc::clone(&link)));
    // A loop that starts at once from a calibration is built before `limit_duration_s` can
    // reach it, so its part ends at the limit instead.
    let mut stopped_at_limit = Rc::new(RefCell::new(false));
    let run = match (calibration, teach_force) {
        (Some(calibration), _) => {
            let mut run_part = part();
            stopped_at_limit = run_part.stop_at(duration_s);
            LabRun::calibrated_on(spec, run_part, calibration)
        }
        (None, Some(teach_force)) => LabRun::on_machines(
            spec,
            RunMachines::Separate {
                teach: Box::new(LinkPart::new(Rc::clone(&link)).abandoning_on_fallback()),
                run: part(),
            },
            teach_force,
        ),
        (None, None) => Err(LoopError::NoTeachForce),
    };
    let result = run.and_then(|mut run| {
        if let Some(d) = duration_s {
            run.limit_duration_s(d);
        }
        run.run_to_end()
    });
    let result = result.map_err(|e: LoopError| HostError(e.to_string()));
    let mut link = link.borrow_mut();
    link.finish();
    let lost = link.lost();
    let alarm = link.alarm().cloned();
    // What ended the session before the run's program could end, and in which part.
    let stopped = match (&alarm, link.lost_in_part(), link.fell_back_in_part()) {
        (Some(a), _, _) => Some((a.part, a.text.clone())),
        (None, Some(part), _) => Some((part, link.lost_reason())),
        (None, None, Some(part)) => Some((part, TEACH_CUT_FELL_BACK.to_string())),
        (None, None, None) => None,
    };
    let result = match (result, stopped) {
        (result, Some((part, why))) if part < run_part => {
            let then = match result {
                Err(HostError(e)) => format!(" ({e})"),
                Ok(_) => String::new(),
            };
            Err(HostError(format!(
                "the teach cut (part {part}) was abandoned, so there is no run: {why}{then}"
            )))
        }
        (Ok(mut r), Some(_)) => {
            // The loop saw the part end; it ended because the link or the alarm did.
            r.trace.completed = false;
            r.metrics = compute(&r.trace, &metrics_config(r.spec.preset, &r.settings));
            Ok(r)
        }
        (Ok(mut r), None) if *stopped_at_limit.borrow() => {
            r.trace.completed = false;
            r.metrics = compute(&r.trace, &metrics_config(r.spec.preset, &r.settings));
            Ok(r)
        }
        (result, _) => result,
    };
    let session = link.session();
    LinkRun {
        result,
        stats: session.stats(),
        events: session.events().to_vec(),
        link_lost: lost,
        alarm,
        device,
    }
}
