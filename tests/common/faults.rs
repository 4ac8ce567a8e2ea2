//! A sensor fault injected into a preset's run machine, and the runs paper 004's sensor failure
//! prediction is judged on: tests/sensor_failure.rs asserts them, tests/docs.rs states them.
// Each test binary uses a different subset of these helpers.
#![allow(dead_code)]

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::{LabRun, RunMachines, RunResult};
use cutlab::closed_loop::teach_cut::TeachForce;
use cutlab::machine::{
    DynamometerReading, Machine, MachineStep, OverrideCommand, SensorlessEstimate,
};
use cutlab::plant::scenario::Scenario;
use cutlab::plant::simulator::Simulator;
use cutlab::work::Work;

/// When the injected fault starts, s of machine time: in kim-step-doc's first depth section,
/// after the loop has armed.
pub const FAULT_AT_S: f64 = 20.0;

/// The spindle Hall sensors' gain after the fault: 40 % low (a drifting burden resistor or a
/// failing transducer), which no plausibility check of the envelope sees.
pub const FAULTY_GAIN: f64 = 0.6;

/// A machine whose spindle current sensors read `gain` of the current from `from_s` on.
pub struct DriftingSpindleSensor {
    /// The healthy machine.
    pub machine: Box<dyn Machine>,
    /// When the gain changes, s of machine time.
    pub from_s: f64,
    /// The gain from then on.
    pub gain: f64,
}

impl Machine for DriftingSpindleSensor {
    fn sample_rate_hz(&self) -> f64 {
        self.machine.sample_rate_hz()
    }

    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        let mut step = self.machine.step(command);
        if step.sensors.time_s >= self.from_s {
            for phase in &mut step.sensors.spindle_phase_currents_a {
                *phase *= self.gain;
            }
        }
        step
    }

    fn finished(&self) -> bool {
        self.machine.finished()
    }

    fn sensorless_force(&self) -> Option<SensorlessEstimate> {
        self.machine.sensorless_force()
    }

    fn dynamometer_force_n(&self) -> Option<DynamometerReading> {
        self.machine.dynamometer_force_n()
    }
}

/// `spec` run with its closed loop on the machine `wrap` makes of the preset's run machine (the
/// teach cut on the preset's own).
pub fn run_on(
    spec: &RunSpec,
    wrap: impl FnOnce(Box<dyn Machine>) -> Box<dyn Machine>,
) -> RunResult {
    let RunMachines::Separate { teach, run } = RunMachines::for_preset(spec).unwrap() else {
        panic!("a simulated preset has separate teach and run machines");
    };
    let machines = RunMachines::Separate {
        teach,
        run: wrap(run),
    };
    LabRun::on_machines(spec, machines, TeachForce::SimulationTruth)
        .unwrap()
        .run_to_end()
        .unwrap()
}

/// The run machine kim-step-doc's `spec` would run on, estimating with paper 004's published
/// weights (calibrated on the program's nominal cut) instead of the learned network.
pub fn published_run_machine(spec: &RunSpec) -> Box<dyn Machine> {
    let scenario = Scenario::new(spec.preset.scenario_spec().unwrap()).unwrap();
    Box::new(Simulator::new(scenario, spec.preset.sim_config(spec.seed)).unwrap())
}

/// How long after [`FAULT_AT_S`] the first period predicts a sensor failure, s (`None`: never).
pub fn prediction_delay_s(result: &RunResult) -> Option<f64> {
    result
        .trace
        .rows
        .iter()
        .find(|r| r.time_s >= FAULT_AT_S && r.sensor_failure_predicted)
        .map(|r| r.time_s - FAULT_AT_S)
}
