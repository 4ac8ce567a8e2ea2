//! The sixteen quantities only a simulation knows, in the order the serial protocol sends them:
//! one list for the plant's truth at full precision ([`crate::machine::PlantTruth`], f64) and
//! the wire's ([`crate::protocol::frame::SimTruth`], f32), which convert through it.
//!
//! The lowest layer, so that both the machine (below the protocol) and the protocol's codec can
//! use it; the codec a bridge's firmware compiles without `std` includes this file as it is
//! (`tests/no_std/lib.rs`), so it uses nothing else.

/// How many values a simulation's truth carries.
pub const TRUTH_VALUES: usize = 16;

/// Calls `$then!` with the truth's field names in wire order (a field's name is also its name in
/// JSON, in `SimTruth::NAMES` and in `PlantTruth`'s serialisation). A struct literal built from
/// the list names every field, so the compiler refuses a struct that has a field more or less.
macro_rules! in_wire_order {
    ($then:ident) => {
        $then! {
            force_x_n,
            force_y_n,
            force_z_n,
            force_resultant_n,
            feed_force_n,
            spindle_torque_nm,
            cutting_power_w,
            depth_mm,
            width_mm,
            feed_per_tooth_mm,
            path_position_mm,
            material_removal_mm3_s,
            tool_x_mm,
            tool_y_mm,
            feed_current_rms_a,
            spindle_current_rms_a,
        }
    };
}
pub(crate) use in_wire_order;
