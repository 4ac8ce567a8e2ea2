//! The page's other jobs for a computation worker: paper 000's bench recording (the Signal chain
//! page), an open-loop recording of a preset's machine (the Machine page) and the teach cuts of
//! Tune's teach-in; each a [`Work`] the worker advances in one go while it posts progress.
//!
//! A recording is megabytes of numbers, so its answer is [`Packed`]: the long lists travel as raw
//! `f64`s (a transferred `Float64Array` each in the browser, moved rather than copied) and the
//! rest as JSON, whose numbers read back exactly (serde_json's `float_roundtrip`). What the page
//! rebuilds equals what the page itself would have recorded with the same seed, bit for bit (the
//! tests below). A teach-in's answer is its calibrations, from which the page derives the
//! proposals as `cutlab tune --teach-in` does.

use serde::{Deserialize, Serialize};

use super::definition::RunSpec;
use super::flat_row::flat_row;
use super::lab::teach_cut_work;
use super::sample_loop::OnMachine;
use super::teach_cut::TeachCut;
use crate::estimation::estimator::Calibration;
use crate::plant::recording::{
    BenchRecording, BlockRow, OpenLoopRecording, OpenLoopRun, PhaseRecording, StepSummary,
};
use crate::plant::Preset;
use crate::signal::spectrum::{AmplitudeSpectrum, Window};
use crate::work::{Progress, Work};

/// A finished job's answer whose bulk is numbers: `arrays` travel as raw `f64`s, `json` holds the
/// rest.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Packed {
    /// What is not a long list of numbers, as JSON.
    pub json: String,
    /// The long lists of numbers, in the order the kind of answer defines.
    pub arrays: Vec<Vec<f64>>,
}

fn to_json(what: &str, value: &impl Serialize) -> Result<String, String> {
    serde_json::to_string(value).map_err(|e| format!("the {what} could not be sent: {e}"))
}

fn from_json<T: for<'de> Deserialize<'de>>(what: &str, json: &str) -> Result<T, String> {
    serde_json::from_str(json).map_err(|e| format!("the worker's {what} could not be read: {e}"))
}

/// `arrays` as exactly `N` lists, or why not.
fn arrays<const N: usize>(what: &str, arrays: Vec<Vec<f64>>) -> Result<[Vec<f64>; N], String> {
    let count = arrays.len();
    arrays
        .try_into()
        .map_err(|_| format!("the worker's {what} holds {count} lists of numbers, not {N}"))
}

/// Paper 000's bench recorded over a window of machine time ([`BenchRecording::new`]), answered
/// by its [`PhaseRecording`] ([`pack_phase_recording`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchRequest {
    /// The bench's seed.
    pub seed: u64,
    /// Where the window starts, s of machine time.
    pub from_s: f64,
    /// How long it is, s.
    pub duration_s: f64,
}

impl BenchRequest {
    /// The loaded step the Signal chain page shows ([`BenchRecording::loaded_step`]).
    pub fn loaded_step(seed: u64) -> Self {
        Self {
            seed,
            from_s: BenchRecording::LOADED_STEP_FROM_S,
            duration_s: BenchRecording::LOADED_STEP_FOR_S,
        }
    }

    /// The recording.
    pub fn into_work(self) -> Result<BenchRecording, String> {
        BenchRecording::new(self.seed, self.from_s, self.duration_s).map_err(|e| e.to_string())
    }
}

/// What of a [`PhaseRecording`] travels as JSON.
#[derive(Serialize, Deserialize)]
struct PhaseHeader {
    sample_rate_hz: f64,
    window: Window,
}

/// A bench recording to send: its times, phase currents, and the raw spectrum's bins and
/// amplitudes as four lists.
pub fn pack_phase_recording(recording: &PhaseRecording) -> Result<Packed, String> {
    let header = PhaseHeader {
        sample_rate_hz: recording.sample_rate_hz,
        window: recording.raw_spectrum.window,
    };
    Ok(Packed {
        json: to_json("bench recording", &header)?,
        arrays: vec![
            recording.time_s.clone(),
            recording.phases_a.clone(),
            recording.raw_spectrum.freq_hz.clone(),
            recording.raw_spectrum.amplitude.clone(),
        ],
    })
}

/// A bench recording read from a worker's answer.
pub fn unpack_phase_recording(packed: Packed) -> Result<PhaseRecording, String> {
    let header: PhaseHeader = from_json("bench recording", &packed.json)?;
    let [time_s, phases_a, freq_hz, amplitude] = arrays("bench recording", packed.arrays)?;
    if phases_a.len() != 3 * time_s.len() || freq_hz.len() != amplitude.len() {
        return Err(format!(
            "the worker's bench recording is ragged: {} times, {} phase currents, {} bins, {} amplitudes",
            time_s.len(),
            phases_a.len(),
            freq_hz.len(),
            amplitude.len()
        ));
    }
    Ok(PhaseRecording {
        sample_rate_hz: header.sample_rate_hz,
        time_s,
        phases_a,
        raw_spectrum: AmplitudeSpectrum {
            freq_hz,
            amplitude,
            window: header.window,
        },
    })
}

/// A preset's machine recorded open-loop at a fixed override ([`OpenLoopRun::new`]), answered by
/// its [`OpenLoopRecording`] ([`pack_open_loop_recording`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OpenLoopRequest {
    /// The preset.
    pub preset: Preset,
    /// Its machine's seed.
    pub seed: u64,
    /// The feed override, percent.
    pub override_pct: f64,
    /// Samples summarised per row.
    pub block_samples: usize,
    /// The most machine time recorded, s.
    pub max_duration_s: f64,
}

impl OpenLoopRequest {
    /// The recording.
    pub fn into_work(self) -> Result<OpenLoopRun, String> {
        OpenLoopRun::new(
            self.preset,
            self.seed,
            self.override_pct,
            self.block_samples,
            self.max_duration_s,
        )
        .map_err(|e| e.to_string())
    }
}

/// What of an [`OpenLoopRecording`] travels as JSON: all but its rows.
#[derive(Serialize, Deserialize)]
struct OpenLoopHeader {
    preset: Preset,
    load_steps: Vec<StepSummary>,
}

flat_row! {
    BlockRow;
    /// Numbers per row in an open-loop recording's list, in `BlockRow`'s order.
    BLOCK_VALUES,
    block_values,
    block_from;
    numbers:
        time_s,
        force_x_n,
        force_y_n,
        force_z_n,
        resultant_min_n,
        resultant_max_n,
        spindle_torque_nm,
        cutting_power_w,
        feed_iu_min_a,
        feed_iu_max_a,
        spindle_iu_min_a,
        spindle_iu_max_a,
        feed_rms_a,
        spindle_rms_a,
        depth_mm,
        feed_mm_min,
        spindle_rpm,
        brake_torque_nm,
}

/// An open-loop recording to send: its rows as one list of [`BLOCK_VALUES`] numbers each, the
/// preset and the load steps' summaries as JSON.
pub fn pack_open_loop_recording(recording: &OpenLoopRecording) -> Result<Packed, String> {
    let header = OpenLoopHeader {
        preset: recording.preset,
        load_steps: recording.load_steps.clone(),
    };
    let mut rows = Vec::with_capacity(recording.rows.len() * BLOCK_VALUES);
    for row in &recording.rows {
        rows.extend_from_slice(&block_values(row));
    }
    Ok(Packed {
        json: to_json("machine's recording", &header)?,
        arrays: vec![rows],
    })
}

/// An open-loop recording read from a worker's answer.
pub fn unpack_open_loop_recording(packed: Packed) -> Result<OpenLoopRecording, String> {
    let header: OpenLoopHeader = from_json("machine's recording", &packed.json)?;
    let [rows] = arrays("machine's recording", packed.arrays)?;
    if !rows.len().is_multiple_of(BLOCK_VALUES) {
        return Err(format!(
            "the worker's machine recording holds {} numbers, not a whole number of rows of {BLOCK_VALUES}",
            rows.len()
        ));
    }
    Ok(OpenLoopRecording {
        preset: header.preset,
        rows: rows.chunks_exact(BLOCK_VALUES).map(block_from).collect(),
        load_steps: header.load_steps,
    })
}

/// The teach cuts of a teach-in, one per scenario, answered by their calibrations in order
/// ([`pack_calibrations`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TeachCutsRequest {
    /// The scenarios.
    pub specs: Vec<RunSpec>,
}

impl TeachCutsRequest {
    /// The teach cuts.
    pub fn into_work(self) -> TeachCuts {
        TeachCuts {
            specs: self.specs,
            current: None,
            taught: Vec::new(),
        }
    }
}

/// The teach cuts of several scenarios on the simulated machine, one after another: the same
/// calibrations as [`super::lab::teach_cut_only`] gives each.
pub struct TeachCuts {
    specs: Vec<RunSpec>,
    current: Option<Box<OnMachine<TeachCut>>>,
    taught: Vec<Calibration>,
}

impl Work for TeachCuts {
    type Output = Vec<Calibration>;
    /// The message names the scenario whose teach cut failed.
    type Error = String;

    /// Advances the teach cut under way by at most `periods` control periods.
    fn advance(&mut self, periods: usize) -> Result<bool, String> {
        let Some(spec) = self.specs.get(self.taught.len()) else {
            return Ok(true);
        };
        let failed = |error: super::error::LoopError| format!("{}: {error}", spec.preset.name());
        let teach = match &mut self.current {
            Some(teach) => teach,
            None => self
                .current
                .insert(Box::new(teach_cut_work(spec).map_err(failed)?)),
        };
        if teach.advance(periods).map_err(failed)? {
            let calibration = teach.finish().map_err(failed)?;
            self.current = None;
            self.taught.push(calibration);
        }
        Ok(self.taught.len() >= self.specs.len())
    }

    fn progress(&self) -> Progress {
        let total = self.specs.len().max(1);
        let part = self.current.as_ref().map_or(0.0, |t| t.progress().fraction);
        Progress::new(
            format!(
                "Teach cut {} of {total}",
                (self.taught.len() + 1).min(total)
            ),
            (self.taught.len() as f64 + part) / total as f64,
        )
    }

    fn finish(&mut self) -> Result<Vec<Calibration>, String> {
        if self.taught.len() < self.specs.len() {
            return Err("the teach-in has not finished".into());
        }
        Ok(std::mem::take(&mut self.taught))
    }
}

/// Calibrations to send (small: JSON only).
pub fn pack_calibrations(calibrations: &[Calibration]) -> Result<Packed, String> {
    Ok(Packed {
        json: to_json("teach cuts' calibrations", &calibrations)?,
        arrays: Vec::new(),
    })
}

/// Calibrations read from a worker's answer, one per scenario of `expected`.
pub fn unpack_calibrations(packed: Packed, expected: usize) -> Result<Vec<Calibration>, String> {
    let calibrations: Vec<Calibration> = from_json("teach cuts' calibrations", &packed.json)?;
    if calibrations.len() != expected {
        return Err(format!(
            "the worker sent {} teach cuts for {expected} scenarios",
            calibrations.len()
        ));
    }
    Ok(calibrations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_loop::lab::teach_cut_only;
    use crate::closed_loop::transfer::JobRequest;
    use crate::control::registry::ControllerKind;

    /// `request` written and read as the page sends it to the worker.
    fn through_json(request: JobRequest) -> JobRequest {
        let json = request.to_json().unwrap();
        let back = JobRequest::from_json(&json).unwrap();
        assert_eq!(back, request, "{json}");
        back
    }

    #[test]
    fn a_bench_recording_made_in_a_worker_equals_the_pages_bit_for_bit() {
        // A shorter window than the page's loaded step, so the test stays quick.
        let request = BenchRequest {
            seed: 1,
            from_s: 2.0,
            duration_s: 0.5,
        };
        let JobRequest::Bench(request) = through_json(JobRequest::Bench(request)) else {
            panic!("read back as another job");
        };
        let on_page = BenchRecording::new(1, 2.0, 0.5)
            .unwrap()
            .run_to_end()
            .unwrap();
        let in_worker = request.into_work().unwrap().run_to_end().unwrap();
        let received = unpack_phase_recording(pack_phase_recording(&in_worker).unwrap()).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&received.phases_a), bits(&on_page.phases_a));
        assert_eq!(bits(&received.time_s), bits(&on_page.time_s));
        assert_eq!(
            bits(&received.raw_spectrum.amplitude),
            bits(&on_page.raw_spectrum.amplitude)
        );
        assert_eq!(format!("{received:?}"), format!("{on_page:?}"));
        assert_eq!(received.phases_a.len(), 15_000);
        assert_eq!(
            BenchRequest::loaded_step(1)
                .into_work()
                .unwrap()
                .progress()
                .stage,
            "Simulating the brake bench"
        );
    }

    #[test]
    fn a_ragged_or_short_bench_recording_is_refused() {
        let recording = BenchRecording::new(1, 0.0, 0.01)
            .unwrap()
            .run_to_end()
            .unwrap();
        let mut packed = pack_phase_recording(&recording).unwrap();
        packed.arrays[1].pop();
        assert!(unpack_phase_recording(packed.clone())
            .unwrap_err()
            .contains("ragged"));
        packed.arrays.pop();
        assert!(unpack_phase_recording(packed)
            .unwrap_err()
            .contains("3 lists of numbers, not 4"));
        assert!(BenchRequest {
            seed: 1,
            from_s: 0.0,
            duration_s: -1.0
        }
        .into_work()
        .is_err());
    }

    #[test]
    fn an_open_loop_recording_made_in_a_worker_equals_the_pages_bit_for_bit() {
        // The brake bench, whose recording has load steps with spectra, and a mill preset.
        for (preset, duration_s) in [(Preset::WangBrakeBench, 8.0), (Preset::ManeeratDoc1, 2.0)] {
            let request = OpenLoopRequest {
                preset,
                seed: 1,
                override_pct: 100.0,
                block_samples: 50,
                max_duration_s: duration_s,
            };
            let JobRequest::OpenLoop(request) = through_json(JobRequest::OpenLoop(request)) else {
                panic!("read back as another job");
            };
            let on_page = OpenLoopRun::new(preset, 1, 100.0, 50, duration_s)
                .unwrap()
                .run_to_end()
                .unwrap();
            let in_worker = request.into_work().unwrap().run_to_end().unwrap();
            let received =
                unpack_open_loop_recording(pack_open_loop_recording(&in_worker).unwrap()).unwrap();
            let bits = |r: &OpenLoopRecording| {
                r.rows
                    .iter()
                    .map(|row| block_values(row).map(f64::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&received), bits(&on_page));
            assert_eq!(format!("{received:?}"), format!("{on_page:?}"));
            assert!(!on_page.rows.is_empty());
        }
    }

    #[test]
    fn a_ragged_open_loop_recording_is_refused() {
        let recording = OpenLoopRun::new(Preset::ManeeratDoc1, 1, 100.0, 50, 0.1)
            .unwrap()
            .run_to_end()
            .unwrap();
        let mut packed = pack_open_loop_recording(&recording).unwrap();
        packed.arrays[0].pop();
        assert!(unpack_open_loop_recording(packed)
            .unwrap_err()
            .contains("whole number"));
    }

    #[test]
    fn teach_cuts_made_in_a_worker_equal_the_teach_cuts_alone() {
        let specs: Vec<RunSpec> = [Preset::ManeeratDoc1, Preset::KimStepDoc]
            .into_iter()
            .map(|p| RunSpec::new(p, ControllerKind::Threshold))
            .collect();
        let request = TeachCutsRequest {
            specs: specs.clone(),
        };
        let JobRequest::TeachCuts(request) = through_json(JobRequest::TeachCuts(request)) else {
            panic!("read back as another job");
        };
        let mut work = request.into_work();
        assert_eq!(work.progress().stage, "Teach cut 1 of 2");
        assert!(work.finish().is_err(), "not finished yet");
        let in_worker = work.run_to_end().unwrap();
        let received = unpack_calibrations(pack_calibrations(&in_worker).unwrap(), 2).unwrap();
        for (spec, calibration) in specs.iter().zip(&received) {
            let (_, alone) = teach_cut_only(spec).unwrap();
            // Debug: every number at full precision, NaN as NaN.
            assert_eq!(format!("{calibration:?}"), format!("{alone:?}"));
        }
        assert!(
            unpack_calibrations(pack_calibrations(&in_worker).unwrap(), 3)
                .unwrap_err()
                .contains("2 teach cuts for 3")
        );
    }
}
