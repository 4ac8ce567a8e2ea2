//! The forms that define a run: the scenario (preset, seed, target, override limit) and a
//! controller with its parameters. Both keep the typed text and turn it into the core's validated
//! types, with one message per field; both read from and write to the URL query.

use std::collections::BTreeMap;

use leptos::prelude::*;

use crate::closed_loop::lab::SettingsOverrides;
use crate::control::fuzzy::rules::RuleTable;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::plant::materials::Material;
use crate::plant::presets::PlantEdits;
use crate::plant::Preset;
use crate::web::components::fields::{
    parse_count, parse_number, parse_seed, NumberField, SelectField,
};

/// Text of the scenario fields.
#[derive(Clone, Copy)]
pub struct ScenarioForm {
    /// Preset name.
    pub preset: RwSignal<String>,
    /// Seed.
    pub seed: RwSignal<String>,
    /// Target force; blank keeps the preset's.
    pub target: RwSignal<String>,
    /// Highest override the envelope allows.
    pub max_override: RwSignal<String>,
    /// Control period; blank keeps the preset's (whole spindle revolutions).
    pub period: RwSignal<String>,
    /// Order of the current low-pass filters.
    pub filter_order: RwSignal<String>,
    /// Spindle current low-pass cut-off.
    pub spindle_cutoff: RwSignal<String>,
    /// Feed current low-pass cut-off.
    pub feed_cutoff: RwSignal<String>,
    /// Work material; blank keeps the preset's.
    pub material: RwSignal<String>,
    /// Spindle speed; blank keeps the preset's.
    pub rpm: RwSignal<String>,
    /// Programmed feed; blank keeps the preset's.
    pub feed: RwSignal<String>,
    /// Factor on the depth profile.
    pub depth_scale: RwSignal<String>,
    /// Cutter diameter; blank keeps the preset's.
    pub diameter: RwSignal<String>,
    /// Number of teeth; blank keeps the preset's.
    pub teeth: RwSignal<String>,
    /// Hall-sensor noise; blank keeps the preset's.
    pub noise: RwSignal<String>,
}

/// The plant-edit fields: (query key, default text).
/// The preset a fresh form shows.
const DEFAULT_PRESET: &str = "kim-step-doc";

const PLANT_KEYS: [&str; 7] = [
    "material",
    "rpm",
    "feed",
    "depth_scale",
    "diameter",
    "teeth",
    "noise",
];

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
        let blank = || RwSignal::new(String::new());
        let form = Self {
            preset: blank(),
            seed: blank(),
            target: blank(),
            max_override: blank(),
            period: blank(),
            filter_order: blank(),
            spindle_cutoff: blank(),
            feed_cutoff: blank(),
            material: blank(),
            rpm: blank(),
            feed: blank(),
            depth_scale: blank(),
            diameter: blank(),
            teeth: blank(),
            noise: blank(),
        };
        for (key, signal, default) in form.fields() {
            let typed = query.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone());
            signal.set(typed.unwrap_or_else(|| default.to_string()));
        }
        form
    }

    /// Every field with its query key and default text. Blank keeps the preset's value; the
    /// preset, seed and override limit are always written to the query.
    fn fields(&self) -> [(&'static str, RwSignal<String>, &'static str); 15] {
        [
            ("preset", self.preset, DEFAULT_PRESET),
            ("seed", self.seed, "1"),
            ("target", self.target, ""),
            ("max_override", self.max_override, "150"),
            ("period", self.period, ""),
            ("filter_order", self.filter_order, "4"),
            ("spindle_cutoff", self.spindle_cutoff, "260"),
            ("feed_cutoff", self.feed_cutoff, "50"),
            (PLANT_KEYS[0], self.material, ""),
            (PLANT_KEYS[1], self.rpm, ""),
            (PLANT_KEYS[2], self.feed, ""),
            (PLANT_KEYS[3], self.depth_scale, "1"),
            (PLANT_KEYS[4], self.diameter, ""),
            (PLANT_KEYS[5], self.teeth, ""),
            (PLANT_KEYS[6], self.noise, ""),
        ]
    }

    /// Every field back to its default, on `preset`: a one-click experiment starts from the
    /// paper's own values, not from edits made for another preset.
    pub fn reset_to(&self, preset: Preset) {
        for (_, signal, default) in self.fields() {
            signal.set(default.to_string());
        }
        self.preset.set(preset.name().to_string());
    }

    /// The query pairs that reproduce this form.
    pub fn query(&self) -> Vec<(String, String)> {
        self.fields()
            .into_iter()
            .filter_map(|(key, signal, default)| {
                let text = signal.get();
                let always = matches!(key, "preset" | "seed" | "max_override");
                (always || text.trim() != default).then(|| (key.to_string(), text))
            })
            .collect()
    }

    /// Parses the plant edits; blank fields keep the preset's values.
    fn parse_plant(&self, errors: &mut BTreeMap<&'static str, String>) -> PlantEdits {
        let mut optional = |key: &'static str, text: String, min: f64, max: f64, unit: &str| {
            if text.trim().is_empty() {
                return None;
            }
            match parse_number(&text) {
                Ok(v) if (min..=max).contains(&v) => Some(v),
                Ok(v) => {
                    errors.insert(key, format!("{v} {unit} is outside {min}–{max} {unit}"));
                    None
                }
                Err(e) => {
                    errors.insert(key, e);
                    None
                }
            }
        };
        let edits = PlantEdits {
            material: Material::from_name(&self.material.get()),
            spindle_rpm: optional("rpm", self.rpm.get(), 50.0, 20_000.0, "rpm"),
            programmed_feed_mm_min: optional("feed", self.feed.get(), 1.0, 20_000.0, "mm/min"),
            depth_scale: optional("depth_scale", self.depth_scale.get(), 0.05, 5.0, "×"),
            tool_diameter_mm: optional("diameter", self.diameter.get(), 0.5, 100.0, "mm"),
            teeth: optional("teeth", self.teeth.get(), 1.0, 12.0, "teeth")
                .map(|z| z.round() as u32),
            sensor_noise_a: optional("noise", self.noise.get(), 0.0, 5.0, "A"),
        };
        PlantEdits {
            depth_scale: edits.depth_scale.filter(|k| *k != 1.0),
            ..edits
        }
    }

    /// Parses the fields; errors are keyed by field name.
    pub fn parse(&self) -> Result<ScenarioChoice, BTreeMap<&'static str, String>> {
        let mut errors = BTreeMap::new();
        let preset = Preset::from_name(&self.preset.get());
        if preset.is_none() {
            errors.insert("preset", "choose a preset".to_string());
        }
        let seed = parse_seed(&self.seed.get())
            .map_err(|e| errors.insert("seed", e))
            .ok();
        let target_text = self.target.get();
        let target = if target_text.trim().is_empty() {
            Some(None)
        } else {
            match parse_number(&target_text) {
                Ok(v) if v > 0.0 => Some(Some(v)),
                Ok(v) => {
                    errors.insert("target", format!("the target must be positive, not {v} N"));
                    None
                }
                Err(e) => {
                    errors.insert("target", e);
                    None
                }
            }
        };
        let max_override = match parse_number(&self.max_override.get()) {
            Ok(v) if (20.0..=255.0).contains(&v) => Some(v),
            Ok(v) => {
                errors.insert("max_override", format!("{v} % is outside 20–255 %"));
                None
            }
            Err(e) => {
                errors.insert("max_override", e);
                None
            }
        };
        let period_text = self.period.get();
        let period = if period_text.trim().is_empty() {
            None
        } else {
            match parse_number(&period_text) {
                Ok(v) if (0.001..=2.0).contains(&v) => Some(v),
                Ok(v) => {
                    errors.insert("period", format!("{v} s is outside 0.001–2 s"));
                    None
                }
                Err(e) => {
                    errors.insert("period", e);
                    None
                }
            }
        };
        let order = match parse_count(&self.filter_order.get()) {
            Ok(v) if (1..=20).contains(&v) => Some(v),
            Ok(v) => {
                errors.insert("filter_order", format!("order {v} is outside 1–20"));
                None
            }
            Err(e) => {
                errors.insert("filter_order", e);
                None
            }
        };
        // The sensors sample at 10 kHz: a cut-off must stay below 5 kHz (the core checks again).
        let mut cutoff = |key: &'static str, text: String| match parse_number(&text) {
            Ok(v) if v > 0.0 && v < 5000.0 => Some(v),
            Ok(v) => {
                errors.insert(
                    key,
                    format!("{v} Hz must lie between 0 and the 5000 Hz Nyquist frequency"),
                );
                None
            }
            Err(e) => {
                errors.insert(key, e);
                None
            }
        };
        let spindle_cutoff = cutoff("spindle_cutoff", self.spindle_cutoff.get());
        let feed_cutoff = cutoff("feed_cutoff", self.feed_cutoff.get());
        // The machine fields are hidden for presets without a mill; what they hold then must
        // neither block the run nor change it.
        let plant = match preset {
            Some(p) if p.scenario().is_some() => self.parse_plant(&mut errors),
            _ => PlantEdits::default(),
        };
        match (preset, seed, target, max_override) {
            (Some(preset), Some(seed), Some(target), Some(max)) if errors.is_empty() => {
                Ok(ScenarioChoice {
                    preset,
                    seed,
                    settings: SettingsOverrides {
                        target_force_n: target,
                        max_override_pct: Some(max),
                        control_period_s: period,
                        lowpass_order: order,
                        spindle_lowpass_hz: spindle_cutoff,
                        feed_lowpass_hz: feed_cutoff,
                        ..SettingsOverrides::default()
                    },
                    plant,
                })
            }
            _ => Err(errors),
        }
    }
}

/// The scenario fields.
#[component]
pub fn ScenarioFields(form: ScenarioForm) -> impl IntoView {
    let errors = Memo::new(move |_| form.parse().err().unwrap_or_default());
    let error =
        move |key: &'static str| Signal::derive(move || errors.with(|e| e.get(key).cloned()));
    let summary = move || {
        Preset::from_name(&form.preset.get()).map(|p| {
            let s = p.summary();
            let mut parts = vec![p.source().to_string()];
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
            <p class="hint">{summary}</p>
            <NumberField id="seed" label="Seed" value=form.seed error=error("seed") step="1" />
            <NumberField
                id="target"
                label="Target force (blank: preset's)"
                unit="N"
                value=form.target
                error=error("target")
            />
            <NumberField
                id="max-override"
                label="Highest override"
                unit="%"
                value=form.max_override
                error=error("max_override")
            />
        </fieldset>
    }
}

/// The machine, cut and signal-chain fields of a scenario form (shown after the controller).
#[component]
pub fn MachineAndSignalFields(form: ScenarioForm) -> impl IntoView {
    let errors = Memo::new(move |_| form.parse().err().unwrap_or_default());
    let error =
        move |key: &'static str| Signal::derive(move || errors.with(|e| e.get(key).cloned()));
    view! {
        <fieldset hidden=move || {
            Preset::from_name(&form.preset.get()).is_none_or(|p| p.scenario().is_none())
        }>
            <legend>"Machine and cut (blank: the preset's)"</legend>
            <SelectField
                id="material"
                label="Work material"
                options=std::iter::once(("", "The preset's"))
                    .chain(Material::ALL.iter().map(|m| (m.name(), m.label())))
                    .collect()
                value=form.material
            />
            <NumberField id="rpm" label="Spindle speed" unit="rpm" value=form.rpm error=error("rpm") />
            <NumberField id="feed" label="Programmed feed" unit="mm/min" value=form.feed error=error("feed") />
            <NumberField id="depth-scale" label="Depth of cut ×" value=form.depth_scale error=error("depth_scale") />
            <NumberField id="diameter" label="Tool diameter" unit="mm" value=form.diameter error=error("diameter") />
            <NumberField id="teeth" label="Teeth" value=form.teeth error=error("teeth") step="1" />
            <NumberField id="noise" label="Sensor noise" unit="A" value=form.noise error=error("noise") />
        </fieldset>
        <fieldset>
            <legend>"Signal chain"</legend>
            <NumberField
                id="period"
                label="Control period (blank: whole revolutions ≥ 40 ms)"
                unit="s"
                value=form.period
                error=error("period")
            />
            <NumberField
                id="filter-order"
                label="Current filter order"
                value=form.filter_order
                error=error("filter_order")
                step="1"
            />
            <NumberField
                id="spindle-cutoff"
                label="Spindle current cut-off"
                unit="Hz"
                value=form.spindle_cutoff
                error=error("spindle_cutoff")
            />
            <NumberField
                id="feed-cutoff"
                label="Feed current cut-off"
                unit="Hz"
                value=form.feed_cutoff
                error=error("feed_cutoff")
            />
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

fn is_fuzzy(kind: &str) -> bool {
    kind.starts_with("fuzzy")
}

impl ControllerForm {
    /// A form for `default_kind`, then whatever `query` says (`controller=pi&kp=0.4`); query keys
    /// are prefixed with `prefix` (e.g. `a.kp`) when several forms share a page.
    pub fn new(
        id_prefix: &'static str,
        default_kind: ControllerKind,
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
                    p.default.to_string(),
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
        Self {
            kind: RwSignal::new(kind),
            values: RwSignal::new(values),
            id_prefix,
            rule_table: RwSignal::new(rule_table),
        }
    }

    /// `kind` with its default parameters and built-in rules.
    pub fn reset_to(&self, kind: ControllerKind) {
        self.kind.set(kind.name().to_string());
        self.values.update(|values| {
            for p in kind.params() {
                values.insert(
                    (kind.name().to_string(), p.key.to_string()),
                    p.default.to_string(),
                );
            }
        });
        self.rule_table.set(None);
    }

    /// Query pairs for the chosen controller and its non-default parameters.
    pub fn query(&self, query_prefix: &str) -> Vec<(String, String)> {
        let kind = self.kind.get();
        let mut q = vec![(format!("{query_prefix}controller"), kind.clone())];
        if let Some(table) = self.rule_table.get().filter(|_| is_fuzzy(&kind)) {
            q.push((format!("{query_prefix}rules"), encode_rule_table(&table)));
        }
        if let Ok(k) = kind.parse::<ControllerKind>() {
            self.values.with(|v| {
                for p in k.params() {
                    if let Some(text) = v.get(&(kind.clone(), p.key.to_string())) {
                        if text.trim() != p.default.to_string() {
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
        let mut config = ControllerConfig::new(kind);
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
        if errors.is_empty() {
            Ok(config)
        } else {
            Err(errors)
        }
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
                    Effect::new(move |_| {
                        let t = text.get();
                        form.values.update(|v| {
                            v.insert(key_for_effect.clone(), t);
                        });
                    });
                    let param_key = p.key.to_string();
                    let error = Signal::derive(move || errors.with(|e| e.get(&param_key).cloned()));
                    let id = format!("{}{}", form.id_prefix, p.key);
                    view! {
                        <NumberField id=id label=p.label.to_string() unit=p.unit value=text error=error />
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
