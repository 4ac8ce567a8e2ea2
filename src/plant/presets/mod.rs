//! The papers' experiments as named, seeded machines.
//!
//! | preset | source | plant |
//! |---|---|---|
//! | `kim-step-doc` | paper 003 Fig. 10: DOC 1 → 5 mm in 1 mm steps, SM45C, 2-flute Ø20 carbide end mill, 1000 rpm | mill |
//! | `kim-material-taper` | paper 003 Fig. 11: SM45C then aluminium, DOC 1 → 4 mm, 600 rpm, 160 mm/min | mill |
//! | `kim-circular-taper` | paper 003 Fig. 12–13: line at DOC 2 mm, then a circle with DOC 2 → 5 → 2 mm, 3000 rpm, 170 mm/min | mill |
//! | `maneerat-doc-1/2/4` | paper 001 Fig. 7–9: Ø10 flat end mill, 3000 rpm, DOC 1/2/4 mm, targets 150/200/320 N | mill |
//! | `liu-current-step` | paper 002 Fig. 7: bond-graph spindle and x axis of a machining centre, a Ø50 face mill in SM45C at 1500 mm/min, a step in depth, I_ref 25 A | bond graph |
//! | `wang-brake-bench` | paper 000 §4: magnetic-particle brake in excitation steps, with hysteresis | brake bench |
//!
//! Each preset is one [`Definition`] (a `static` in `definitions`: names, source, the values chosen where
//! the paper is silent, override mode, plant, cut and target), and [`Preset`] is the registry
//! that names them. Every method of `Preset` reads the definition, so adding a preset is one
//! variant, one line in [`Preset::ALL`] and [`Preset::definition`], and one `static`.
//!
//! Every value a paper leaves out is chosen and listed in [`Preset::choices`] (and in
//! docs/plant.md). Each preset's machine takes a seed: the same seed gives the same run.
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | [`Preset`], the registry: names, summaries, and every preset's machines and program from its definition |
//! | `definitions` | one [`Definition`] per preset (a `static`), and a mill preset's cut ([`MillParameters`]) |
//! | `edits` | [`PlantEdits`], what a person may change of a mill preset, with their accepted ranges |
//! | `machine` | [`PresetMachine`], any preset's machine behind one type |

mod definitions;
mod edits;
mod machine;

use definitions::{
    mean_resultant_n, KIM_CIRCULAR_TAPER, KIM_MATERIAL_TAPER, KIM_STEP_DOC, LIU_CURRENT_STEP,
    MANEERAT_DOC_1, MANEERAT_DOC_2, MANEERAT_DOC_4, MANEERAT_SECOND_ORDER, WANG_BRAKE_BENCH,
};
pub use definitions::{Definition, ForceTarget, MillParameters, PlantDefinition};
pub use edits::{EditError, PlantEdits};
pub use machine::PresetMachine;

use serde::{Deserialize, Serialize};

use crate::machine::Machine;
use crate::plant::bench::{BrakeBench, BrakeBenchConfig};
use crate::plant::bond_graph::{BondGraphMachine, BondGraphRun};
use crate::plant::cnc::{CncConfig, OverrideMode};
use crate::plant::dynamometer::{DynamometerConfig, WithDynamometer};
use crate::plant::scenario::{Scenario, ScenarioSpec};
use crate::plant::second_order::{SecondOrderConfig, SecondOrderMachine, SecondOrderRun};
use crate::plant::simulator::{SimConfig, Simulator};
use crate::plant::PlantError;

/// What the teach cut's machine adds to a run's seed: the teach cut and the closed loop run on
/// two parts of one machine, cut with different noise ([`Preset::teach_and_run_machines`]).
pub const TEACH_SEED_OFFSET: u64 = 0x7EAC;

/// A named experiment. Serialised by its [`name`](Preset::name), e.g. `"maneerat-doc-1"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "&'static str", try_from = "String")]
pub enum Preset {
    /// Paper 003 Fig. 10.
    KimStepDoc,
    /// Paper 003 Fig. 11.
    KimMaterialTaper,
    /// Paper 003 Fig. 12–13.
    KimCircularTaper,
    /// Paper 001 Fig. 7.
    ManeeratDoc1,
    /// Paper 001 Fig. 8.
    ManeeratDoc2,
    /// Paper 001 Fig. 9.
    ManeeratDoc4,
    /// Paper 001's own model: the second-order force process of eq 2.3 on Fig. 8's cut.
    ManeeratSecondOrder,
    /// Paper 002 Fig. 7.
    LiuCurrentStep,
    /// Paper 000 §4.
    WangBrakeBench,
}

/// Which plant a preset runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlantKind {
    /// The full simulated mill ([`Simulator`]).
    Mill,
    /// Paper 002's bond graph ([`BondGraphMachine`]).
    BondGraph,
    /// Paper 000's brake bench ([`BrakeBench`]).
    BrakeBench,
    /// Paper 001's second-order force process ([`SecondOrderMachine`]).
    SecondOrder,
}

impl PlantKind {
    /// Every plant kind.
    pub const ALL: [PlantKind; 4] = [
        PlantKind::Mill,
        PlantKind::BondGraph,
        PlantKind::BrakeBench,
        PlantKind::SecondOrder,
    ];

    /// Short name.
    ///
    /// ```
    /// use cutlab::plant::presets::PlantKind;
    /// assert_eq!(
    ///     PlantKind::ALL.map(PlantKind::name),
    ///     ["mill", "bond-graph", "brake-bench", "second-order"]
    /// );
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            PlantKind::Mill => "mill",
            PlantKind::BondGraph => "bond-graph",
            PlantKind::BrakeBench => "brake-bench",
            PlantKind::SecondOrder => "second-order",
        }
    }

    /// Label for forms.
    pub fn label(self) -> &'static str {
        match self {
            PlantKind::Mill => "Simulated mill (mechanistic cutting, drives, sensors)",
            PlantKind::BondGraph => "Paper 002's bond-graph spindle + x-axis model",
            PlantKind::BrakeBench => "Paper 000's magnetic-particle brake bench",
            PlantKind::SecondOrder => "Paper 001's second-order force process (eq 2.3)",
        }
    }
}

/// A time schedule of a non-cutting preset's load, for drawing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadSchedule {
    /// What the values are.
    pub quantity: &'static str,
    /// Their unit.
    pub unit: &'static str,
    /// (time in s, value) at each step; the value holds until the next point.
    pub points: Vec<(f64, f64)>,
    /// End of the run.
    pub end_s: f64,
}

/// One line of `cutlab scenarios`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PresetSummary {
    /// Preset name.
    pub name: &'static str,
    /// Label.
    pub label: &'static str,
    /// The paper and figure.
    pub source: &'static str,
    /// Which plant.
    pub plant: &'static str,
    /// Cutter, e.g. "Ø20 mm, 2 teeth, 30° helix".
    pub tool: Option<String>,
    /// Work material(s).
    pub material: Option<String>,
    /// Milling mode.
    pub mode: Option<&'static str>,
    /// Spindle speed.
    pub spindle_rpm: Option<f64>,
    /// Programmed feed.
    pub programmed_feed_mm_min: Option<f64>,
    /// Smallest and largest axial depth.
    pub depth_mm: Option<[f64; 2]>,
    /// Radial width.
    pub width_mm: Option<f64>,
    /// Path length.
    pub path_length_mm: Option<f64>,
    /// Run time at 100 % override (spindle start and corners not counted).
    pub nominal_duration_s: f64,
    /// How the override reaches the machine.
    pub override_mode: &'static str,
    /// Suggested force target, if the preset has one.
    pub target_force_n: Option<f64>,
    /// Suggested spindle-current target, if the preset has one.
    pub target_spindle_current_a: Option<f64>,
    /// Values chosen where the paper is silent.
    pub choices: &'static [&'static str],
}

/// How long a program runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProgramLength {
    /// A path: the program ends when the path is cut, sooner at a higher feed (the mills, and
    /// paper 001's process on a mill's path).
    Path,
    /// A time: the program ends at the same moment whatever the feed (the brake bench's
    /// excitation schedule, paper 002's 40 s around its load step).
    Time,
}

impl From<Preset> for &'static str {
    fn from(preset: Preset) -> Self {
        preset.name()
    }
}

impl TryFrom<String> for Preset {
    type Error = String;

    fn try_from(name: String) -> Result<Self, Self::Error> {
        Preset::named(&name)
    }
}

impl Preset {
    /// The preset called `name`, or the one message every front end gives for a name that is
    /// none (the CLI puts its flag in front).
    pub fn named(name: &str) -> Result<Preset, String> {
        Preset::from_name(name)
            .ok_or_else(|| format!("unknown preset {name:?}; presets: {}", Preset::names()))
    }

    /// Every preset.
    pub const ALL: [Preset; 9] = [
        Preset::KimStepDoc,
        Preset::KimMaterialTaper,
        Preset::KimCircularTaper,
        Preset::ManeeratDoc1,
        Preset::ManeeratDoc2,
        Preset::ManeeratDoc4,
        Preset::ManeeratSecondOrder,
        Preset::LiuCurrentStep,
        Preset::WangBrakeBench,
    ];

    /// Everything about this preset.
    pub fn definition(self) -> &'static Definition {
        match self {
            Preset::KimStepDoc => &KIM_STEP_DOC,
            Preset::KimMaterialTaper => &KIM_MATERIAL_TAPER,
            Preset::KimCircularTaper => &KIM_CIRCULAR_TAPER,
            Preset::ManeeratDoc1 => &MANEERAT_DOC_1,
            Preset::ManeeratDoc2 => &MANEERAT_DOC_2,
            Preset::ManeeratDoc4 => &MANEERAT_DOC_4,
            Preset::ManeeratSecondOrder => &MANEERAT_SECOND_ORDER,
            Preset::LiuCurrentStep => &LIU_CURRENT_STEP,
            Preset::WangBrakeBench => &WANG_BRAKE_BENCH,
        }
    }

    /// Name for the CLI and URLs.
    pub fn name(self) -> &'static str {
        self.definition().name
    }

    /// Label for lists.
    pub fn label(self) -> &'static str {
        self.definition().label
    }

    /// The paper and figure it reproduces.
    pub fn source(self) -> &'static str {
        self.definition().source
    }

    /// The preset named `name`.
    ///
    /// ```
    /// use cutlab::plant::Preset;
    /// assert_eq!(Preset::from_name("kim-step-doc"), Some(Preset::KimStepDoc));
    /// assert_eq!(Preset::from_name("nope"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        let n = name.trim();
        Self::ALL.into_iter().find(|p| p.name() == n)
    }

    /// Every preset's name, comma separated, for error messages.
    pub fn names() -> String {
        Self::ALL.map(Preset::name).join(", ")
    }

    /// The plant it runs on.
    pub fn plant_kind(self) -> PlantKind {
        match self.definition().plant {
            PlantDefinition::Mill(_) => PlantKind::Mill,
            PlantDefinition::BondGraph { .. } => PlantKind::BondGraph,
            PlantDefinition::BrakeBench => PlantKind::BrakeBench,
            PlantDefinition::SecondOrder(_) => PlantKind::SecondOrder,
        }
    }

    /// Whether the program ends when its path is cut (the mills, and paper 001's process on a
    /// mill's path) or at a time whatever the feed (the brake bench's excitation schedule, paper
    /// 002's run around its load step): only the first can save cycle time.
    ///
    /// ```
    /// use cutlab::plant::presets::ProgramLength;
    /// use cutlab::plant::Preset;
    /// assert_eq!(Preset::KimStepDoc.program_length(), ProgramLength::Path);
    /// assert_eq!(Preset::LiuCurrentStep.program_length(), ProgramLength::Time);
    /// ```
    pub fn program_length(self) -> ProgramLength {
        match self.plant_kind() {
            PlantKind::Mill | PlantKind::SecondOrder => ProgramLength::Path,
            PlantKind::BondGraph | PlantKind::BrakeBench => ProgramLength::Time,
        }
    }

    /// Every value this preset had to choose because its paper does not give it.
    pub fn choices(self) -> &'static [&'static str] {
        self.definition().choices
    }

    /// The cut of a mill preset (and of the second-order process standing in for one); `None`
    /// for the bench and the bond graph.
    pub fn mill_parameters(self) -> Option<&'static MillParameters> {
        match &self.definition().plant {
            PlantDefinition::Mill(cut) | PlantDefinition::SecondOrder(cut) => Some(cut),
            _ => None,
        }
    }

    /// The scenario of a mill preset (its path, depth and width profiles and materials, for
    /// drawing); `None` for the bench and the bond graph.
    pub fn scenario(self) -> Option<Scenario> {
        self.scenario_spec()
            .and_then(|spec| Scenario::new(spec).ok())
    }

    /// The scenario's plain specification.
    pub fn scenario_spec(self) -> Option<ScenarioSpec> {
        self.mill_parameters()
            .map(|cut| cut.scenario_spec(self.name()))
    }

    /// How the override reaches the preset's machine.
    pub fn override_mode(self) -> OverrideMode {
        self.definition().override_mode
    }

    /// The control of every plant: the defaults with this preset's override mode.
    fn cnc_config(self) -> CncConfig {
        CncConfig {
            override_mode: self.override_mode(),
            ..CncConfig::default()
        }
    }

    /// The mill's configuration for `seed` (the defaults with this preset's override mode).
    pub fn sim_config(self, seed: u64) -> SimConfig {
        SimConfig {
            seed,
            cnc: self.cnc_config(),
            ..SimConfig::default()
        }
    }

    /// The full simulated mill of a mill preset.
    pub fn simulator(self, seed: u64) -> Result<Simulator, PlantError> {
        let spec = self
            .scenario_spec()
            .filter(|_| self.plant_kind() == PlantKind::Mill);
        let spec = spec.ok_or_else(|| {
            PlantError::new(
                "preset",
                format!(
                    "{} runs on the {} plant, not the mill",
                    self.name(),
                    self.plant_kind().name()
                ),
            )
        })?;
        let simulator = Simulator::new(Scenario::new(spec)?, self.sim_config(seed))?;
        Ok(self.with_learned_network(simulator, &PlantEdits::default()))
    }

    /// `simulator` (this preset's program, with `edits`) estimating its sensorless force with the
    /// network the preset learned on its trial cuts ([`super::sensorless::shipped_network`]),
    /// when it has one and the edits keep the part's material: a network learned on one
    /// material knows nothing of another, and a run on another material estimates with paper
    /// 004's published weights, calibrated. Speed, feed, depth and the tool are inputs the
    /// network reads (the diameter and the teeth with the published exponents it holds).
    fn with_learned_network(self, simulator: Simulator, edits: &PlantEdits) -> Simulator {
        let same_material = match (edits.material, self.scenario_spec()) {
            (None, _) => true,
            (Some(m), Some(spec)) => spec.materials.iter().all(|r| r.material == m),
            (Some(_), None) => false,
        };
        match super::sensorless::shipped_network(self).filter(|_| same_material) {
            Some(network) => simulator.with_sensorless_network(network),
            None => simulator,
        }
    }

    /// The brake bench's settings (wang-brake-bench only).
    pub fn bench_config(self, seed: u64) -> Option<BrakeBenchConfig> {
        matches!(self.definition().plant, PlantDefinition::BrakeBench).then(|| BrakeBenchConfig {
            seed,
            cnc: self.cnc_config(),
            ..BrakeBenchConfig::default()
        })
    }

    /// The rate the preset's machine samples at, Hz.
    ///
    /// ```
    /// use cutlab::machine::Machine;
    /// use cutlab::plant::Preset;
    /// for preset in Preset::ALL {
    ///     assert_eq!(preset.sample_rate_hz(), preset.machine(1).unwrap().sample_rate_hz());
    /// }
    /// ```
    pub fn sample_rate_hz(self) -> f64 {
        match (self.bench_config(0), self.bond_graph_run(0)) {
            (Some(bench), _) => bench.sample_rate_hz,
            (None, Some(run)) => run.sample_rate_hz,
            // The mills, and paper 001's second-order process on a mill's configuration.
            (None, None) => self.sim_config(0).sample_rate_hz,
        }
    }

    /// The bond graph's run (liu-current-step only), with the load step of its definition.
    pub fn bond_graph_run(self, seed: u64) -> Option<BondGraphRun> {
        matches!(self.definition().plant, PlantDefinition::BondGraph { .. }).then(|| BondGraphRun {
            seed,
            cnc: self.cnc_config(),
            ..BondGraphRun::paper_002(BondGraphRun::DEFAULT_LOAD_STEP_PCT)
        })
    }

    /// When the load steps that no depth of cut shows (paper 002's step in cutting resistance);
    /// empty for the presets whose steps are in their depth profile.
    ///
    /// ```
    /// use cutlab::plant::Preset;
    /// assert_eq!(Preset::LiuCurrentStep.load_step_times_s(), vec![15.0]);
    /// assert!(Preset::KimStepDoc.load_step_times_s().is_empty());
    /// ```
    pub fn load_step_times_s(self) -> Vec<f64> {
        self.bond_graph_run(0).map_or_else(Vec::new, |run| {
            run.load_steps
                .iter()
                .map(|s| s.time_s)
                .filter(|t| *t > 0.0)
                .collect()
        })
    }

    /// The preset's machine, seeded.
    ///
    /// ```
    /// use cutlab::machine::{Machine, OverrideCommand};
    /// use cutlab::plant::Preset;
    /// for preset in Preset::ALL {
    ///     let mut m = preset.machine(42).unwrap();
    ///     let s = m.step(OverrideCommand::default());
    ///     assert!(s.truth.is_some() && m.sample_rate_hz() == 10_000.0);
    /// }
    /// ```
    pub fn machine(self, seed: u64) -> Result<PresetMachine, PlantError> {
        Ok(match self.plant_kind() {
            PlantKind::Mill => PresetMachine::Mill(Box::new(self.simulator(seed)?)),
            PlantKind::BrakeBench => {
                let cfg = self
                    .bench_config(seed)
                    .ok_or_else(|| PlantError::new("preset", "not a bench preset"))?;
                PresetMachine::BrakeBench(Box::new(BrakeBench::new(cfg)?))
            }
            PlantKind::BondGraph => {
                let run = self
                    .bond_graph_run(seed)
                    .ok_or_else(|| PlantError::new("preset", "not a bond-graph preset"))?;
                PresetMachine::BondGraph(Box::new(BondGraphMachine::new(run)?))
            }
            PlantKind::SecondOrder => {
                let run = self
                    .second_order_equivalent(seed)
                    .ok_or_else(|| PlantError::new("preset", "not a second-order preset"))?;
                PresetMachine::SecondOrder(Box::new(SecondOrderMachine::new(run)?))
            }
        })
    }

    /// The preset's machine with a user's edits applied (mill presets only: edits for the bench
    /// or the bond graph are an error, not silently ignored). Edited values are checked like
    /// any configuration: an error names the field.
    ///
    /// ```
    /// use cutlab::plant::presets::{PlantEdits, Preset};
    /// use cutlab::plant::materials::Material;
    /// let edits = PlantEdits { material: Some(Material::Aluminium), ..PlantEdits::default() };
    /// assert!(Preset::KimStepDoc.machine_with(1, &edits).is_ok());
    /// let bad = PlantEdits { spindle_rpm: Some(-5.0), ..PlantEdits::default() };
    /// assert!(Preset::KimStepDoc.machine_with(1, &bad).unwrap_err().to_string().contains("spindle"));
    /// assert!(Preset::LiuCurrentStep.machine_with(1, &edits).is_err());
    /// ```
    pub fn machine_with(self, seed: u64, edits: &PlantEdits) -> Result<PresetMachine, PlantError> {
        if *edits == PlantEdits::default() {
            return self.machine(seed);
        }
        let others = PlantEdits {
            load_step_pct: None,
            ..*edits
        };
        if let (Some(pct), Some(run)) = (edits.load_step_pct, self.bond_graph_run(seed)) {
            if others == PlantEdits::default() {
                edits.check_load_step()?;
                return Ok(PresetMachine::BondGraph(Box::new(BondGraphMachine::new(
                    run.with_load_step_pct(pct),
                )?)));
            }
        }
        if edits.load_step_pct.is_some() && self.plant_kind() != PlantKind::BondGraph {
            // Ignoring it would run something other than what the user asked for.
            return Err(PlantError::new(
                "load_step_pct",
                format!(
                    "the load step is paper 002's (liu-current-step); {} has none",
                    self.name()
                ),
            ));
        }
        if self.plant_kind() != PlantKind::Mill {
            // Ignoring them would run something other than what the user asked for.
            return Err(PlantError::new(
                "plant",
                format!(
                    "machine and cut edits apply to the mill presets; {} runs {}",
                    self.name(),
                    self.plant_kind().label()
                ),
            ));
        }
        let (Some(cut), Some(spec)) = (self.mill_parameters(), self.edited_scenario_spec(edits))
        else {
            return self.machine(seed);
        };
        let mut config = self.sim_config(seed);
        edits.check(cut, &config)?;
        if let Some(noise) = edits.sensor_noise_a {
            config.feed_sensor.hall.noise_a = noise;
            config.spindle_sensor.hall.noise_a = noise;
        }
        let simulator = Simulator::new(Scenario::new(spec)?, config)?;
        Ok(PresetMachine::Mill(Box::new(
            self.with_learned_network(simulator, edits),
        )))
    }

    /// The mill program with `edits` made (material, speed, feed, depth, cutter), unchecked:
    /// what [`Preset::seeded_machine`] cuts once the edits are checked. `None` on the plants
    /// without a program.
    pub fn edited_scenario_spec(self, edits: &PlantEdits) -> Option<ScenarioSpec> {
        let mut spec = self.scenario_spec()?;
        if let Some(m) = edits.material {
            for region in &mut spec.materials {
                region.material = m;
            }
        }
        for mv in &mut spec.moves {
            if let Some(rpm) = edits.spindle_rpm {
                mv.spindle_rpm = rpm;
            }
            if let Some(feed) = edits.programmed_feed_mm_min {
                mv.feed_mm_min = feed;
            }
        }
        if let Some(k) = edits.depth_scale {
            for point in &mut spec.depth_mm {
                point.1 *= k;
            }
        }
        if let Some(d) = edits.tool_diameter_mm {
            spec.cutter.diameter_mm = d;
        }
        if let Some(z) = edits.teeth {
            spec.cutter.teeth = z;
        }
        Some(spec)
    }

    /// The machines of one lab run: the teach cut's, seeded with `seed` plus
    /// [`TEACH_SEED_OFFSET`], and the closed loop's, seeded with `seed` — each with `edits`, and
    /// with a dynamometer under the part when the run feeds back the measured force. `cutlab
    /// sim`'s runs and the device emulator's first two parts are these machines, so a run over
    /// the protocol repeats a simulated one.
    ///
    /// ```
    /// use cutlab::machine::{Machine, OverrideCommand};
    /// use cutlab::plant::presets::{PlantEdits, Preset};
    /// let [mut teach, mut run] =
    ///     Preset::KimStepDoc.teach_and_run_machines(1, &PlantEdits::default(), false).unwrap();
    /// let (a, b) = (teach.step(OverrideCommand::default()), run.step(OverrideCommand::default()));
    /// assert_eq!(a.sensors.time_s, b.sensors.time_s);
    /// assert_ne!(a.sensors.spindle_phase_currents_a, b.sensors.spindle_phase_currents_a);
    /// ```
    pub fn teach_and_run_machines(
        self,
        seed: u64,
        edits: &PlantEdits,
        dynamometer: bool,
    ) -> Result<[Box<dyn Machine>; 2], PlantError> {
        Ok([
            self.seeded_machine(seed.wrapping_add(TEACH_SEED_OFFSET), edits, dynamometer)?,
            self.seeded_machine(seed, edits, dynamometer)?,
        ])
    }

    /// The preset's machine seeded with `seed`, with `edits`, and with a dynamometer under the
    /// part if `dynamometer` (one of [`Preset::teach_and_run_machines`]).
    pub fn seeded_machine(
        self,
        seed: u64,
        edits: &PlantEdits,
        dynamometer: bool,
    ) -> Result<Box<dyn Machine>, PlantError> {
        let machine = Box::new(self.machine_with(seed, edits)?);
        Ok(if dynamometer {
            Box::new(WithDynamometer::new(
                machine,
                DynamometerConfig::default(),
                seed,
            )?)
        } else {
            machine
        })
    }

    /// The load schedule of a non-cutting preset, for drawing (`None` for mill presets, whose
    /// load is the scenario's depth profile).
    ///
    /// ```
    /// use cutlab::plant::Preset;
    /// let s = Preset::WangBrakeBench.load_schedule().unwrap();
    /// assert_eq!((s.unit, s.points.len(), s.end_s), ("A", 21, 63.0));
    /// assert!(Preset::KimStepDoc.load_schedule().is_none());
    /// ```
    pub fn load_schedule(self) -> Option<LoadSchedule> {
        if let Some(cfg) = self.bench_config(0) {
            return Some(LoadSchedule {
                quantity: "brake excitation",
                unit: "A",
                points: cfg
                    .excitation_steps_a
                    .iter()
                    .enumerate()
                    .map(|(i, e)| (i as f64 * cfg.step_duration_s, *e))
                    .collect(),
                end_s: cfg.duration_s(),
            });
        }
        self.bond_graph_run(0).map(|run| LoadSchedule {
            quantity: "depth of cut",
            unit: "mm",
            points: run
                .load_steps
                .iter()
                .map(|s| (s.time_s, s.depth_mm))
                .collect(),
            end_s: run.duration_s,
        })
    }

    /// The force target the paper gives, or one chosen for it (see [`Preset::choices`]).
    ///
    /// ```
    /// use cutlab::plant::Preset;
    /// assert_eq!(Preset::ManeeratDoc4.target_force_n(), Some(320.0));
    /// assert!(Preset::KimStepDoc.target_force_n().unwrap() > 100.0);
    /// assert_eq!(Preset::WangBrakeBench.target_force_n(), None);
    /// ```
    pub fn target_force_n(self) -> Option<f64> {
        self.mill_parameters().map(MillParameters::target_force_n)
    }

    /// The spindle-current target the paper gives (paper 002: I_ref = 25 A).
    pub fn target_spindle_current_a(self) -> Option<f64> {
        match self.definition().plant {
            PlantDefinition::BondGraph {
                target_spindle_current_a,
            } => Some(target_spindle_current_a),
            _ => None,
        }
    }

    /// Paper 001's reduced plant standing in for a maneerat preset: eq 2.3 with the static gain
    /// of the mechanistic model's mean resultant at the programmed feed, τ_f = 1/K_v (the
    /// position loop) and τ_c = one spindle revolution (chosen), over the same path with the
    /// gain zero in the air before the material. `None` for other presets.
    ///
    /// ```
    /// use cutlab::plant::Preset;
    /// let run = Preset::ManeeratDoc2.second_order_equivalent(1).unwrap();
    /// assert!((run.process.force_time_constant_s - 0.02).abs() < 1e-12);
    /// assert!(Preset::KimStepDoc.second_order_equivalent(1).is_none());
    /// ```
    pub fn second_order_equivalent(self, seed: u64) -> Option<SecondOrderRun> {
        let p = self
            .mill_parameters()
            .filter(|p| p.second_order_equivalent)?;
        let &(air_mm, _, material) = p.materials.first()?;
        let depth_mm = p.depth_mm.iter().map(|&(_, d)| d).fold(0.0, f64::max);
        let machine = self.sim_config(seed);
        let gain = mean_resultant_n(p, depth_mm, material) / p.feed_mm_min;
        let process = SecondOrderConfig {
            feed_time_constant_s: 1.0 / machine.cnc.position_loop_gain_per_s,
            force_time_constant_s: 60.0 / p.spindle_rpm,
            force_gain_n_per_mm_min: gain,
        };
        Some(SecondOrderRun {
            process,
            length_mm: self.scenario()?.total_length_mm(),
            programmed_feed_mm_min: p.feed_mm_min,
            spindle_rpm: p.spindle_rpm,
            gain_n_per_mm_min: vec![(0.0, 0.0), (air_mm, 0.0), (air_mm, gain)],
            cutter_radius_mm: 0.5 * p.cutter.diameter_mm,
            radial_ratio: material.coefficients().radial_ratio(),
            cut_depth_width_mm: (depth_mm, p.width_mm),
            machine,
        })
    }

    /// The summary `cutlab scenarios` prints.
    ///
    /// ```
    /// use cutlab::plant::Preset;
    /// let s = Preset::KimMaterialTaper.summary();
    /// assert_eq!((s.spindle_rpm, s.programmed_feed_mm_min), (Some(600.0), Some(160.0)));
    /// assert_eq!(s.depth_mm, Some([1.0, 4.0]));
    /// ```
    pub fn summary(self) -> PresetSummary {
        let p = self.mill_parameters();
        let scenario = self.scenario();
        let bench = self.bench_config(0);
        let bond_graph = self.bond_graph_run(0);
        let bond_graph_cut = bond_graph.as_ref().map(|r| r.cut);
        let materials = scenario
            .as_ref()
            .map(|s| {
                let mut names: Vec<&str> = Vec::new();
                for r in s.material_regions() {
                    if !names.contains(&r.material.name()) {
                        names.push(r.material.name());
                    }
                }
                names.join(" then ")
            })
            .or_else(|| bond_graph_cut.map(|c| c.material.name().to_string()));
        let span = |values: Vec<f64>| {
            let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            [lo, hi]
        };
        let depth = scenario
            .as_ref()
            .map(|s| span(s.depth_profile().points().iter().map(|q| q.value).collect()))
            .or_else(|| {
                bond_graph
                    .as_ref()
                    .map(|r| span(r.load_steps.iter().map(|s| s.depth_mm).collect()))
            });
        let nominal_duration_s = match (&scenario, &bench, &bond_graph) {
            (Some(s), _, _) => s.nominal_duration_s(),
            (None, Some(b), _) => b.duration_s(),
            (None, None, Some(r)) => r.duration_s,
            _ => 0.0,
        };
        let (spindle_rpm, programmed_feed_mm_min) = match (p, &bench, &bond_graph) {
            (Some(p), _, _) => (Some(p.spindle_rpm), Some(p.feed_mm_min)),
            (None, Some(b), _) => (None, Some(b.feed_mm_min)),
            // The speed of the reference cut, at which its forces are evaluated.
            (None, None, Some(r)) => (Some(r.cut.spindle_rpm), Some(r.programmed_feed_mm_min)),
            (None, None, None) => (None, None),
        };
        let cutter = p.map(|p| p.cutter).or(bond_graph_cut.map(|c| c.cutter));
        PresetSummary {
            name: self.name(),
            label: self.label(),
            source: self.source(),
            plant: self.plant_kind().name(),
            tool: cutter.map(|c| {
                format!(
                    "Ø{} mm, {} teeth, {}° helix",
                    c.diameter_mm, c.teeth, c.helix_deg
                )
            }),
            material: materials,
            mode: p
                .map(|p| p.mode.name())
                .or(bond_graph_cut.map(|c| c.mode.name())),
            spindle_rpm,
            programmed_feed_mm_min,
            depth_mm: depth,
            width_mm: p.map(|p| p.width_mm).or(bond_graph_cut.map(|c| c.width_mm)),
            path_length_mm: scenario.as_ref().map(Scenario::total_length_mm),
            nominal_duration_s,
            override_mode: self.override_mode().name(),
            target_force_n: self.target_force_n(),
            target_spindle_current_a: self.target_spindle_current_a(),
            choices: self.choices(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::OverrideCommand;
    use crate::plant::materials::Material;

    #[test]
    fn names_are_unique_and_round_trip() {
        for p in Preset::ALL {
            assert_eq!(Preset::from_name(p.name()), Some(p));
            assert!(!p.choices().is_empty());
            assert!(p.source().starts_with("paper 00"));
        }
    }

    #[test]
    fn mill_presets_have_valid_scenarios_and_the_others_a_schedule() {
        for p in Preset::ALL {
            match p.plant_kind() {
                // The second-order process runs along its mill preset's path.
                PlantKind::Mill | PlantKind::SecondOrder => {
                    let spec = p.scenario_spec().unwrap();
                    Scenario::new(spec).unwrap();
                    assert!(p.load_schedule().is_none());
                }
                _ => {
                    assert!(p.scenario().is_none());
                    assert!(p.load_schedule().unwrap().points.len() >= 2);
                }
            }
        }
    }

    #[test]
    fn maneerat_forces_at_full_feed_exceed_their_targets() {
        for p in [
            Preset::ManeeratDoc1,
            Preset::ManeeratDoc2,
            Preset::ManeeratDoc4,
        ] {
            let params = *p.mill_parameters().unwrap();
            let depth = params.depth_mm[0].1;
            let f = mean_resultant_n(&params, depth, Material::ToolSteel);
            let target = p.target_force_n().unwrap();
            assert!(f > target, "{}: {f} vs {target}", p.name());
            // …and the target is reachable: the edge forces alone stay below it.
            let edge_only = MillParameters {
                feed_mm_min: 1e-9,
                ..params
            };
            assert!(mean_resultant_n(&edge_only, depth, Material::ToolSteel) < target);
        }
    }

    #[test]
    fn absurd_edits_are_refused_naming_the_field_and_its_range() {
        let cases = [
            (
                Preset::KimStepDoc,
                PlantEdits {
                    programmed_feed_mm_min: Some(1e308),
                    ..PlantEdits::default()
                },
                "programmed_feed_mm_min",
                "1–20000 mm/min",
            ),
            (
                // 1000 mm deep on maneerat's Ø10 mm cutter.
                Preset::ManeeratDoc1,
                PlantEdits {
                    depth_scale: Some(1000.0),
                    ..PlantEdits::default()
                },
                "depth_scale",
                "0.01–40",
            ),
            (
                Preset::KimStepDoc,
                PlantEdits {
                    tool_diameter_mm: Some(1e6),
                    ..PlantEdits::default()
                },
                "tool_diameter_mm",
                "0.5–100 mm",
            ),
        ];
        for (preset, edits, field, range) in cases {
            let e = preset.machine_with(1, &edits).unwrap_err();
            assert_eq!(e.field, field, "{e}");
            assert!(e.message.contains(range), "{e}");
        }
    }

    #[test]
    fn edits_are_checked_with_the_edited_tool_and_the_machine_s_spindle() {
        let p = Preset::KimStepDoc; // 5 mm deep at the end, Ø20 mm
        let (cut, machine) = (p.mill_parameters().unwrap(), p.sim_config(0));
        let check = |edits: PlantEdits| edits.check(cut, &machine);
        // A 1 mm tool for the preset's own 5 mm: the tool is what was edited.
        let e = check(PlantEdits {
            tool_diameter_mm: Some(1.0),
            ..PlantEdits::default()
        })
        .unwrap_err();
        assert_eq!((e.field, e.min, e.max), ("tool_diameter_mm", 1.25, 100.0));
        // Scaled with a smaller tool, the limit follows the tool.
        let e = check(PlantEdits {
            tool_diameter_mm: Some(10.0),
            depth_scale: Some(9.0),
            ..PlantEdits::default()
        })
        .unwrap_err();
        assert_eq!((e.field, e.max), ("depth_scale", 8.0));
        // Faster than the spindle can turn, NaN, and a tooth count the model cannot hold.
        let top = machine.spindle_drive.max_spindle_rpm();
        for (edits, field) in [
            (
                PlantEdits {
                    spindle_rpm: Some(top + 1.0),
                    ..PlantEdits::default()
                },
                "spindle_rpm",
            ),
            (
                PlantEdits {
                    programmed_feed_mm_min: Some(f64::NAN),
                    ..PlantEdits::default()
                },
                "programmed_feed_mm_min",
            ),
            (
                PlantEdits {
                    teeth: Some(40),
                    ..PlantEdits::default()
                },
                "teeth",
            ),
            (
                PlantEdits {
                    sensor_noise_a: Some(-0.1),
                    ..PlantEdits::default()
                },
                "sensor_noise_a",
            ),
        ] {
            assert_eq!(check(edits).unwrap_err().field, field);
        }
        // The ends of every range are accepted and run.
        let edge = PlantEdits {
            spindle_rpm: Some(top),
            programmed_feed_mm_min: Some(20_000.0),
            tool_diameter_mm: Some(100.0),
            teeth: Some(16),
            depth_scale: Some(0.01),
            sensor_noise_a: Some(5.0),
            material: Some(Material::Aluminium),
            load_step_pct: None,
            // 10 diameters of the Ø100 mm tool would be 1000 mm: the table's end binds.
            tool_stick_out_mm: Some(400.0),
            spindle_stiffness_n_um: Some(500.0),
            tool_youngs_modulus_gpa: Some(700.0),
        };
        assert_eq!(check(edge), Ok(()));
        assert!(p.machine_with(1, &edge).is_ok());
        let e = p
            .machine_with(
                1,
                &PlantEdits {
                    tool_diameter_mm: Some(1e6),
                    ..PlantEdits::default()
                },
            )
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "tool_diameter_mm: 1000000 mm is outside the accepted 0.5–100 mm (end mills)"
        );
    }

    #[test]
    fn the_load_step_is_liu_current_steps_own_edit() {
        let liu = Preset::LiuCurrentStep;
        let step = |pct| PlantEdits {
            load_step_pct: Some(pct),
            ..PlantEdits::default()
        };
        // The ends of its range are accepted; beyond them the error names the edit.
        for pct in PlantEdits::LOAD_STEP_PCT {
            assert!(liu.machine_with(1, &step(pct)).is_ok());
        }
        for pct in [-91.0, 151.0, f64::NAN] {
            assert_eq!(
                liu.machine_with(1, &step(pct)).unwrap_err().field,
                "load_step_pct"
            );
        }
        // A mill has no load step, and the bond graph takes no other edit.
        assert_eq!(
            Preset::KimStepDoc
                .machine_with(1, &step(40.0))
                .unwrap_err()
                .field,
            "load_step_pct"
        );
        let both = PlantEdits {
            sensor_noise_a: Some(0.1),
            ..step(40.0)
        };
        assert_eq!(liu.machine_with(1, &both).unwrap_err().field, "plant");
        // The size reaches the machine: the depth doubles at 15 s.
        let mut m = liu.machine_with(1, &step(100.0)).unwrap();
        let depth_at = |m: &mut PresetMachine, t_s: f64| loop {
            let s = m.step(OverrideCommand::default());
            if s.sensors.time_s >= t_s {
                break s.truth.map_or(f64::NAN, |t| t.depth_mm);
            }
        };
        let before = depth_at(&mut m, 14.9);
        let after = depth_at(&mut m, 15.1);
        assert!(
            (after - 2.0 * before).abs() < 1e-12,
            "{before} → {after} mm"
        );
    }

    #[test]
    fn the_circular_taper_has_a_right_angle_at_b() {
        let s = Preset::KimCircularTaper.scenario().unwrap();
        let blocks = s.plan_blocks();
        let turn = (blocks[1].start_direction_rad - blocks[0].end_direction_rad).abs();
        assert!((turn - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        let end = s.point_at(s.total_length_mm());
        assert!(end.position_mm[0].abs() < 1e-9 && end.position_mm[1].abs() < 1e-9);
    }
}
