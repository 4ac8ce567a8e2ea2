//! The closed loop as a real machine drives it: samples pushed one at a time give the trace the
//! simulation's pull path gives, and a teach cut calibrates from a dynamometer or from the model of
//! the cut, without the simulation's truth.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::closed_loop::lab::{simulate, LabRun, RunMachines, RunSpec};
use cutlab::closed_loop::runner::{
    FeedbackLoop, LoopSample, OnMachine, SampleLoop, TeachCut, TeachForce,
};
use cutlab::control::registry::{ControllerKind, RunContext};
use cutlab::estimation::cut_forces::CutGeometry;
use cutlab::machine::{DynamometerReading, Machine, MachineStep, OverrideCommand};
use cutlab::plant::Preset;
use cutlab::work::Work;

#[test]
fn pushed_samples_give_the_trace_of_the_pulled_loop() {
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let pulled = simulate(&spec).unwrap();

    // The samples arrive as a serial line would deliver them: the loop never sees the machine.
    let mut machine = spec.preset.machine(spec.seed).unwrap();
    let controller = spec
        .controller
        .build(&RunContext {
            target_force_n: pulled.settings.target_force_n,
            control_period_s: pulled.settings.control_period_s,
        })
        .unwrap();
    let mut pushed = FeedbackLoop::new(
        machine.sample_rate_hz(),
        controller,
        pulled.calibration.estimator.clone(),
        pulled.settings.clone(),
    )
    .unwrap();
    let mut command = pushed.command();
    let mut commands = 0;
    while !pushed.finished() {
        let step = machine.step(command);
        let sample = LoopSample {
            step: &step,
            sensorless_force_n: machine.sensorless_force_n(),
            dynamometer: None,
        };
        if let Some(next) = pushed.push(&sample) {
            command = next;
            commands += 1;
            if machine.finished() {
                pushed.end_of_program();
            }
        }
    }
    let trace = pushed.finish().unwrap();
    assert_eq!(commands, trace.rows.len());
    assert_eq!(trace, pulled.trace);
}

/// A machine with a force sensor: the preset's simulation, its truth read by a dynamometer.
struct WithDynamometer {
    machine: Box<dyn Machine>,
    last: MachineStep,
}

impl Machine for WithDynamometer {
    fn sample_rate_hz(&self) -> f64 {
        self.machine.sample_rate_hz()
    }
    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        self.last = self.machine.step(command);
        // What a real machine reports: sensors only.
        MachineStep {
            truth: None,
            ..self.last
        }
    }
    fn finished(&self) -> bool {
        self.machine.finished()
    }
    fn dynamometer_force_n(&self) -> Option<DynamometerReading> {
        self.last.truth.map(|t| DynamometerReading {
            force_x_n: t.force_x_n,
            force_y_n: t.force_y_n,
            feed_force_n: t.feed_force_n,
        })
    }
}

fn teach(machine: Box<dyn Machine>, force: TeachForce) -> OnMachine<TeachCut> {
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let settings = cutlab::closed_loop::lab::default_settings(&spec).unwrap();
    let mut teach = OnMachine::teach_cut(machine, &settings, force).unwrap();
    while !teach.advance(1000).unwrap() {}
    teach
}

#[test]
fn a_dynamometer_teach_cut_calibrates_as_the_truth_does_without_any_truth() {
    let preset = Preset::ManeeratDoc1;
    let truth = teach(
        Box::new(preset.machine(7).unwrap()),
        TeachForce::SimulationTruth,
    );
    let sensed = teach(
        Box::new(WithDynamometer {
            machine: Box::new(preset.machine(7).unwrap()),
            last: MachineStep::default(),
        }),
        TeachForce::Dynamometer,
    );
    let (a, b) = (truth.calibration().unwrap(), sensed.calibration().unwrap());
    // Debug text, since an unused gear range's NaN never equals itself.
    assert_eq!(format!("{:?}", a.estimator), format!("{:?}", b.estimator));
    assert_eq!(a.periods, b.periods);

    // Without truth, the truth source has nothing to fit.
    let blind = teach(
        Box::new(WithDynamometer {
            machine: Box::new(preset.machine(7).unwrap()),
            last: MachineStep::default(),
        }),
        TeachForce::SimulationTruth,
    );
    assert!(blind.calibration().is_err());
}

#[test]
fn a_teach_cut_on_the_model_of_the_cut_holds_the_target_on_a_machine_without_truth() {
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let scenario = spec.preset.scenario_spec().unwrap();
    let depth_mm = scenario.depth_mm[0].1;
    let width_mm = scenario.width_mm[0].1;
    let geometry = CutGeometry {
        cutter: scenario.cutter,
        mode: scenario.mode,
        coefficients: scenario.materials[0].material.coefficients(),
    };
    let truthless = |seed: u64| -> Box<dyn Machine> {
        Box::new(WithDynamometer {
            machine: Box::new(spec.preset.machine(seed).unwrap()),
            last: MachineStep::default(),
        })
    };
    // One machine does the teach cut and then the run, as a real one does.
    let run = LabRun::on_machines(
        &spec,
        RunMachines::Shared(truthless(1)),
        TeachForce::CutModel {
            geometry,
            depth_mm,
            width_mm,
        },
    )
    .unwrap()
    .run_to_end()
    .unwrap();
    let reference = simulate(&spec).unwrap();
    // The model of the cut is the plant's mechanistic model without runout: the calibrated
    // estimator agrees with the truth-taught one to a few percent.
    let estimate = |r: &cutlab::closed_loop::lab::RunResult, current_a: f64| {
        let row = &r.trace.rows[r.trace.rows.len() / 2];
        r.calibration.estimator.force_for_current_n(
            current_a,
            row.spindle_speed_rpm,
            row.feed_mm_min,
        )
    };
    let mid = &reference.trace.rows[reference.trace.rows.len() / 2];
    let (modelled, taught) = (
        estimate(&run, mid.spindle_current_rms_a),
        estimate(&reference, mid.spindle_current_rms_a),
    );
    assert!(
        (modelled - taught).abs() < 0.1 * taught,
        "cut model {modelled} N vs truth {taught} N"
    );
    // The run itself: no truth in its trace, and the loop still ran to the program's end.
    assert!(run.trace.completed);
    assert!(run.trace.rows.iter().all(|r| r.force_n.is_nan()));
}
