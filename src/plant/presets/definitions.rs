//! One definition per preset: its names, source, the values chosen where the paper is silent,
//! override mode, plant, cut and target.

use std::f64::consts::PI;

use crate::math;
use crate::plant::bond_graph::PAPER_002_REFERENCE_CURRENT_A;
use crate::plant::cnc::{DialTable, OverrideMode};
use crate::plant::materials::Material;
use crate::plant::mechanics::{mean_forces, Cutter, Immersion, MillingMode};
use crate::plant::scenario::{MaterialRegion, Move, MoveKind, ScenarioSpec};

/// Everything about one preset.
#[derive(Debug)]
pub struct Definition {
    /// Name for the CLI and URLs.
    pub name: &'static str,
    /// Label for lists.
    pub label: &'static str,
    /// The paper and figure it reproduces.
    pub source: &'static str,
    /// Every value chosen because the paper does not give it.
    pub choices: &'static [&'static str],
    /// How the override reaches the machine.
    pub override_mode: OverrideMode,
    /// The plant and what it runs.
    pub plant: PlantDefinition,
}

/// A preset's plant and what runs on it.
#[derive(Debug)]
pub enum PlantDefinition {
    /// The simulated mill cutting this.
    Mill(MillParameters),
    /// Paper 002's bond graph on its Fig. 7 run ([`crate::plant::bond_graph::BondGraphRun::paper_002`]).
    BondGraph {
        /// The reference current the paper regulates the spindle to.
        target_spindle_current_a: f64,
    },
    /// Paper 000's brake bench on its default schedule ([`crate::plant::bench::BrakeBenchConfig`]'s default).
    BrakeBench,
    /// Paper 001's eq 2.3 standing in for the mill on this cut
    /// ([`crate::plant::Preset::second_order_equivalent`]).
    SecondOrder(MillParameters),
}

/// A mill preset's cut: tool, conditions, path, depth, materials and force target.
#[derive(Debug, Clone, Copy)]
pub struct MillParameters {
    /// The end mill.
    pub cutter: Cutter,
    /// Up, down or slot.
    pub mode: MillingMode,
    /// Radial width of cut, constant along the path.
    pub width_mm: f64,
    /// Spindle speed of every block.
    pub spindle_rpm: f64,
    /// Programmed feed of every block.
    pub feed_mm_min: f64,
    /// Start of the path.
    pub start_mm: [f64; 2],
    /// The moves, each to its end point.
    pub path: &'static [([f64; 2], MoveKind)],
    /// Axial depth as (path position, depth) points.
    pub depth_mm: &'static [(f64, f64)],
    /// Material regions as (from, to, material) in path position.
    pub materials: &'static [(f64, f64, Material)],
    /// The force target.
    pub target: ForceTarget,
    /// Paper 001's reduced plant can stand in for this cut: it has one depth and one material.
    pub second_order_equivalent: bool,
}

/// Where a mill preset's force target comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ForceTarget {
    /// The paper gives it.
    Given(f64),
    /// Chosen: the mechanistic mean resultant at this depth in this material, at the programmed
    /// feed.
    MeanResultantAt {
        /// Axial depth.
        depth_mm: f64,
        /// Work material.
        material: Material,
    },
}

/// |F̄| of the mechanistic model at a depth, at the cut's programmed feed.
pub(super) fn mean_resultant_n(p: &MillParameters, depth_mm: f64, material: Material) -> f64 {
    let feed_per_tooth = p.feed_mm_min / (f64::from(p.cutter.teeth) * p.spindle_rpm);
    let f = mean_forces(
        &p.cutter,
        &material.coefficients(),
        &Immersion::new(p.mode, p.width_mm, p.cutter.diameter_mm),
        depth_mm,
        feed_per_tooth,
    );
    math::hypot(f.fx_n, f.fy_n)
}

impl MillParameters {
    /// The force target in newtons.
    pub fn target_force_n(&self) -> f64 {
        match self.target {
            ForceTarget::Given(force_n) => force_n,
            ForceTarget::MeanResultantAt { depth_mm, material } => {
                mean_resultant_n(self, depth_mm, material)
            }
        }
    }

    /// The scenario's plain specification, named `name`.
    pub fn scenario_spec(&self, name: &str) -> ScenarioSpec {
        ScenarioSpec {
            name: name.to_string(),
            start_mm: self.start_mm,
            moves: self
                .path
                .iter()
                .map(|&(end_mm, kind)| Move {
                    end_mm,
                    kind,
                    feed_mm_min: self.feed_mm_min,
                    spindle_rpm: self.spindle_rpm,
                })
                .collect(),
            cutter: self.cutter,
            mode: self.mode,
            depth_mm: self.depth_mm.to_vec(),
            width_mm: vec![(0.0, self.width_mm)],
            materials: self
                .materials
                .iter()
                .map(|&(from_mm, to_mm, material)| MaterialRegion {
                    from_mm,
                    to_mm,
                    material,
                })
                .collect(),
            spindle_start_dwell_s: 0.0,
        }
    }
}

/// A cutter without runout, for the definitions.
const fn end_mill(diameter_mm: f64, teeth: u32, helix_deg: f64) -> Cutter {
    Cutter {
        diameter_mm,
        teeth,
        helix_deg,
        runout_mm: 0.0,
        runout_angle_deg: 0.0,
    }
}

/// Paper 003's tool where it names one (Fig. 10), and cutlab's choice where it does not.
const KIM_CUTTER: Cutter = end_mill(20.0, 2, 30.0);

/// Paper 003 (Kim, Kwon, Chu) Fig. 10: depth steps 1 → 5 mm in SM45C.
pub(super) static KIM_STEP_DOC: Definition = Definition {
    name: "kim-step-doc",
    label: "Depth steps 1→5 mm, SM45C",
    source: "paper 003 (Kim, Kwon, Chu), Fig. 10",
    choices: &[
        "slot (full immersion, as eq 4-6 assume)",
        "feed 200 mm/min (0.1 mm/tooth; Fig. 5 spans 30-500 mm/min)",
        "30° helix",
        "each depth step 30 mm long, 15 mm air approach and exit",
        "target force: mean resultant at DOC 2.5 mm (control started at 3 mm)",
        "override 0-255 % in 1 % steps (the paper's DSP board)",
    ],
    override_mode: OverrideMode::WholePercent,
    plant: PlantDefinition::Mill(MillParameters {
        cutter: KIM_CUTTER,
        mode: MillingMode::Slot,
        width_mm: 20.0,
        spindle_rpm: 1000.0,
        feed_mm_min: 200.0,
        start_mm: [-15.0, 0.0],
        path: &[([165.0, 0.0], MoveKind::Line)],
        depth_mm: &[
            (15.0, 1.0),
            (45.0, 1.0),
            (45.0, 2.0),
            (75.0, 2.0),
            (75.0, 3.0),
            (105.0, 3.0),
            (105.0, 4.0),
            (135.0, 4.0),
            (135.0, 5.0),
        ],
        materials: &[(15.0, 165.0, Material::Sm45c)],
        target: ForceTarget::MeanResultantAt {
            depth_mm: 2.5,
            material: Material::Sm45c,
        },
        second_order_equivalent: false,
    }),
};

/// Paper 003 Fig. 11: a taper across SM45C then aluminium.
pub(super) static KIM_MATERIAL_TAPER: Definition = Definition {
    name: "kim-material-taper",
    label: "Taper across SM45C → aluminium",
    source: "paper 003 (Kim, Kwon, Chu), Fig. 11",
    choices: &[
        "Ø20 mm 2-flute carbide end mill with 30° helix (Fig. 11 gives no tool)",
        "slot",
        "120 mm block: 60 mm SM45C then 60 mm aluminium 7050",
        "taper 1 → 4 mm linear over the whole block",
        "target force: mean resultant at DOC 2 mm in SM45C",
        "override 0-255 % in 1 % steps",
    ],
    override_mode: OverrideMode::WholePercent,
    plant: PlantDefinition::Mill(MillParameters {
        cutter: KIM_CUTTER,
        mode: MillingMode::Slot,
        width_mm: 20.0,
        spindle_rpm: 600.0,
        feed_mm_min: 160.0,
        start_mm: [-15.0, 0.0],
        path: &[([135.0, 0.0], MoveKind::Line)],
        depth_mm: &[(15.0, 1.0), (135.0, 4.0)],
        materials: &[(15.0, 135.0, Material::Composite)],
        target: ForceTarget::MeanResultantAt {
            depth_mm: 2.0,
            material: Material::Sm45c,
        },
        second_order_equivalent: false,
    }),
};

/// The circular taper's circle: radius, and where it starts along the path (B, after 15 mm of
/// air and the 30 mm line A→B).
const CIRCLE_RADIUS_MM: f64 = 20.0;
const CIRCLE_START_MM: f64 = 45.0;
const HALF_CIRCLE_MM: f64 = PI * CIRCLE_RADIUS_MM;

/// Paper 003 Fig. 12–13: a line at DOC 2 mm, then a circle with DOC 2 → 5 → 2 mm.
pub(super) static KIM_CIRCULAR_TAPER: Definition = Definition {
    name: "kim-circular-taper",
    label: "Circular taper 2→5→2 mm",
    source: "paper 003 (Kim, Kwon, Chu), Fig. 12-13",
    choices: &[
        "Ø20 mm 2-flute carbide end mill with 30° helix, SM45C",
        "slot along the whole path",
        "A→B 30 mm (after 15 mm of air), circle of radius 20 mm about B + (20, 0) mm, clockwise: B→C then C→B",
        "a 90° corner at B, so the axes stop (in-position check) as in Fig. 13's dip",
        "depth 2 → 5 mm linear over B→C, 5 → 2 mm over C→B",
        "target force: mean resultant at DOC 3 mm",
        "override 0-255 % in 1 % steps",
    ],
    override_mode: OverrideMode::WholePercent,
    plant: PlantDefinition::Mill(MillParameters {
        cutter: KIM_CUTTER,
        mode: MillingMode::Slot,
        width_mm: 20.0,
        spindle_rpm: 3000.0,
        feed_mm_min: 170.0,
        start_mm: [-45.0, 0.0],
        path: &[
            ([0.0, 0.0], MoveKind::Line),
            (
                [2.0 * CIRCLE_RADIUS_MM, 0.0],
                MoveKind::Arc {
                    center_mm: [CIRCLE_RADIUS_MM, 0.0],
                    clockwise: true,
                },
            ),
            (
                [0.0, 0.0],
                MoveKind::Arc {
                    center_mm: [CIRCLE_RADIUS_MM, 0.0],
                    clockwise: true,
                },
            ),
        ],
        depth_mm: &[
            (CIRCLE_START_MM, 2.0),
            (CIRCLE_START_MM + HALF_CIRCLE_MM, 5.0),
            (CIRCLE_START_MM + 2.0 * HALF_CIRCLE_MM, 2.0),
        ],
        materials: &[(
            15.0,
            CIRCLE_START_MM + 2.0 * HALF_CIRCLE_MM,
            Material::Sm45c,
        )],
        target: ForceTarget::MeanResultantAt {
            depth_mm: 3.0,
            material: Material::Sm45c,
        },
        second_order_equivalent: false,
    }),
};

/// Paper 001's three experiments differ only in depth and target.
const fn maneerat(
    name: &'static str,
    label: &'static str,
    source: &'static str,
    depth_mm: &'static [(f64, f64)],
    target_force_n: f64,
) -> Definition {
    Definition {
        name,
        label,
        source,
        choices: &[
            "4 flutes, 30° helix",
            "hardened tool steel coefficients for the printed 'SKD41'",
            "down milling at 3 mm radial width",
            "programmed feed 900 mm/min (0.075 mm/tooth), above target at every depth",
            "120 mm cut after 40 mm of air: the approach outlasts the 3 s arming delay, as a part \
             program's would, so the loop is armed before the tool enters",
            "continuous override (the paper's D/A card)",
        ],
        override_mode: OverrideMode::Continuous,
        plant: PlantDefinition::Mill(MillParameters {
            cutter: end_mill(10.0, 4, 30.0),
            mode: MillingMode::Down,
            width_mm: 3.0,
            spindle_rpm: 3000.0,
            feed_mm_min: 900.0,
            start_mm: [-40.0, 0.0],
            path: &[([120.0, 0.0], MoveKind::Line)],
            depth_mm,
            materials: &[(40.0, 160.0, Material::ToolSteel)],
            // The paper prints the targets in "Nm"; they are forces.
            target: ForceTarget::Given(target_force_n),
            second_order_equivalent: true,
        }),
    }
}

/// Paper 001 (Maneerat et al.) Fig. 7.
pub(super) static MANEERAT_DOC_1: Definition = maneerat(
    "maneerat-doc-1",
    "Tool steel, DOC 1 mm, target 150 N",
    "paper 001 (Maneerat et al.), Fig. 7",
    &[(0.0, 1.0)],
    150.0,
);

/// Paper 001 Fig. 8.
pub(super) static MANEERAT_DOC_2: Definition = maneerat(
    "maneerat-doc-2",
    "Tool steel, DOC 2 mm, target 200 N",
    "paper 001 (Maneerat et al.), Fig. 8",
    &[(0.0, 2.0)],
    200.0,
);

/// Paper 001 Fig. 9.
pub(super) static MANEERAT_DOC_4: Definition = maneerat(
    "maneerat-doc-4",
    "Tool steel, DOC 4 mm, target 320 N",
    "paper 001 (Maneerat et al.), Fig. 9",
    &[(0.0, 4.0)],
    320.0,
);

/// Paper 001's own process model (eq 2.3) on Fig. 8's cut, with the force measured by a
/// dynamometer as the paper's experiments measure it.
pub(super) static MANEERAT_SECOND_ORDER: Definition = {
    let doc_2 = maneerat(
        "maneerat-second-order",
        "Paper 001's model: eq 2.3, DOC 2 mm, target 200 N",
        "paper 001 (Maneerat et al.), eq 2.1–2.3 and Fig. 8",
        &[(0.0, 2.0)],
        200.0,
    );
    let PlantDefinition::Mill(cut) = doc_2.plant else {
        unreachable!()
    };
    Definition {
        choices: &[
            "the process of eq 2.3: m·F̈ + (mc + d)·Ḟ + dc·F = k·f_r with f_r the commanded feed",
            "its static gain the mechanistic model's mean resultant force per mm/min on Fig. 8's \
             cut (tool steel, DOC 2 mm, 3 mm wide, 3000 rpm), zero in the 40 mm of air",
            "τ_f = 1/K_v (the position loop) and τ_c = one spindle revolution (20 ms)",
            "the force fed back by a dynamometer under the part (500 Hz, σ 2 N), as in the \
             paper's experiments",
            "continuous override (the paper's D/A card)",
        ],
        plant: PlantDefinition::SecondOrder(cut),
        ..doc_2
    }
};

/// Paper 002 (Liu, Wang, Wang) Fig. 7: the bond-graph plant and a step in load.
pub(super) static LIU_CURRENT_STEP: Definition = Definition {
    name: "liu-current-step",
    label: "Bond-graph plant, load step",
    source: "paper 002 (Liu, Wang, Wang), eq 5, Table 1, Fig. 7",
    choices: &[
        "eq 5 on a machining centre: Table 1's voltages, resistances, x-axis inertia, stiffness, \
         mass and damping; a 2.4 N·m/A spindle motor (1500 rpm at 380 V, J 0.1 kg·m², drag \
         0.03 N·m·s/rad), a 1.2 N·m/A x-axis servo on a 10 mm-lead screw, 5 mH armatures, m_s = 0 \
         (spindle and table meet in the cut)",
        "the cut: a Ø50 mm 5-insert face mill climb-milling SM45C 40 mm wide at 0.2 mm per tooth, \
         mean chip forces without edge forces, at the depth where the spindle draws the 25 A \
         reference at 1500 mm/min",
        "the load step: the depth +40 % at 15 s (a setting: paper 002 gives no size); 40 s run",
        "the control smooths the commanded feed with Table 1's x-axis time constant \
         L_q2/R_s2 = 0.57 s (exponential acceleration/deceleration), keeping eq 5's ~3 s response",
        "spindle at speed from t = 0 (eq 5's steady state, table still), feed after 3 s",
        "S_e2 set for the smoothed commanded feed in steady state",
        "continuous override",
        "the fuzzy controllers at the paper's scalings: k_u's 100 % of the feed added each period \
         (eq 1), let through by the envelope's rate limit, and EC read in A/s (Table 2)",
        "Table 2's 0.05 s spacing as the control period (the paper states none)",
    ],
    override_mode: OverrideMode::Continuous,
    plant: PlantDefinition::BondGraph {
        target_spindle_current_a: PAPER_002_REFERENCE_CURRENT_A,
    },
};

/// Paper 000 (Wang, Ai, Ze, He) §4: the magnetic-particle brake bench.
pub(super) static WANG_BRAKE_BENCH: Definition = Definition {
    name: "wang-brake-bench",
    label: "Brake bench, excitation steps",
    source: "paper 000 (Wang, Ai, Ze, He), section 4, Fig. 5, 9, 11, 12",
    choices: &[
        "feed 600 mm/min: 4 Hz electrical frequency with a 10 mm screw and 4 pole pairs",
        "brake 2 N·m/A, hysteresis ±0.03 A",
        "excitation 0 → 1 A → 0 in 0.1 A steps of 3 s",
        "override on the 16-position dial (paper 000's X20.7/X20.4/X20.3/X20.2)",
    ],
    override_mode: OverrideMode::Dial(DialTable::FANUC),
    plant: PlantDefinition::BrakeBench,
};
