//! The simulated mill: scenario → CNC → cutting → drives → sensors, one sample per step.
//!
//! Each [`Machine::step`](crate::machine::Machine::step) (Δt = 1/sample rate, 10 kHz by default):
//!
//! 1. the PMC latches the override and feed hold ([`super::cnc::OverrideInput`]);
//! 2. the CNC advances the commanded and actual path position ([`super::cnc::FeedPlanner`]),
//!    holding motion until the spindle has reached speed;
//! 3. the scenario gives the tool's position, direction α, depth, width and material there;
//! 4. feed per tooth s_t = v/(Z·n) (at the tool centre: no curvature correction on arcs); the
//!    mechanistic model gives the forces at the tooth angle φ = θ_spindle + α in the feed frame
//!    ([`super::mechanics`]), rotated into the machine frame;
//! 5. each feed axis carries the force component along it (paper 000 eq 3) and turns it into
//!    phase currents ([`super::feed_drive`]); the spindle turns the cutting torque into its RMS
//!    and phase currents ([`super::spindle_drive`]);
//! 6. Hall sensors and the ADC read one feed axis and the spindle ([`super::sensors`]).
//!
//! Nothing in `step` allocates. Its only inputs are the override command and the seed, so two
//! runs with the same seed and commands are bit-identical (natively and in wasm: all
//! transcendental functions come from [`crate::math`]).
//!
//! The run ends when the program has ended and the axes are in position, or after
//! [`SimConfig::max_duration_s`]; `step` then keeps returning the last sample.
//!
//! A NaN override keeps the override applied last and ±∞ clamps (see [`super::cnc`]); nothing
//! else non-finite can reach a validated simulator, so its outputs stay finite.

use serde::{Deserialize, Serialize};

use super::cnc::{samples_per, AppliedOverride, CncConfig, Control, Every};
use super::feed_drive::{three_phase_rms_a, FeedDrive, FeedDriveConfig, PhasePoint};
use super::materials::{CuttingCoefficients, Material};
use super::mechanics::{mean_forces, Immersion, MillingForceModel, MillingMode};
use super::power_law::{
    CachedPowerLaw, PowerLawInputs, PowerLawMaterial, PowerLawModel, PowerLawReading,
};
use super::scenario::Scenario;
use super::sensorless::SensorlessNetwork;
use super::sensors::{CurrentSensor, CurrentSensorConfig};
use super::signals::{AxisSignals, PlantSignals};
use super::spindle_drive::{SpindleDrive, SpindleDriveConfig};
use super::{positive, Plant, PlantError, PlantModel, PlantSample, Sampling, Tick};
use crate::machine::{
    BlockStep, MachineStep, OverrideCommand, PlantTruth, SensorSample, SensorlessEstimate,
};
use crate::math;

/// Which feed axis the feed-current sensors are on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FeedAxis {
    /// The X axis.
    X,
    /// The Y axis.
    Y,
}

/// Everything about the simulated machine except the scenario.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimConfig {
    /// Sensor sample rate; the simulation steps at Δt = 1/rate. Default 10 kHz.
    pub sample_rate_hz: f64,
    /// Seed of every noise source.
    pub seed: u64,
    /// The control.
    pub cnc: CncConfig,
    /// Both feed axes (the same drive on X and Y).
    pub feed_drive: FeedDriveConfig,
    /// The spindle drive.
    pub spindle_drive: SpindleDriveConfig,
    /// The feed-current channel.
    pub feed_sensor: CurrentSensorConfig,
    /// The spindle-current channel.
    pub spindle_sensor: CurrentSensorConfig,
    /// The axis the feed sensors measure. Default X.
    pub measured_axis: FeedAxis,
    /// The run ends after this long even if the program has not (e.g. with 0 % override).
    /// Default 600 s.
    pub max_duration_s: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            sample_rate_hz: 10_000.0,
            seed: 0,
            cnc: CncConfig::default(),
            feed_drive: FeedDriveConfig::default(),
            spindle_drive: SpindleDriveConfig::default(),
            feed_sensor: CurrentSensorConfig::feed(),
            spindle_sensor: CurrentSensorConfig::spindle(),
            measured_axis: FeedAxis::X,
            max_duration_s: 600.0,
        }
    }
}

impl FeedAxis {
    /// Both axes.
    pub const ALL: [FeedAxis; 2] = [FeedAxis::X, FeedAxis::Y];

    /// Label for forms.
    pub fn label(self) -> &'static str {
        match self {
            FeedAxis::X => "X axis",
            FeedAxis::Y => "Y axis",
        }
    }
}

impl SimConfig {
    /// The default machine with another seed.
    ///
    /// ```
    /// use cutlab::plant::simulator::SimConfig;
    /// let c = SimConfig::with_seed(7);
    /// assert_eq!((c.seed, c.sample_rate_hz), (7, 10_000.0));
    /// assert!(c.validate().is_ok());
    /// ```
    pub fn with_seed(seed: u64) -> Self {
        Self {
            seed,
            ..Self::default()
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("sample_rate_hz", self.sample_rate_hz)?;
        if self.sample_rate_hz > 1e6 {
            return Err(PlantError::new(
                "sample_rate_hz",
                format!("must be at most 1 MHz, got {}", self.sample_rate_hz),
            ));
        }
        self.cnc.validate().map_err(|e| e.within("cnc"))?;
        self.feed_drive
            .validate()
            .map_err(|e| e.within("feed_drive"))?;
        self.spindle_drive
            .validate()
            .map_err(|e| e.within("spindle_drive"))?;
        self.feed_sensor
            .validate()
            .map_err(|e| e.within("feed_sensor"))?;
        self.spindle_sensor
            .validate()
            .map_err(|e| e.within("spindle_sensor"))?;
        positive("max_duration_s", self.max_duration_s)?;
        Ok(())
    }
}

/// What the phase currents of one sample are made from: the measured feed axis's and the
/// spindle's amplitude and angle.
#[derive(Debug, Clone, Copy, Default)]
struct PhasePoints {
    feed: PhasePoint,
    spindle: PhasePoint,
}

/// One sample's phase currents (the measured feed axis's and the spindle's) and what the
/// sensors read of them.
#[derive(Debug, Clone, Copy)]
struct SampleCurrents {
    feed_a: [f64; 3],
    spindle_a: [f64; 3],
    feed_read_a: [f64; 3],
    spindle_read_a: [f64; 3],
}

impl SampleCurrents {
    /// Not worked out yet: [`Simulator::read_currents`] fills them in after a block's physics.
    const LATER: Self = Self {
        feed_a: [f64::NAN; 3],
        spindle_a: [f64::NAN; 3],
        feed_read_a: [f64::NAN; 3],
        spindle_read_a: [f64::NAN; 3],
    };
}

/// Whether a block's phase currents and sensor readings are worked out together after its
/// physics ([`PlantModel::advance_block`]), or each sample's with its physics. They feed
/// nothing back, so the bits are the same either way; natively the block stages take 6–10 %
/// less time, in the browser's worker (wasm under V8) 4–9 % more (docs/benchmarks.md,
/// "The block stages at opt-level 3"), so wasm reads sample by sample.
const READ_AFTER_PHYSICS: bool = !cfg!(target_arch = "wasm32");

/// Samples whose phase currents and sensor readings are worked out together: a closed loop's
/// block (64 samples, [`crate::closed_loop::sample_loop`]) fits in one.
const CHUNK: usize = 64;

/// Noise streams: the feed sensor uses 0–2, the spindle sensor 3–5.
const FEED_SENSOR_STREAM: u64 = 0;
const SPINDLE_SENSOR_STREAM: u64 = 3;

/// A feed per tooth above this is a crash, not a cut; the model clamps to it.
const MAX_FEED_PER_TOOTH_MM: f64 = 1.0;

/// Below this spindle speed the tool is not cutting.
const MIN_CUTTING_RPM: f64 = 1.0;

/// The published weights paper 004 gives for a cutlab material: cast iron's for GC30, carbon
/// steel's for the rest (the paper has no others).
pub fn power_law_material(material: Material) -> PowerLawMaterial {
    match material {
        Material::Gc30 => PowerLawMaterial::CastIron,
        _ => PowerLawMaterial::CarbonSteel,
    }
}

/// The cut paper 004's power law is calibrated on for `material` in `scenario` — the first
/// block's feed per tooth at its spindle speed, the largest depth and width — and the mechanistic
/// mean resultant force there (`material`'s coefficients, [`mean_forces`]).
///
/// ```
/// use cutlab::plant::materials::Material;
/// use cutlab::plant::simulator::power_law_calibration_cut;
/// use cutlab::plant::Preset;
/// let scenario = Preset::KimStepDoc.scenario().unwrap();
/// let (cut, mechanistic_n) = power_law_calibration_cut(&scenario, Material::Sm45c);
/// assert_eq!((cut.axial_depth_mm, cut.feed_per_tooth_mm, cut.cutter_teeth), (5.0, 0.1, 2.0));
/// assert!((mechanistic_n - 744.0).abs() < 0.5); // a Ø20 mm slot, 5 mm deep, in SM45C
/// ```
pub fn power_law_calibration_cut(scenario: &Scenario, material: Material) -> (PowerLawInputs, f64) {
    let cutter = scenario.cutter();
    let first = &scenario.segments()[0];
    let feed_per_tooth_mm = if first.spindle_rpm > 0.0 {
        first.feed_mm_min / (f64::from(cutter.teeth) * first.spindle_rpm)
    } else {
        0.0
    };
    let depth_mm = scenario.depth_profile().max_value();
    let immersion = Immersion::new(
        scenario.mode(),
        scenario.width_profile().max_value(),
        cutter.diameter_mm,
    );
    let inputs = PowerLawInputs {
        radial_width_mm: immersion.radial_width_mm(cutter.diameter_mm),
        feed_per_tooth_mm,
        axial_depth_mm: depth_mm,
        diameter_mm: cutter.diameter_mm,
        teeth_engaged: immersion.teeth_engaged(cutter.teeth),
        cutter_teeth: f64::from(cutter.teeth),
    };
    let mean = mean_forces(
        cutter,
        &material.coefficients(),
        &immersion,
        depth_mm,
        feed_per_tooth_mm,
    );
    (inputs, mean.resultant_n())
}

/// Paper 004's model for `material` ([`power_law_material`], read as
/// [`PowerLawReading::USED`]), its bias calibrated to the mechanistic mean resultant of the
/// scenario's nominal cut ([`power_law_calibration_cut`]).
fn calibrated_power_law(
    scenario: &Scenario,
    material: Material,
) -> (PowerLawModel, PowerLawInputs) {
    let published = PowerLawModel::published(power_law_material(material), PowerLawReading::USED);
    let (inputs, mechanistic_n) = power_law_calibration_cut(scenario, material);
    // A scenario without a nominal cut (no depth, no feed) keeps the published biases.
    let model = published
        .calibrated(&inputs, mechanistic_n)
        .unwrap_or(published);
    (model, inputs)
}

/// The simulated mill.
///
/// ```
/// use cutlab::machine::{Machine, OverrideCommand};
/// use cutlab::plant::{Preset, Plant};
/// let mut sim = Preset::KimStepDoc.simulator(1).unwrap();
/// let mut last = sim.step(OverrideCommand::default());
/// for _ in 0..20_000 { last = sim.step(OverrideCommand::default()); } // 2 s
/// assert!(last.sensors.spindle_running);
/// assert!((sim.signals().spindle_speed_rpm - 1000.0).abs() < 20.0);
/// ```
#[derive(Debug, Clone)]
pub struct Simulator {
    scenario: Scenario,
    config: SimConfig,
    sampling: Sampling,
    ipo: Every,
    control: Control,
    force_model: MillingForceModel,
    region_coefficients: Vec<CuttingCoefficients>,
    /// Each material region's power law and the cut it was calibrated on: the sensorless
    /// estimate of a machine without a learned network.
    region_power_law: Vec<CachedPowerLaw>,
    /// The network learned on this machine's trial cuts ([`super::sensorless`]): when there is
    /// one, the sensorless estimate is its prediction.
    sensorless_network: Option<SensorlessNetwork>,
    spindle: SpindleDrive,
    axes: [FeedDrive; 2],
    feed_sensor: CurrentSensor,
    spindle_sensor: CurrentSensor,
    segment_hint: usize,
    profile_hints: ProfileHints,
    immersion_width_mm: f64,
    immersion: Immersion,
    spindle_arrived_at_s: Option<f64>,
    spindle_started_at_s: Option<f64>,
    power_law_force_n: f64,
    power_law_uncertainty: f64,
    /// The CNC's block at the latest sample (0 before the first).
    cnc_block: usize,
}

/// Where the last sample found the tool in the scenario's profiles and material regions: the
/// next search starts there.
#[derive(Debug, Clone, Copy, Default)]
struct ProfileHints {
    region: usize,
    depth: usize,
    width: usize,
}

impl Simulator {
    /// A machine at rest at the start of `scenario`.
    pub fn new(scenario: Scenario, config: SimConfig) -> Result<Self, PlantError> {
        config.validate()?;
        let sampling = Sampling::new(config.sample_rate_hz);
        let dt_s = sampling.dt_s();
        let blocks = scenario.plan_blocks();
        let force_model = MillingForceModel::new(*scenario.cutter())?;
        let region_coefficients = scenario
            .material_regions()
            .iter()
            .map(|r| r.material.coefficients())
            .collect();
        let region_power_law = scenario
            .material_regions()
            .iter()
            .map(|r| {
                let (model, inputs) = calibrated_power_law(&scenario, r.material);
                CachedPowerLaw::new(model, inputs)
            })
            .collect();
        let axis = FeedDrive::new(config.feed_drive, dt_s).map_err(|e| e.within("feed_drive"))?;
        let mut sim = Self {
            sampling,
            ipo: Every::new(samples_per(config.cnc.interpolation_period_s, dt_s)),
            control: Control::new(&config.cnc, blocks, dt_s).map_err(|e| e.within("cnc"))?,
            force_model,
            region_coefficients,
            region_power_law,
            sensorless_network: None,
            spindle: SpindleDrive::new(config.spindle_drive, dt_s)
                .map_err(|e| e.within("spindle_drive"))?,
            axes: [axis, axis],
            feed_sensor: CurrentSensor::new(
                config.feed_sensor,
                dt_s,
                config.seed,
                FEED_SENSOR_STREAM,
            )
            .map_err(|e| e.within("feed_sensor"))?,
            spindle_sensor: CurrentSensor::new(
                config.spindle_sensor,
                dt_s,
                config.seed,
                SPINDLE_SENSOR_STREAM,
            )
            .map_err(|e| e.within("spindle_sensor"))?,
            immersion: Immersion::new(MillingMode::Slot, 0.0, 1.0),
            immersion_width_mm: f64::NAN,
            scenario,
            config,
            segment_hint: 0,
            profile_hints: ProfileHints::default(),
            spindle_arrived_at_s: None,
            spindle_started_at_s: None,
            power_law_force_n: 0.0,
            power_law_uncertainty: 0.0,
            cnc_block: 0,
        };
        sim.reset();
        Ok(sim)
    }

    /// The same machine estimating its sensorless force with `network`, learned on its trial
    /// cuts, instead of paper 004's published weights.
    pub fn with_sensorless_network(mut self, network: SensorlessNetwork) -> Self {
        self.sensorless_network = Some(network);
        self
    }

    /// The scenario being cut.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The machine's configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    #[inline(always)]
    fn spindle_ready(&mut self, time_s: f64, command_rpm: f64) -> bool {
        if command_rpm == 0.0 {
            return true;
        }
        let tol = self.config.cnc.spindle_arrival_tolerance * command_rpm.abs();
        let speed = self.spindle.speed_rpm();
        let gear_ok = self.config.spindle_drive.gear_for(command_rpm)
            == self
                .config
                .spindle_drive
                .gear_for(speed.max(f64::MIN_POSITIVE));
        let at_speed = (speed - command_rpm).abs() <= tol && gear_ok;
        if at_speed && self.spindle_arrived_at_s.is_none() {
            self.spindle_arrived_at_s = Some(time_s);
        }
        at_speed
            && self
                .spindle_arrived_at_s
                .is_some_and(|t| time_s - t >= self.scenario.spec().spindle_start_dwell_s)
    }

    #[inline(always)]
    fn planner_block(&self) -> usize {
        self.cnc_block
            .min(self.scenario.segments().len().saturating_sub(1))
    }

    /// One sample. With `read_now` false, only its physics: the phase currents of the measured
    /// feed axis and the spindle and what the sensors read of them are left NaN (with the RMS
    /// of the measured feed currents in the truth), for [`Simulator::read_currents`] to work out
    /// from the phase points returned beside the sample. With `keep` false (a sample inside a
    /// block, whose internal signals nobody reads), the unmeasured axis's phase currents, seen
    /// only in the signals, are left out unless the run ends here.
    #[inline(always)]
    fn physics(
        &mut self,
        tick: Tick,
        command: OverrideCommand,
        keep: bool,
        read_now: bool,
    ) -> (PlantSample, PhasePoints) {
        let time_s = tick.time_s;
        let ipo_tick = self.ipo.tick();

        // 1–2. Override through the PMC, then the CNC.
        let block = self.planner_block();
        let spindle_command_rpm = self.scenario.segments()[block].spindle_rpm;
        let ready = self.spindle_ready(time_s, spindle_command_rpm);
        let control = self.control.step(command, ready);
        let (applied, cnc) = (control.applied, control.cnc);
        self.cnc_block = cnc.block;

        // 3. Where the tool is and what it meets.
        let s = cnc.position_mm;
        let point = self.scenario.point_from_hint(s, self.segment_hint);
        self.segment_hint = point.segment;
        let hints = &mut self.profile_hints;
        let region = self.scenario.region_index_from_hint(s, &mut hints.region);
        let depth_mm = self
            .scenario
            .depth_profile()
            .value_from_hint(s, &mut hints.depth);
        let width_profile_mm = self
            .scenario
            .width_profile()
            .value_from_hint(s, &mut hints.width);
        if width_profile_mm != self.immersion_width_mm {
            self.immersion_width_mm = width_profile_mm;
            self.immersion = Immersion::new(
                self.scenario.mode(),
                width_profile_mm,
                self.scenario.cutter().diameter_mm,
            );
        }
        let cutter = *self.scenario.cutter();
        let width_mm = self.immersion.radial_width_mm(cutter.diameter_mm);

        // 4. Cutting forces at the current tooth angle, feed frame then machine frame.
        let spindle_rpm = self.spindle.speed_rpm();
        let feed_mm_min = cnc.feed_mm_min;
        let cutting = region.is_some() && spindle_rpm.abs() >= MIN_CUTTING_RPM && depth_mm > 0.0;
        let feed_per_tooth_mm = if cutting {
            math::min(
                math::max(feed_mm_min, 0.0) / (f64::from(cutter.teeth) * spindle_rpm.abs()),
                MAX_FEED_PER_TOOTH_MM,
            )
        } else {
            0.0
        };
        let (cos_a, sin_a) = (point.direction_cos, point.direction_sin);
        let forces = match region {
            Some(r) if cutting => {
                // The tool's angle φ = θ_spindle + α, its cosine and sine by the addition
                // theorem from the spindle's phasor and the path's direction.
                let spindle = self.spindle.angle();
                let (cs, ss) = (spindle.cos(), spindle.sin());
                self.force_model.forces_at(
                    &self.region_coefficients[r],
                    &self.immersion,
                    depth_mm,
                    feed_per_tooth_mm,
                    spindle.angle_rad() + point.direction_rad,
                    cs * cos_a - ss * sin_a,
                    ss * cos_a + cs * sin_a,
                )
            }
            _ => Default::default(),
        };
        let force_x_n = cos_a * forces.fx_n - sin_a * forces.fy_n;
        let force_y_n = sin_a * forces.fx_n + cos_a * forces.fy_n;

        // 5. Drives: each axis resists its share of the force on the tool.
        let vx = feed_mm_min * cos_a;
        let vy = feed_mm_min * sin_a;
        let finished = cnc.finished || time_s >= self.config.max_duration_s;
        let mut ax = self.axes[0].step_without_currents(vx, -force_x_n, 0.0);
        let mut ay = self.axes[1].step_without_currents(vy, -force_y_n, 0.0);
        let (measured, unmeasured) = match self.config.measured_axis {
            FeedAxis::X => ((&self.axes[0], &ax), (&self.axes[1], &mut ay)),
            FeedAxis::Y => ((&self.axes[1], &ay), (&self.axes[0], &mut ax)),
        };
        let feed_point = measured.0.phase_point(measured.1.iq_a);
        if keep || finished {
            unmeasured.1.phase_currents_a = unmeasured.0.phase_currents_a(unmeasured.1.iq_a);
        }
        let spindle = self
            .spindle
            .step_without_currents(spindle_command_rpm, forces.torque_nm);
        let points = PhasePoints {
            feed: feed_point,
            spindle: self.spindle.phase_point(spindle.rms_current_a),
        };
        if spindle.running && self.spindle_started_at_s.is_none() {
            self.spindle_started_at_s = Some(time_s);
        } else if !spindle.running {
            self.spindle_started_at_s = None;
        }

        // 6. Sensors: now, or for a whole block after its physics (Simulator::read_currents).
        let currents = if read_now {
            self.read_sample(points)
        } else {
            SampleCurrents::LATER
        };
        match self.config.measured_axis {
            FeedAxis::X => ax.phase_currents_a = currents.feed_a,
            FeedAxis::Y => ay.phase_currents_a = currents.feed_a,
        }

        // Paper 004's sensorless estimate from what the CNC knows, once per interpolation period.
        if ipo_tick {
            (self.power_law_force_n, self.power_law_uncertainty) = match region {
                Some(r) if cutting => {
                    let now = PowerLawInputs {
                        radial_width_mm: width_mm,
                        feed_per_tooth_mm,
                        axial_depth_mm: depth_mm,
                        diameter_mm: cutter.diameter_mm,
                        teeth_engaged: self.immersion.teeth_engaged(cutter.teeth),
                        cutter_teeth: f64::from(cutter.teeth),
                    };
                    match &self.sensorless_network {
                        Some(network) => {
                            let estimate = network.estimate(&now);
                            (estimate.force_n, estimate.relative_uncertainty)
                        }
                        None => self.region_power_law[r].evaluate(&now),
                    }
                }
                _ => (0.0, 0.0),
            };
        }

        let in_work = region.is_some();
        let cut_depth_mm = if in_work { depth_mm } else { 0.0 };
        let cut_width_mm = if in_work { width_mm } else { 0.0 };
        let resultant_n = forces.resultant_n();
        let power_w = forces.power_w(spindle.speed_rpm);
        let removal = cut_depth_mm * cut_width_mm * math::max(feed_mm_min, 0.0) / 60.0;
        let time_since_start_s = self.spindle_started_at_s.map_or(0.0, |t| time_s - t);

        let sensors = SensorSample {
            time_s,
            feed_phase_currents_a: currents.feed_read_a,
            spindle_phase_currents_a: currents.spindle_read_a,
            spindle_fv_voltage_v: spindle.fv_voltage_v,
            spindle_speed_rpm: spindle.speed_rpm,
            spindle_command_rpm,
            programmed_feed_mm_min: cnc.programmed_feed_mm_min,
            feed_mm_min,
            applied_override_pct: applied.pct,
            spindle_running: spindle.running,
            time_since_spindle_start_s: time_since_start_s,
        };
        let truth = PlantTruth {
            force_x_n,
            force_y_n,
            force_z_n: forces.fz_n,
            force_resultant_n: resultant_n,
            feed_force_n: -forces.fx_n,
            spindle_torque_nm: forces.torque_nm,
            cutting_power_w: power_w,
            depth_mm: cut_depth_mm,
            width_mm: cut_width_mm,
            feed_per_tooth_mm,
            path_position_mm: s,
            material_removal_mm3_s: removal,
            tool_x_mm: point.position_mm[0],
            tool_y_mm: point.position_mm[1],
            feed_current_rms_a: if read_now {
                three_phase_rms_a(currents.feed_a)
            } else {
                f64::NAN
            },
            spindle_current_rms_a: spindle.rms_current_a,
        };
        let signals = PlantSignals {
            spindle_command_rpm,
            spindle_speed_rpm: spindle.speed_rpm,
            spindle_gear: spindle.gear,
            material: region.map(|r| self.scenario.material_regions()[r].material),
            entry_deg: self.immersion.entry_rad.to_degrees(),
            exit_deg: self.immersion.exit_rad.to_degrees(),
            power_law_force_n: self.power_law_force_n,
            axis_x: AxisSignals {
                velocity_mm_min: vx,
                load_force_n: -force_x_n,
                torque_nm: ax.torque_nm,
                iq_a: ax.iq_a,
                phase_currents_a: ax.phase_currents_a,
            },
            axis_y: AxisSignals {
                velocity_mm_min: vy,
                load_force_n: -force_y_n,
                torque_nm: ay.torque_nm,
                iq_a: ay.iq_a,
                phase_currents_a: ay.phase_currents_a,
            },
            spindle_motor_torque_nm: spindle.motor_torque_nm,
            spindle_phase_currents_a: currents.spindle_a,
            fv_voltage_v: spindle.fv_voltage_v,
            feed_currents_read_a: currents.feed_read_a,
            spindle_currents_read_a: currents.spindle_read_a,
            brake_excitation_a: f64::NAN,
            brake_torque_nm: f64::NAN,
            ..PlantSignals::from_control(time_s, truth, &control)
        };
        let sample = PlantSample {
            sensors,
            signals,
            finished,
        };
        (sample, points)
    }

    /// One sample's phase currents from its phase points, and what the sensors read of them.
    #[inline(always)]
    fn read_sample(&mut self, points: PhasePoints) -> SampleCurrents {
        let feed_a = self.measured_axis().waveform().currents_at(points.feed);
        let spindle_a = self.spindle.waveform().currents_at(points.spindle);
        SampleCurrents {
            feed_a,
            spindle_a,
            feed_read_a: self.feed_sensor.read(feed_a),
            spindle_read_a: self.spindle_sensor.read(spindle_a),
        }
    }

    /// The feed axis the feed sensor is on.
    #[inline(always)]
    fn measured_axis(&self) -> &FeedDrive {
        match self.config.measured_axis {
            FeedAxis::X => &self.axes[0],
            FeedAxis::Y => &self.axes[1],
        }
    }

    /// The phase currents of samples whose physics has run and what the sensors read of them,
    /// written into `out` (and into `latest`, the last of them in full, if it is to be kept):
    /// first every sample's true currents from its phase points, then each sensor's readings
    /// in order ([`CurrentSensor::read_block`]). Nothing in the physics depends on them, so a
    /// block's come out with the same bits as sample by sample.
    #[inline(always)]
    fn read_currents(
        &mut self,
        points: &[PhasePoints],
        out: &mut [BlockStep],
        latest: Option<&mut PlantSample>,
    ) {
        let n = points.len().min(out.len()).min(CHUNK);
        if n == 0 {
            return;
        }
        let mut feed = [[0.0; 3]; CHUNK];
        let mut spindle = [[0.0; 3]; CHUNK];
        let (feed, spindle) = (&mut feed[..n], &mut spindle[..n]);
        let (feed_waveform, spindle_waveform) =
            (*self.measured_axis().waveform(), *self.spindle.waveform());
        for ((p, f), s) in points.iter().zip(feed.iter_mut()).zip(spindle.iter_mut()) {
            *f = feed_waveform.currents_at(p.feed);
            *s = spindle_waveform.currents_at(p.spindle);
        }
        for (slot, f) in out.iter_mut().zip(feed.iter()) {
            if let Some(truth) = &mut slot.step.truth {
                truth.feed_current_rms_a = three_phase_rms_a(*f);
            }
        }
        let (true_feed, true_spindle) = (feed[n - 1], spindle[n - 1]);
        self.feed_sensor.read_block(feed);
        self.spindle_sensor.read_block(spindle);
        for ((slot, f), s) in out.iter_mut().zip(feed.iter()).zip(spindle.iter()) {
            slot.step.sensors.feed_phase_currents_a = *f;
            slot.step.sensors.spindle_phase_currents_a = *s;
        }
        if let Some(sample) = latest {
            let last = &out[n - 1].step;
            sample.sensors = last.sensors;
            if let Some(truth) = last.truth {
                sample.signals.truth = truth;
            }
            let signals = &mut sample.signals;
            match self.config.measured_axis {
                FeedAxis::X => signals.axis_x.phase_currents_a = true_feed,
                FeedAxis::Y => signals.axis_y.phase_currents_a = true_feed,
            }
            signals.spindle_phase_currents_a = true_spindle;
            signals.feed_currents_read_a = feed[n - 1];
            signals.spindle_currents_read_a = spindle[n - 1];
        }
    }

    /// Up to [`CHUNK`] samples of a block ([`PlantModel::advance_block`]): their physics sample
    /// after sample, then their phase currents and readings together. `holds_blocks_end` says
    /// whether the block's last sample is in `out`; it is kept as the latest. Returns how many
    /// samples were written and whether the block has ended (at its last sample, or where the
    /// run finished).
    #[inline(always)]
    fn advance_chunk(
        &mut self,
        command: OverrideCommand,
        out: &mut [BlockStep],
        holds_blocks_end: bool,
    ) -> (usize, bool) {
        if self.sampling.latest.finished {
            // A finished run repeats its last sample.
            if let Some(slot) = out.first_mut() {
                slot.step = self.sampling.machine_step();
                slot.dynamometer = None;
            }
            return (out.len().min(1), true);
        }
        let mut points = [PhasePoints::default(); CHUNK];
        let n = out.len().min(CHUNK);
        let mut latest = None;
        let mut stepped = 0;
        for (slot, point) in out[..n].iter_mut().zip(points.iter_mut()) {
            let tick = self.sampling.tick();
            let blocks_end = holds_blocks_end && stepped + 1 == n;
            let (sample, p) = self.physics(tick, command, blocks_end, false);
            *point = p;
            slot.step = MachineStep {
                sensors: sample.sensors,
                truth: Some(sample.signals.truth),
            };
            slot.dynamometer = None;
            stepped += 1;
            if sample.finished || blocks_end {
                latest = Some(sample);
                break;
            }
        }
        self.read_currents(&points[..stepped], &mut out[..stepped], latest.as_mut());
        let ended = latest.is_some();
        if let Some(sample) = latest {
            self.sampling.latest = sample;
        }
        (stepped, ended)
    }

    /// The override the machine applies now.
    pub fn applied_override(&self) -> AppliedOverride {
        self.control.applied()
    }
}

impl PlantModel for Simulator {
    fn sampling(&self) -> &Sampling {
        &self.sampling
    }

    fn sampling_mut(&mut self) -> &mut Sampling {
        &mut self.sampling
    }

    #[inline(always)]
    fn advance(&mut self, tick: Tick, command: OverrideCommand) -> PlantSample {
        self.physics(tick, command, true, true).0
    }

    #[inline(always)]
    fn advance_unkept(&mut self, tick: Tick, command: OverrideCommand) -> PlantSample {
        self.physics(tick, command, false, true).0
    }

    #[inline(always)]
    fn advance_block(&mut self, command: OverrideCommand, out: &mut [BlockStep]) -> usize {
        if !READ_AFTER_PHYSICS {
            return super::advance_sample_by_sample(self, command, out);
        }
        let (mut done, n) = (0, out.len());
        while done < n {
            let end = (done + CHUNK).min(n);
            let (stepped, ended) = self.advance_chunk(command, &mut out[done..end], end == n);
            done += stepped;
            if ended || stepped == 0 {
                break;
            }
        }
        done
    }

    fn power_law_force(&self) -> Option<SensorlessEstimate> {
        Some(SensorlessEstimate {
            force_n: self.power_law_force_n,
            relative_uncertainty: self.power_law_uncertainty,
        })
    }

    fn restart(&mut self) -> PlantSignals {
        self.ipo.reset();
        self.control.reset();
        self.spindle.reset();
        for axis in self.axes.iter_mut() {
            axis.reset();
        }
        self.feed_sensor.reset(self.config.seed, FEED_SENSOR_STREAM);
        self.spindle_sensor
            .reset(self.config.seed, SPINDLE_SENSOR_STREAM);
        self.segment_hint = 0;
        self.profile_hints = ProfileHints::default();
        self.immersion_width_mm = f64::NAN;
        self.spindle_arrived_at_s = None;
        self.spindle_started_at_s = None;
        self.power_law_force_n = 0.0;
        self.power_law_uncertainty = 0.0;
        self.cnc_block = 0;
        let start = self.scenario.point_at(0.0);
        PlantSignals {
            truth: PlantTruth {
                tool_x_mm: start.position_mm[0],
                tool_y_mm: start.position_mm[1],
                ..PlantTruth::default()
            },
            brake_excitation_a: f64::NAN,
            brake_torque_nm: f64::NAN,
            ..PlantSignals::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::{Machine, MachineStep};
    use crate::plant::mechanics::Cutter;
    use crate::plant::scenario::{MaterialRegion, Move, ScenarioSpec};

    fn short_slot(rpm: f64) -> Scenario {
        Scenario::new(ScenarioSpec {
            name: "short".into(),
            start_mm: [0.0, 0.0],
            moves: vec![Move::line([12.0, 0.0], 600.0, rpm)],
            cutter: Cutter::new(10.0, 2, 30.0).unwrap(),
            mode: MillingMode::Slot,
            depth_mm: vec![(0.0, 2.0)],
            width_mm: vec![(0.0, 10.0)],
            materials: vec![MaterialRegion {
                from_mm: 2.0,
                to_mm: 12.0,
                material: Material::Sm45c,
            }],
            spindle_start_dwell_s: 0.0,
        })
        .unwrap()
    }

    fn config() -> SimConfig {
        SimConfig {
            sample_rate_hz: 2000.0,
            ..SimConfig::with_seed(5)
        }
    }

    #[test]
    fn nothing_moves_before_the_spindle_is_at_speed() {
        let mut sim = Simulator::new(short_slot(3000.0), config()).unwrap();
        for _ in 0..200 {
            let s = sim.step(OverrideCommand::default());
            assert_eq!(s.truth.unwrap().path_position_mm, 0.0);
        }
    }

    #[test]
    fn runs_to_the_end_of_the_program() {
        let mut sim = Simulator::new(short_slot(1000.0), config()).unwrap();
        let mut n = 0;
        let mut peak_force = 0.0f64;
        while !sim.finished() && n < 40_000 {
            let s = sim.step(OverrideCommand::default());
            peak_force = peak_force.max(s.truth.unwrap().force_resultant_n);
            n += 1;
        }
        assert!(sim.finished());
        assert!((sim.signals().truth.path_position_mm - 12.0).abs() < 0.02);
        assert!(peak_force > 100.0);
        // Stepping after the end repeats the last sample.
        let a = sim.step(OverrideCommand::default());
        assert_eq!(a, sim.step(OverrideCommand::default()));
    }

    #[test]
    fn reset_reproduces_the_first_run() {
        let mut sim = Simulator::new(short_slot(1000.0), config()).unwrap();
        let first: Vec<MachineStep> = (0..3000)
            .map(|_| sim.step(OverrideCommand::default()))
            .collect();
        sim.reset();
        let second: Vec<MachineStep> = (0..3000)
            .map(|_| sim.step(OverrideCommand::default()))
            .collect();
        assert_eq!(first, second);
    }

    #[test]
    fn bad_configs_name_the_nested_field() {
        let mut c = config();
        c.feed_drive.screw_pitch_mm = 0.0;
        let e = Simulator::new(short_slot(1000.0), c).unwrap_err();
        assert_eq!(e.field, "feed_drive.screw_pitch_mm");
    }
}
