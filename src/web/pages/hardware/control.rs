//! The run on the machine: the preset whose settings it takes (following the program the device
//! names), the controller, the target and safety envelope, the host's own safety, the signal
//! chain (rows of the run definition and the host's table) and the calibration.

use leptos::prelude::*;

use super::calibration::CalibrationFieldset;
use super::HardwareState;
use crate::closed_loop::definition::RunSetting;
use crate::hardware::host_settings::HostSetting;
use crate::input::table::Table;
use crate::plant::Preset;
use crate::web::components::fields::SelectField;
use crate::web::components::run_form::{ControllerFields, SettingFields};
use crate::web::components::table_form::SettingField;

/// The settings of the run shown in the Control panel, in order.
const RUN_SETTINGS: [RunSetting; 6] = [
    RunSetting::TargetForce,
    RunSetting::Feedback,
    RunSetting::MinOverride,
    RunSetting::MaxOverride,
    RunSetting::MaxRate,
    RunSetting::ArmingOverride,
];
const SIGNAL_SETTINGS: [RunSetting; 4] = [
    RunSetting::ControlPeriod,
    RunSetting::FilterOrder,
    RunSetting::SpindleCutoff,
    RunSetting::FeedCutoff,
];

/// The Control panel.
#[component]
pub fn ControlPanel(shared: HardwareState) -> impl IntoView {
    let HardwareState {
        scenario,
        controller,
        host,
        host_errors,
        options_error,
        station,
        ui,
        ..
    } = shared;
    view! {
        <form class="panel" aria-label="Control" on:submit=|ev| ev.prevent_default()>
            <fieldset>
                <legend>"Run settings"</legend>
                <SelectField
                    id="preset"
                    label="Preset (the run's settings)"
                    options=Preset::ALL.iter().map(|p| (p.name(), p.label())).collect()
                    value=scenario.preset
                />
                <p class="hint">"Follows the program the device names, as cutlab host does."</p>
            </fieldset>
            <ControllerFields form=controller />
            <SettingFields form=scenario legend="Target and safety envelope" settings=RUN_SETTINGS.to_vec() />
            <fieldset>
                <legend>"Host safety"</legend>
                {HostSetting::ROWS
                    .iter()
                    .map(|s| view! { <SettingField form=host setting=*s errors=host_errors id_prefix="hw-" /> })
                    .collect_view()}
                {move || options_error.get().map(|e| view! { <p class="field-error" role="alert">{e}</p> })}
            </fieldset>
            <SettingFields form=scenario legend="Signal chain" settings=SIGNAL_SETTINGS.to_vec() />
            <CalibrationFieldset station=station ui=ui />
        </form>
    }
}
