//! The forms that define a run: the scenario (the preset and the run definition's settings,
//! rendered from the core's table by [`SettingField`]) and a controller with its parameters. Both
//! keep the typed text and turn it into the core's validated types, with one message per field;
//! both read from and write to the URL query.

use std::collections::BTreeMap;

use leptos::prelude::*;

use crate::closed_loop::config::RunConfiguration;
use crate::closed_loop::definition::{
    parse_texts, RunSetting, RunSpec, SettingGroup, SettingsOverrides,
};
use crate::closed_loop::lab::preset_plan;
use crate::closed_loop::paper_defaults::{preset_controller, preset_parameter};
use crate::control::fuzzy::fll;
use crate::control::fuzzy::rules::RuleTable;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::input::table::Table;
use crate::plant::presets::PlantEdits;
use crate::plant::Preset;
use crate::web::components::fields::{parse_number, NumberField, SelectField};
use crate::web::components::paper_link::WithPaperLinks;
use crate::web::components::table_form::{self, FieldErrors, Placeholders, TableForm};
use crate::web::js::read_chosen_file;

/// Text of the scenario fields: the preset, and every setting of the run definition
/// ([`RunSetting::ALL`]), each parsed and checked by the core's table, so the form accepts exactly
/// what the command line and a saved configuration accept.
#[derive(Clone, Copy)]
pub struct ScenarioForm {
    /// Preset name.
    pub preset: RwSignal<String>,
    /// The typed text of each setting.
    settings: TableForm<RunSetting>,
    /// The fields parsed, once per change for every reader (the page's run and each fieldset's
    /// messages), instead of once per reader.
    parsed: Memo<ParsedScenario>,
    /// What each blank field resolves to on the chosen preset: the run's plan, as text.
    planned: Memo<Placeholders>,
}

/// A parsed scenario form: the choice, or the message of each field that did not parse.
type ParsedScenario = Result<ScenarioChoice, FieldErrors>;

/// The preset a fresh form shows.
const DEFAULT_PRESET: &str = "kim-step-doc";

/// A parsed scenario, or the message of each field that did not parse.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioChoice {
    /// The preset.
    pub preset: Preset,
    /// The seed.
    pub seed: u64,
    /// Setting overrides.
    pub settings: SettingsOverrides,
    /// Machine and cut edits.
    pub plant: PlantEdits,
}

impl ScenarioForm {
    /// A form with the defaults, then whatever `query` says.
    pub fn new(query: &[(String, String)]) -> Self {
        let typed = |key: &str| query.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone());
        let preset = RwSignal::new(typed("preset").unwrap_or_else(|| DEFAULT_PRESET.to_string()));
        let settings = TableForm::new(query);
        let parsed = Memo::new(move |_| parse_scenario(preset, settings));
        Self {
            preset,
            settings,
            parsed,
            planned: Memo::new(move |_| planned_texts(&preset.get(), parsed.get().ok())),
        }
    }

    /// The text signal of `setting`.
    pub fn text(&self, setting: RunSetting) -> RwSignal<String> {
        self.settings.text(setting)
    }

    /// Every field back to its default, on `preset`: a one-click experiment starts from the
    /// paper's own values, not from edits made for another preset.
    pub fn reset_to(&self, preset: Preset) {
        self.settings.reset();
        self.preset.set(preset.name().to_string());
    }

    /// Shows `spec`'s preset and settings: each setting the spec changes as the text that reads
    /// back as its value, every other at its default (blank: the preset's).
    pub fn load(&self, spec: &RunSpec) {
        self.preset.set(spec.preset.name().to_string());
        for setting in RunSetting::ALL {
            let text = setting
                .value_in(spec)
                .map_or_else(|| setting.row().default_text(), |v| v.text());
            self.text(setting).set(text);
        }
    }

    /// The query pairs that reproduce this form; the seed always, so a shared link keeps it
    /// whatever the default becomes.
    pub fn query(&self) -> Vec<(String, String)> {
        let seed = RunSetting::Seed.row().key;
        let mut query = vec![("preset".to_string(), self.preset.get())];
        if !self.settings.query().iter().any(|(k, _)| k == seed) {
            query.push((seed.to_string(), self.text(RunSetting::Seed).get()));
        }
        query.extend(self.settings.query());
        query
    }

    /// The fields parsed through the run definition ([`parse_texts`], as the command line
    /// does); errors are keyed by the setting's query key. Tracked.
    pub fn parse(&self) -> ParsedScenario {
        self.parsed.get()
    }

    /// The message of each field that did not parse (tracked).
    fn errors(&self) -> Signal<FieldErrors> {
        let form = *self;
        Signal::derive(move || form.parse().err().unwrap_or_default())
    }
}

/// What each field of a scenario form resolves to when left blank on `preset_name`, from the
/// run's plan ([`crate::closed_loop::settings::Plan::planned_text`]) for the other settings as
/// parsed (the preset's alone while a field is wrong). A field the form sets is planned without
/// its own value ([`RunSetting::apply`] with `None`), so a select's blank option ("The preset's")
/// names the preset's choice, not the one the user picked instead.
fn planned_texts(preset_name: &str, choice: Option<ScenarioChoice>) -> Placeholders {
    let Some(preset) = Preset::from_name(preset_name) else {
        return Placeholders::new();
    };
    // A closed loop: the target and the envelope as an adaptive controller sees them.
    let mut spec = RunSpec::new(preset, ControllerKind::Pi);
    if let Some(choice) = choice.filter(|c| c.preset == preset) {
        spec.seed = choice.seed;
        spec.settings = choice.settings;
        spec.plant = choice.plant;
    }
    let Ok(plan) = preset_plan(&spec) else {
        return Placeholders::new();
    };
    RunSetting::ALL
        .into_iter()
        .filter_map(|s| {
            let text = if s != RunSetting::Seed && s.value_in(&spec).is_some() {
                let mut blank = spec.clone();
                s.apply(&mut blank, None);
                preset_plan(&blank).ok()?.planned_text(s, &blank)
            } else {
                plan.planned_text(s, &spec)
            };
            Some((s.spec().query_key, text?))
        })
        .collect()
}

/// Parses a scenario form's fields (see [`ScenarioForm::parse`]).
fn parse_scenario(preset: RwSignal<String>, settings: TableForm<RunSetting>) -> ParsedScenario {
    let Some(preset) = Preset::from_name(&preset.get()) else {
        return Err(BTreeMap::from([("preset", "choose a preset".to_string())]));
    };
    // The machine fields are hidden for presets without a mill; what they hold then must
    // neither block the run nor change it.
    let has_mill = preset.scenario().is_some();
    let texts: Vec<(RunSetting, String)> = settings
        .texts()
        .into_iter()
        .filter(|(setting, _)| has_mill || setting.spec().group != SettingGroup::Machine)
        .collect();
    match parse_texts(preset, ControllerConfig::new(ControllerKind::Fixed), &texts) {
        Ok(spec) => Ok(ScenarioChoice {
            preset,
            seed: spec.seed,
            settings: spec.settings,
            plant: spec.plant,
        }),
        Err(errors) => Err(errors
            .into_iter()
            .map(|e| (e.setting.spec().query_key, e.problem.to_string()))
            .collect()),
    }
}

/// The fields of `settings`, in order.
fn setting_fields(form: ScenarioForm, settings: impl Iterator<Item = RunSetting>) -> impl IntoView {
    let planned = form.planned;
    view! {
        <table_form::SettingFields
            form=form.settings
            settings=settings.collect()
            errors=form.errors()
            placeholders=Signal::derive(move || planned.get())
        />
    }
}

/// The fields of one group of settings.
fn group_fields(form: ScenarioForm, group: SettingGroup) -> impl IntoView {
    setting_fields(
        form,
        RunSetting::ALL
            .into_iter()
            .filter(move |s| s.spec().group == group),
    )
}

/// The scenario fields.
#[component]
pub fn ScenarioFields(form: ScenarioForm) -> impl IntoView {
    let summary = move || {
        Preset::from_name(&form.preset.get()).map(|p| {
            let s = p.summary();
            // The full title first: a narrow select cuts it.
            let mut parts = vec![p.label().to_string(), p.source().to_string()];
            if let Some(t) = s.tool {
                parts.push(t);
            }
            if let Some(m) = s.material {
                parts.push(m);
            }
            if let Some(rpm) = s.spindle_rpm {
                parts.push(format!("{rpm:.0} rpm"));
            }
            if let Some(f) = s.programmed_feed_mm_min {
                parts.push(format!("{f:.0} mm/min"));
            }
            if let Some(t) = s.target_force_n {
                parts.push(format!("target {t:.0} N"));
            }
            parts.join(" · ")
        })
    };
    view! {
        <fieldset>
            <legend>"Scenario"</legend>
            <SelectField
                id="preset"
                label="Preset"
                options=Preset::ALL.iter().map(|p| (p.name(), p.label())).collect()
                value=form.preset
            />
            <p class="hint">{move || summary().map(|text| view! { <WithPaperLinks text=text /> })}</p>
            {group_fields(form, SettingGroup::Scenario)}
        </fieldset>
    }
}

/// Chosen settings of a scenario form, in a fieldset of their own (the Hardware page shows the
/// run's target, safety envelope and signal chain, but no machine edits: the machine is real).
#[component]
pub fn SettingFields(
    form: ScenarioForm,
    /// The fieldset's legend.
    legend: &'static str,
    /// The settings, in order.
    settings: Vec<RunSetting>,
) -> impl IntoView {
    view! {
        <fieldset>
            <legend>{legend}</legend>
            {setting_fields(form, settings.into_iter())}
        </fieldset>
    }
}

/// The machine, cut and signal-chain fields of a scenario form (shown after the controller).
#[component]
pub fn MachineAndSignalFields(form: ScenarioForm) -> impl IntoView {
    view! {
        <fieldset hidden=move || {
            Preset::from_name(&form.preset.get()).is_none_or(|p| p.scenario().is_none())
        }>
            <legend>"Machine and cut (blank: the preset's)"</legend>
            {group_fields(form, SettingGroup::Machine)}
        </fieldset>
        <fieldset>
            <legend>"Signal chain"</legend>
            {group_fields(form, SettingGroup::SignalChain)}
        </fieldset>
    }
}

/// Text of a controller choice and its parameters; the text of every controller's parameters is
/// kept, so switching away and back loses nothing.
#[derive(Clone, Copy)]
pub struct ControllerForm {
    /// Controller name.
    pub kind: RwSignal<String>,
    /// Parameter text by (controller, key).
    pub values: RwSignal<BTreeMap<(String, String), String>>,
    /// Prefix of element ids, so several forms can share a page.
    pub id_prefix: &'static str,
    /// A rule table from the Fuzzy rules page, used by the fuzzy controllers.
    pub rule_table: RwSignal<Option<RuleTable>>,
    /// The `fuzzy-engine` controller's engine as FLL (its default, paper 002's dynamics table,
    /// when `None`): imported here or carried from the Fuzzy rules page in the URL
    /// ([`fll::to_url_text`]).
    pub engine: RwSignal<Option<String>>,
    /// The preset whose defaults the untouched parameters show (a paper's own values on its
    /// preset, [`preset_controller`]).
    preset: RwSignal<Preset>,
}

/// The text of `key`'s default for `kind` on `preset`.
fn default_text(preset: Preset, kind: ControllerKind, key: &str) -> String {
    preset_parameter(preset, kind, key).map_or_else(String::new, |v| v.to_string())
}

/// A rule table as 49 digits 0–6 (level + 3), row by row, for URLs.
pub fn encode_rule_table(table: &RuleTable) -> String {
    table
        .iter()
        .flatten()
        .map(|l| char::from(b'0' + (l + 3).clamp(0, 6) as u8))
        .collect()
}

/// The table of [`encode_rule_table`]'s text, if it is one.
pub fn decode_rule_table(text: &str) -> Option<RuleTable> {
    let digits: Vec<i8> = text
        .chars()
        .map(|c| c.to_digit(10).filter(|d| *d <= 6).map(|d| d as i8 - 3))
        .collect::<Option<_>>()?;
    if digits.len() != 49 {
        return None;
    }
    let mut table = [[0i8; 7]; 7];
    for (cell, d) in table.iter_mut().flatten().zip(digits) {
        *cell = d;
    }
    Some(table)
}

/// Whether the controller named `kind` runs an imported engine.
fn runs_engine(kind: &str) -> bool {
    kind.parse::<ControllerKind>() == Ok(ControllerKind::FuzzyEngine)
}

/// Whether the controller named `kind` takes a rule table.
fn is_fuzzy(kind: &str) -> bool {
    matches!(
        kind.parse::<ControllerKind>(),
        Ok(ControllerKind::FuzzyExperience | ControllerKind::FuzzyDynamics)
    )
}

impl ScenarioForm {
    /// The preset chosen now, if the name is one (tracked).
    pub fn chosen_preset(&self) -> Option<Preset> {
        Preset::from_name(&self.preset.get())
    }

    /// The preset chosen now, or the default preset while the name is none (untracked).
    pub fn chosen_preset_untracked(&self) -> Preset {
        Preset::from_name(&self.preset.get_untracked())
            .or_else(|| Preset::from_name(DEFAULT_PRESET))
            .unwrap_or(Preset::ALL[0])
    }
}

impl ControllerForm {
    /// A form for `default_kind`, then whatever `query` says (`controller=pi&kp=0.4`); query keys
    /// are prefixed with `prefix` (e.g. `a.kp`) when several forms share a page.
    pub fn new(
        id_prefix: &'static str,
        default_kind: ControllerKind,
        preset: Preset,
        query: &[(String, String)],
        query_prefix: &str,
    ) -> Self {
        let get = |key: &str| {
            query
                .iter()
                .find(|(k, _)| k == &format!("{query_prefix}{key}"))
                .map(|(_, v)| v.clone())
        };
        let kind = get("controller")
            .filter(|k| k.parse::<ControllerKind>().is_ok())
            .unwrap_or_else(|| default_kind.name().to_string());
        let mut values = BTreeMap::new();
        for k in ControllerKind::ALL {
            for p in k.params() {
                values.insert(
                    (k.name().to_string(), p.key.to_string()),
                    default_text(preset, k, p.key),
                );
            }
        }
        if let Ok(k) = kind.parse::<ControllerKind>() {
            for p in k.params() {
                if let Some(v) = get(p.key) {
                    values.insert((k.name().to_string(), p.key.to_string()), v);
                }
            }
        }
        let rule_table = get("rules").and_then(|t| decode_rule_table(&t));
        // A damaged engine in a link is shown as the field's error by `parse`, not dropped.
        let engine = get("engine").map(|t| fll::from_url_text(&t));
        Self {
            kind: RwSignal::new(kind),
            values: RwSignal::new(values),
            id_prefix,
            rule_table: RwSignal::new(rule_table),
            engine: RwSignal::new(engine),
            preset: RwSignal::new(preset),
        }
    }

    /// `kind` with its default parameters and built-in rules.
    pub fn reset_to(&self, kind: ControllerKind) {
        let preset = self.preset.get_untracked();
        self.kind.set(kind.name().to_string());
        self.values.update(|values| {
            for p in kind.params() {
                values.insert(
                    (kind.name().to_string(), p.key.to_string()),
                    default_text(preset, kind, p.key),
                );
            }
        });
        self.rule_table.set(None);
        self.engine.set(None);
    }

    /// Shows `config` on `preset`: its controller, every parameter's value, its rule table and
    /// engine. The preset is followed first, so the page's following of the preset changes
    /// none of the values loaded.
    pub fn load(&self, config: &ControllerConfig, preset: Preset) {
        self.follow_preset(preset);
        let kind = config.kind().name().to_string();
        self.values.update(|values| {
            for (param, value) in config.values() {
                values.insert((kind.clone(), param.key.to_string()), value.to_string());
            }
        });
        self.kind.set(kind);
        self.rule_table.set(config.rule_table().copied());
        self.engine.set(config.engine_fll().map(str::to_string));
    }

    /// Follows a change of preset: every parameter still at the old preset's default takes the
    /// new one's (paper 002's k_u on its preset); what the user typed stays.
    pub fn follow_preset(&self, preset: Preset) {
        let old = self.preset.get_untracked();
        if old == preset {
            return;
        }
        self.values.update(|values| {
            for kind in ControllerKind::ALL {
                for p in kind.params() {
                    let key = (kind.name().to_string(), p.key.to_string());
                    if values.get(&key) == Some(&default_text(old, kind, p.key)) {
                        values.insert(key, default_text(preset, kind, p.key));
                    }
                }
            }
        });
        self.preset.set(preset);
    }

    /// Query pairs for the chosen controller and its non-default parameters.
    pub fn query(&self, query_prefix: &str) -> Vec<(String, String)> {
        let kind = self.kind.get();
        let mut q = vec![(format!("{query_prefix}controller"), kind.clone())];
        if let Some(table) = self.rule_table.get().filter(|_| is_fuzzy(&kind)) {
            q.push((format!("{query_prefix}rules"), encode_rule_table(&table)));
        }
        if let Some(engine) = self.engine.get().filter(|_| runs_engine(&kind)) {
            q.push((format!("{query_prefix}engine"), fll::to_url_text(&engine)));
        }
        if let Ok(k) = kind.parse::<ControllerKind>() {
            let preset = self.preset.get();
            self.values.with(|v| {
                for p in k.params() {
                    if let Some(text) = v.get(&(kind.clone(), p.key.to_string())) {
                        if text.trim() != default_text(preset, k, p.key) {
                            q.push((format!("{query_prefix}{}", p.key), text.clone()));
                        }
                    }
                }
            });
        }
        q
    }

    /// Parses the chosen controller's parameters; errors keyed by parameter.
    pub fn parse(&self) -> Result<ControllerConfig, BTreeMap<String, String>> {
        let kind_text = self.kind.get();
        let Ok(kind) = kind_text.parse::<ControllerKind>() else {
            return Err(BTreeMap::from([(
                "controller".to_string(),
                "choose a controller".to_string(),
            )]));
        };
        let mut config = preset_controller(self.preset.get(), kind);
        let mut errors = BTreeMap::new();
        self.values.with(|v| {
            for p in kind.params() {
                let text = v
                    .get(&(kind_text.clone(), p.key.to_string()))
                    .cloned()
                    .unwrap_or_default();
                match parse_number(&text) {
                    Ok(value) => {
                        if let Err(e) = config.set(p.key, value) {
                            errors.insert(p.key.to_string(), e.to_string());
                        }
                    }
                    Err(e) => {
                        errors.insert(p.key.to_string(), e);
                    }
                }
            }
        });
        if let Some(table) = self.rule_table.get().filter(|_| is_fuzzy(&kind_text)) {
            if let Err(e) = config.set_rule_table(table) {
                errors.insert("rules".to_string(), e.to_string());
            }
        }
        if let Some(engine) = self.engine.get().filter(|_| runs_engine(&kind_text)) {
            if let Err(e) = config.set_engine(&engine) {
                errors.insert(ENGINE_KEY.to_string(), e.to_string());
            }
        }
        if errors.is_empty() {
            Ok(config)
        } else {
            Err(errors)
        }
    }
}

/// The key of the engine's error among a controller form's errors.
const ENGINE_KEY: &str = "engine";

/// A `fuzzy-engine` controller's engine: how E, EC and U map onto it (the core's statement of
/// the mapping) and the file input to import another.
fn engine_fields(form: ControllerForm, errors: Memo<BTreeMap<String, String>>) -> impl IntoView {
    let mapping = move || match form.parse() {
        Ok(config) => config.engine_mapping().unwrap_or_default(),
        Err(_) => String::new(),
    };
    let error = move || {
        errors
            .with(|e| e.get(ENGINE_KEY).cloned())
            .map(|e| view! { <p class="run-error" role="alert">{e}</p> })
    };
    view! {
        <p class="hint engine-mapping">{mapping}</p>
        <EngineFile engine=form.engine id=format!("{}engine-file", form.id_prefix) />
        {error}
    }
}

/// A file input that imports an FLL or FIS engine into `engine` (as FLL), checked as the
/// `fuzzy-engine` controller checks it: a bad file keeps the engine there was and says why.
#[component]
pub fn EngineFile(
    /// The engine imported (`None`: paper 002's dynamics table).
    engine: RwSignal<Option<String>>,
    /// The file input's id.
    id: String,
) -> impl IntoView {
    let (import_error, set_import_error) = signal(None::<String>);
    let on_file = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |name, text| {
            let outcome = text.and_then(|text| {
                let mut config = ControllerConfig::new(ControllerKind::FuzzyEngine);
                config
                    .set_engine(&text)
                    .map_err(|e| format!("{name}: {e}"))?;
                Ok(config.engine_fll().map(str::to_string))
            });
            match outcome {
                Ok(imported) => {
                    set_import_error.set(None);
                    engine.set(imported);
                }
                Err(e) => set_import_error.set(Some(e)),
            }
        });
    };
    view! {
        <div class="field">
            <label for=id.clone()>"Engine file (FLL or FIS)"</label>
            <input id=id type="file" accept=".fll,.fis,text/plain" on:change=on_file />
        </div>
        {move || import_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
        {move || {
            engine.get().is_some().then(|| view! {
                <p class="hint">
                    <button type="button" on:click=move |_| engine.set(None)>
                        "Use paper 002's dynamics table as the engine"
                    </button>
                </p>
            })
        }}
    }
}

/// "Open configuration…": a file input that reads what "Configuration (JSON)" saves, through
/// the reader `cutlab sim --config` uses, and hands it to `load` (which shows it in the page's
/// forms, or says why it cannot). A file that cannot be read or loaded changes nothing and its
/// message names the file and the line or field.
#[component]
pub fn ConfigurationFile(
    /// The file input's id.
    id: &'static str,
    /// Shows the configuration, or says why not (before changing anything).
    load: Callback<RunConfiguration, Result<(), String>>,
) -> impl IntoView {
    let (message, set_message) = signal(None::<Result<String, String>>);
    let on_file = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |name, text| {
            let outcome = text
                .and_then(|text| RunConfiguration::from_json(&text).map_err(|e| e.to_string()))
                .and_then(|config| {
                    let runs = config.runs.len();
                    load.run(config)?;
                    Ok(format!(
                        "Opened {name} ({runs} run{}).",
                        if runs == 1 { "" } else { "s" }
                    ))
                })
                .map_err(|e| format!("{name}: {e} (nothing on the page was changed)"));
            set_message.set(Some(outcome));
        });
    };
    view! {
        <div class="field">
            <label for=id>"Open configuration…"</label>
            <input id=id type="file" accept=".json,application/json" on:change=on_file />
        </div>
        {move || {
            message
                .get()
                .map(|m| match m {
                    Ok(done) => view! { <p class="hint" role="status">{done}</p> }.into_any(),
                    Err(e) => view! { <p class="run-error" role="alert">{e}</p> }.into_any(),
                })
        }}
    }
}

/// The controller select and its parameter fields.
#[component]
pub fn ControllerFields(
    form: ControllerForm,
    /// Legend of the fieldset.
    #[prop(default = "Controller")]
    legend: &'static str,
) -> impl IntoView {
    let errors = Memo::new(move |_| form.parse().err().unwrap_or_default());
    let select_id = format!("{}controller", form.id_prefix);
    let fields = move || {
        let kind_text = form.kind.get();
        let Ok(kind) = kind_text.parse::<ControllerKind>() else {
            return ().into_any();
        };
        let custom_rules = form.rule_table.get().is_some() && is_fuzzy(&kind_text);
        view! {
            <p class="hint">{kind.source()}</p>
            {(kind == ControllerKind::FuzzyEngine).then(|| engine_fields(form, errors))}
            {custom_rules
                .then(|| {
                    view! {
                        <p class="hint">
                            "Using the rule table edited on the Fuzzy rules page. "
                            <button type="button" on:click=move |_| form.rule_table.set(None)>
                                "Use the built-in table"
                            </button>
                        </p>
                    }
                })}
            {kind
                .params()
                .iter()
                .map(|p| {
                    let key = (kind_text.clone(), p.key.to_string());
                    let text = RwSignal::new(
                        form.values.with_untracked(|v| v.get(&key).cloned().unwrap_or_default()),
                    );
                    let key_for_effect = key.clone();
                    // Only a changed text is written: the first run of the effect, as the field
                    // mounts, writes nothing, so the page's run and URL are not worked out twice.
                    Effect::new(move |_| {
                        let t = text.get();
                        let changed = form
                            .values
                            .with_untracked(|v| v.get(&key_for_effect) != Some(&t));
                        if changed {
                            form.values.update(|v| {
                                v.insert(key_for_effect.clone(), t);
                            });
                        }
                    });
                    let param_key = p.key.to_string();
                    let error = Signal::derive(move || errors.with(|e| e.get(&param_key).cloned()));
                    let id = format!("{}{}", form.id_prefix, p.key);
                    view! {
                        <NumberField id=id label=p.label.to_string() unit=p.unit value=text error=error help=p.help />
                    }
                })
                .collect_view()}
        }
        .into_any()
    };
    view! {
        <fieldset>
            <legend>{legend}</legend>
            <SelectField
                id=select_id
                label="Controller"
                options=ControllerKind::ALL.iter().map(|k| (k.name(), k.label())).collect()
                value=form.kind
            />
            {fields}
        </fieldset>
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A parsed form of `preset` with `texts` typed into its fields.
    fn choice(preset: Preset, texts: &[(RunSetting, &str)]) -> ScenarioChoice {
        let spec = parse_texts(preset, ControllerConfig::new(ControllerKind::Fixed), texts)
            .expect("the test's texts parse");
        ScenarioChoice {
            preset,
            seed: spec.seed,
            settings: spec.settings,
            plant: spec.plant,
        }
    }

    #[test]
    fn a_blank_field_names_the_presets_value_not_the_one_chosen_instead() {
        let preset = Preset::from_name("kim-step-doc").expect("a preset");
        let own = planned_texts(preset.name(), None);
        let key = |s: RunSetting| s.spec().query_key;
        let own_feedback = own[key(RunSetting::Feedback)].clone();
        let own_speed = own[key(RunSetting::SpindleSpeed)].clone();
        // The preset's own feedback is not the one chosen below, so the check can fail.
        assert_ne!(own_feedback, "feed");
        assert_ne!(own_speed, "5000");
        let chosen = planned_texts(
            preset.name(),
            Some(choice(
                preset,
                &[
                    (RunSetting::Feedback, "feed"),
                    (RunSetting::SpindleSpeed, "5000"),
                ],
            )),
        );
        assert_eq!(chosen[key(RunSetting::Feedback)], own_feedback);
        assert_eq!(chosen[key(RunSetting::SpindleSpeed)], own_speed);
    }
}
