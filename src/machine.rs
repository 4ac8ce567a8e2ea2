//! The boundary every closed loop talks through.
//!
//! A [`Machine`] takes the feed-override command of one sample period and returns what its sensors
//! read in that period. The simulated FANUC machine ([`crate::plant`]), a replayed CSV log
//! ([`crate::log::machine::LogMachine`]) and a real machine behind the serial protocol implement
//! it, so the signal chain, estimator, controllers and safety envelope above it stay one code path
//! in every mode.
//!
//! [`SensorSample`] holds only what a real installation can measure; what only a simulation knows
//! (the true force, the depth of cut) travels beside it in [`PlantTruth`], used for plots and
//! metrics, never by a controller.

use crate::truth_fields::TRUTH_VALUES;
use serde::Serialize;

/// What the adaptive controller asks of the machine for the next sample period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverrideCommand {
    /// Feed override in percent of the programmed feed, already limited and quantised by the
    /// safety envelope.
    pub override_pct: f64,
    /// Feed hold: the axes decelerate to a stop and stay there while it is set.
    pub feed_hold: bool,
}

impl Default for OverrideCommand {
    fn default() -> Self {
        Self {
            override_pct: 100.0,
            feed_hold: false,
        }
    }
}

/// One sample of what the machine's sensors and control report.
///
/// Non-finite values are possible (a broken sensor, a corrupt log line) and are the safety
/// envelope's to detect: nothing here is validated.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SensorSample {
    /// Time since the start of the run.
    pub time_s: f64,
    /// Feed-drive motor phase currents i_u, i_v, i_w as read through the Hall sensors and ADC.
    pub feed_phase_currents_a: [f64; 3],
    /// Spindle motor phase currents i_u, i_v, i_w.
    pub spindle_phase_currents_a: [f64; 3],
    /// The spindle's frequency-to-voltage converter output (paper 003), proportional to speed
    /// within each gear range.
    pub spindle_fv_voltage_v: f64,
    /// Spindle speed as the control reports it.
    pub spindle_speed_rpm: f64,
    /// Programmed spindle speed (the S word), which fixes the gear range.
    pub spindle_command_rpm: f64,
    /// Programmed feed of the current block, before override.
    pub programmed_feed_mm_min: f64,
    /// Actual path feed of the axes.
    pub feed_mm_min: f64,
    /// The override the machine is applying now (after its own quantisation).
    pub applied_override_pct: f64,
    /// Whether the spindle is turning.
    pub spindle_running: bool,
    /// Time since the spindle last started, for the arming delay.
    pub time_since_spindle_start_s: f64,
}

/// What only a simulation knows: the ground truth for plots and metrics.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PlantTruth {
    /// Cutting force components on the tool in the machine frame.
    pub force_x_n: f64,
    /// Cutting force, y component.
    pub force_y_n: f64,
    /// Cutting force, z (axial) component.
    pub force_z_n: f64,
    /// Magnitude of the cutting force in the x-y plane, the quantity the controllers regulate.
    pub force_resultant_n: f64,
    /// Feed-direction component of the cutting force (paper 000's F_c).
    pub feed_force_n: f64,
    /// Cutting torque on the spindle.
    pub spindle_torque_nm: f64,
    /// Cutting power.
    pub cutting_power_w: f64,
    /// Axial depth of cut at the tool.
    pub depth_mm: f64,
    /// Radial width of cut at the tool.
    pub width_mm: f64,
    /// Feed per tooth actually cut.
    pub feed_per_tooth_mm: f64,
    /// Distance travelled along the programmed path.
    pub path_position_mm: f64,
    /// Material removal rate.
    pub material_removal_mm3_s: f64,
    /// Tool position x in the program's coordinates (for drawing the tool on the path).
    pub tool_x_mm: f64,
    /// Tool position y.
    pub tool_y_mm: f64,
    /// True RMS current of the measured feed axis, before the sensors (eq 7 of paper 003 over
    /// its three phases).
    pub feed_current_rms_a: f64,
    /// True RMS spindle current, before the sensors.
    pub spindle_current_rms_a: f64,
}

/// A simulation's truth as [`crate::protocol::frame::SimTruth`] carries it, at full precision:
/// what a device averages over a block and a host interpolates between samples, in the wire order
/// ([`crate::truth_fields::in_wire_order`]).
macro_rules! plant_truth_in_wire_order {
    ($($field:ident,)*) => {
        impl PlantTruth {
            /// The values in wire order.
            pub fn wire_values(&self) -> [f64; TRUTH_VALUES] {
                [$(self.$field),*]
            }

            /// The truth from the values in wire order.
            pub fn from_wire_values(values: [f64; TRUTH_VALUES]) -> Self {
                let [$($field),*] = values;
                Self { $($field),* }
            }
        }
    };
}
crate::truth_fields::in_wire_order!(plant_truth_in_wire_order);

/// A sensorless force estimate from the programmed cutting conditions (paper 004's power law)
/// and how far to trust it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorlessEstimate {
    /// The estimated cutting force.
    pub force_n: f64,
    /// Its relative uncertainty (1 = ±100 %) from the model's form alone: zero at the cut it was
    /// calibrated on, growing as the conditions move away from it.
    pub relative_uncertainty: f64,
}

/// A dynamometer's reading of the cutting force on the tool, in the machine frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DynamometerReading {
    /// Force along x.
    pub force_x_n: f64,
    /// Force along y.
    pub force_y_n: f64,
    /// Component along the feed direction (the force the feed drive pushes against).
    pub feed_force_n: f64,
}

/// One step's result.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MachineStep {
    /// What the sensors read.
    pub sensors: SensorSample,
    /// Ground truth, if the machine is simulated.
    pub truth: Option<PlantTruth>,
}

/// One sample of a block stepped by [`Machine::step_block`]: the step and the dynamometer's
/// reading at it, if the machine has one.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BlockStep {
    /// What [`Machine::step`] returned.
    pub step: MachineStep,
    /// What [`Machine::dynamometer_force_n`] said right after.
    pub dynamometer: Option<DynamometerReading>,
}

/// A machine the closed loop can drive, one sensor sample period at a time.
///
/// Object-safe so the lab can switch between simulation, replay and hardware at run time.
pub trait Machine {
    /// The sensor sample rate.
    fn sample_rate_hz(&self) -> f64;

    /// Applies `command` for one sample period and returns the sensors' reading at its end.
    fn step(&mut self, command: OverrideCommand) -> MachineStep;

    /// True once the program (or log) has ended; `step` after that keeps returning the last state.
    fn finished(&self) -> bool;

    /// A sensorless estimate of the cutting force at the latest sample from the programmed cutting
    /// conditions (paper 004's power law), if the machine knows them. The closed loop shows it
    /// beside the current-based estimate and flags when they disagree.
    fn sensorless_force(&self) -> Option<SensorlessEstimate> {
        None
    }

    /// A force sensor's reading at the latest sample, if the machine has one (a dynamometer under
    /// the part, or a log's force columns). A teach cut can calibrate against it
    /// ([`crate::closed_loop::teach_cut::TeachForce::Dynamometer`]).
    fn dynamometer_force_n(&self) -> Option<DynamometerReading> {
        None
    }

    /// Steps up to `out.len()` samples under `command`, writing each step and dynamometer
    /// reading: exactly [`Machine::step`] then [`Machine::dynamometer_force_n`], sample after
    /// sample, stopping after the sample at which [`Machine::finished`] turns true (a finished
    /// machine still gives one sample, its last, as `step` does). Returns how many were written
    /// (at least one unless `out` is empty).
    ///
    /// The closed loop steps a control period's samples through this: one call per block instead
    /// of a dynamic call per sample, and, compiled for a concrete machine (this default is
    /// generated for each implementation), a loop the compiler can inline the step into.
    fn step_block(&mut self, command: OverrideCommand, out: &mut [BlockStep]) -> usize {
        for (i, slot) in out.iter_mut().enumerate() {
            slot.step = self.step(command);
            slot.dynamometer = self.dynamometer_force_n();
            if self.finished() {
                return i + 1;
            }
        }
        out.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::frame::SimTruth;

    #[test]
    fn the_truth_s_wire_values_are_in_sim_truth_s_order_and_read_back() {
        let values: [f64; TRUTH_VALUES] = std::array::from_fn(|i| i as f64 + 0.5);
        let truth = PlantTruth::from_wire_values(values);
        assert_eq!(truth.wire_values(), values);
        // Each value is the field the protocol names at its place.
        let fields = serde_json::to_value(truth).unwrap();
        for (name, value) in SimTruth::NAMES.iter().zip(values) {
            assert_eq!(fields[*name].as_f64(), Some(value), "{name}");
        }
    }
}
