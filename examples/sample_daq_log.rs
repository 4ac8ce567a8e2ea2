//! Writes a synthetic DAQ log of the simulated machine to standard output: a teach cut of paper
//! 001's DOC 2 mm cut (maneerat-doc-2, seed 5: the override stepped through 100, 30, 140 and
//! 60 %, 1.5 s each, so the load varies), its first 12 s, recorded the way a data-acquisition box
//! would log it at 1 kHz — the spindle's three phase currents, its speed, the feed, the override,
//! a dynamometer's resultant force and a machining-phase label, with time in milliseconds.
//!
//! Each 1 kHz row is the mean of ten 10 kHz samples (the DAQ's anti-alias averaging). It is made
//! by the simulator, not a machine: `scripts/sample-logs` writes it to
//! `www/data/synthetic-maneerat-doc-2-daq.csv`.
//!
//! ```text
//! cargo run --release --example sample_daq_log > www/data/synthetic-maneerat-doc-2-daq.csv
//! ```

use std::cell::RefCell;
use std::error::Error;
use std::io::Write;
use std::rc::Rc;

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::preset_plan;
use cutlab::closed_loop::sample_loop::OnMachine;
use cutlab::closed_loop::teach_cut::TeachForce;
use cutlab::control::registry::ControllerKind;
use cutlab::machine::{Machine, MachineStep, OverrideCommand};
use cutlab::plant::Preset;
use cutlab::work::Work;

/// A machine that keeps every step it returns.
struct Recorder {
    inner: Box<dyn Machine>,
    steps: Rc<RefCell<Vec<MachineStep>>>,
}

impl Machine for Recorder {
    fn sample_rate_hz(&self) -> f64 {
        self.inner.sample_rate_hz()
    }
    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        let step = self.inner.step(command);
        self.steps.borrow_mut().push(step);
        step
    }
    fn finished(&self) -> bool {
        self.inner.finished()
    }
}

/// Samples averaged into one row.
const BLOCK: usize = 10;

fn main() -> Result<(), Box<dyn Error>> {
    let mut spec = RunSpec::new(Preset::ManeeratDoc2, ControllerKind::Fixed);
    spec.seed = 5;
    let mut plan = preset_plan(&spec)?;
    // A 12 s capture: the approach in air, the entry, the cut at four overrides.
    plan.max_duration_s = 12.0;
    let steps = Rc::new(RefCell::new(Vec::new()));
    let machine = Recorder {
        inner: Box::new(spec.preset.machine_with(spec.seed, &spec.plant)?),
        steps: steps.clone(),
    };
    OnMachine::teach_cut(Box::new(machine), &plan, TeachForce::SimulationTruth)?.run_to_end()?;
    let out = std::io::stdout();
    let mut out = std::io::BufWriter::new(out.lock());
    writeln!(
        out,
        "Time [ms],S_I_U [A],S_I_V [A],S_I_W [A],S_speed [rpm],X_feed [mm/min],Override [%],F [N],Phase"
    )?;
    for block in steps.borrow().chunks_exact(BLOCK) {
        let n = BLOCK as f64;
        let mean = |f: &dyn Fn(&MachineStep) -> f64| block.iter().map(f).sum::<f64>() / n;
        let last = block[BLOCK - 1];
        let depth = mean(&|s| s.truth.map_or(0.0, |t| t.depth_mm));
        writeln!(
            out,
            "{:.0},{:.2},{:.2},{:.2},{:.1},{:.1},{:.1},{:.1},{}",
            last.sensors.time_s * 1000.0,
            mean(&|s| s.sensors.spindle_phase_currents_a[0]),
            mean(&|s| s.sensors.spindle_phase_currents_a[1]),
            mean(&|s| s.sensors.spindle_phase_currents_a[2]),
            mean(&|s| s.sensors.spindle_speed_rpm),
            mean(&|s| s.sensors.feed_mm_min),
            last.sensors.applied_override_pct,
            mean(&|s| s.truth.map_or(f64::NAN, |t| t.force_resultant_n)),
            if depth > 0.0 { "Cut" } else { "Air" }
        )?;
    }
    Ok(())
}
