//! Any preset's machine behind one type: one match per block of samples.

use crate::machine::{BlockStep, Machine, MachineStep, OverrideCommand, SensorlessEstimate};
use crate::plant::bench::BrakeBench;
use crate::plant::bond_graph::BondGraphMachine;
use crate::plant::scenario::Scenario;
use crate::plant::second_order::SecondOrderMachine;
use crate::plant::signals::PlantSignals;
use crate::plant::simulator::Simulator;
use crate::plant::Plant;

/// Any preset's machine.
#[derive(Debug, Clone)]
pub enum PresetMachine {
    /// The full mill.
    Mill(Box<Simulator>),
    /// The brake bench.
    BrakeBench(Box<BrakeBench>),
    /// The bond graph.
    BondGraph(Box<BondGraphMachine>),
    /// Paper 001's second-order process.
    SecondOrder(Box<SecondOrderMachine>),
}

impl PresetMachine {
    fn plant(&self) -> &dyn Plant {
        match self {
            PresetMachine::Mill(m) => m.as_ref(),
            PresetMachine::BrakeBench(m) => m.as_ref(),
            PresetMachine::BondGraph(m) => m.as_ref(),
            PresetMachine::SecondOrder(m) => m.as_ref(),
        }
    }

    fn plant_mut(&mut self) -> &mut dyn Plant {
        match self {
            PresetMachine::Mill(m) => m.as_mut(),
            PresetMachine::BrakeBench(m) => m.as_mut(),
            PresetMachine::BondGraph(m) => m.as_mut(),
            PresetMachine::SecondOrder(m) => m.as_mut(),
        }
    }

    /// The scenario, for a mill.
    pub fn scenario(&self) -> Option<&Scenario> {
        match self {
            PresetMachine::Mill(m) => Some(m.scenario()),
            _ => None,
        }
    }
}

impl Machine for PresetMachine {
    fn sample_rate_hz(&self) -> f64 {
        self.plant().sample_rate_hz()
    }

    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        self.plant_mut().step(command)
    }

    fn finished(&self) -> bool {
        self.plant().finished()
    }

    fn sensorless_force(&self) -> Option<SensorlessEstimate> {
        self.plant().sensorless_force()
    }

    fn step_block(&mut self, command: OverrideCommand, out: &mut [BlockStep]) -> usize {
        // One match per block; each plant's own loop inlines its step.
        match self {
            PresetMachine::Mill(m) => m.step_block(command, out),
            PresetMachine::BrakeBench(m) => m.step_block(command, out),
            PresetMachine::BondGraph(m) => m.step_block(command, out),
            PresetMachine::SecondOrder(m) => m.step_block(command, out),
        }
    }
}

impl Plant for PresetMachine {
    fn signals(&self) -> &PlantSignals {
        self.plant().signals()
    }

    fn reset(&mut self) {
        self.plant_mut().reset();
    }
}
