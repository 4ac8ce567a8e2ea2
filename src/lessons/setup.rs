//! What a lesson's step sets up: a page of the lab and its URL query, exactly as the lab's own
//! links write them (`#/simulate?preset=kim-step-doc&controller=pi&kp=0.3`), and the runs that
//! query defines. The query is read through the run definition's table ([`parse_texts`], keys
//! from [`RunSetting::from_query_key`]) and the controller registry's parameters, and a Signal
//! chain query through the filter design's ([`query_texts`], [`parse_design`]), a Logs query
//! through the Logs page's own ([`LogsLink::parse`]): the same parsers the lab's pages use, so a
//! lesson cannot set up something the lab would read differently.

use crate::closed_loop::definition::{parse_texts, RunSetting, RunSpec};
use crate::closed_loop::paper_defaults::preset_controller;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::input::parse_number;
use crate::log::link::LogsLink;
use crate::plant::Preset;
use crate::sections::Page;
use crate::signal::butterworth::ButterworthSpec;
use crate::signal::design_settings::{parse_design, query_texts};
use crate::signal::sos::Sos;

/// A page of the lab a step can open: the sections ([`Page`]) a lesson can set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LabPage {
    /// One closed-loop run.
    Simulate,
    /// Two to four controllers on one scenario (variants A–D).
    Compare,
    /// Paper 002's fuzzy rules and control surface.
    Fuzzy,
    /// The Butterworth design and the bench current through it.
    SignalChain,
    /// Teach-in, sweeps and tuning.
    Tune,
    /// The student's own machine logs.
    Logs,
    /// The simulated machine on its own.
    Plant,
}

impl LabPage {
    /// Every page a lesson can open.
    pub const ALL: [LabPage; 7] = [
        LabPage::Simulate,
        LabPage::Compare,
        LabPage::Fuzzy,
        LabPage::SignalChain,
        LabPage::Tune,
        LabPage::Logs,
        LabPage::Plant,
    ];

    /// The lab's section it is.
    pub fn section(self) -> Page {
        match self {
            LabPage::Simulate => Page::Simulate,
            LabPage::Compare => Page::Compare,
            LabPage::Fuzzy => Page::Fuzzy,
            LabPage::SignalChain => Page::SignalChain,
            LabPage::Tune => Page::Tune,
            LabPage::Logs => Page::Logs,
            LabPage::Plant => Page::Plant,
        }
    }

    /// The URL hash's page part (the section's).
    pub fn slug(self) -> &'static str {
        self.section().slug()
    }

    /// The page whose slug is `slug`.
    pub fn from_slug(slug: &str) -> Option<LabPage> {
        Self::ALL.into_iter().find(|p| p.slug() == slug)
    }

    /// Whether the page's work is closed-loop runs (whose metrics a condition can check).
    pub fn runs(self) -> bool {
        matches!(self, LabPage::Simulate | LabPage::Compare)
    }
}

/// A page and its query, as a link to the lab writes them.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    /// The page.
    pub page: LabPage,
    /// The query's `key=value` pairs, decoded, in order.
    pub query: Vec<(String, String)>,
}

/// What a setup's query defines.
#[derive(Debug, Clone, PartialEq)]
pub enum Defined {
    /// The runs of a Simulate (one) or Compare (one per variant, A first) page.
    Runs(Vec<RunSpec>),
    /// A Signal chain page's filter.
    Design(ButterworthSpec, Sos),
    /// The Logs page's state: its sample log, mapping and replay form, as the page reads its
    /// own address bar.
    Logs(Box<LogsLink>),
    /// A page whose state a lesson does not check (answers are multiple choice there).
    Nothing,
}

/// The query prefixes of the Compare page's variants, A to D.
pub const VARIANT_PREFIXES: [&str; 4] = ["a.", "b.", "c.", "d."];
/// The variants' names, as the Compare page shows them.
pub const VARIANT_NAMES: [&str; 4] = ["A", "B", "C", "D"];

impl Setup {
    /// Reads a link such as `#/compare?preset=liu-current-step&a.controller=fuzzy-experience`
    /// (the leading `#` and `/` optional; `%XX` escapes and `+` are decoded as a browser does).
    ///
    /// ```
    /// use cutlab::lessons::setup::{LabPage, Setup};
    /// let s = Setup::from_link("#/simulate?preset=kim-step-doc&controller=pi&kp=0%2C3").unwrap();
    /// assert_eq!(s.page, LabPage::Simulate);
    /// assert_eq!(s.query[2], ("kp".to_string(), "0,3".to_string()));
    /// let twice = Setup::from_link("#/simulate?controller=pi&kp=0.5&kp=0.9").unwrap_err();
    /// assert_eq!(twice, "\"kp\" is given twice in the link (kp=0.5, then kp=0.9); give each setting once");
    /// ```
    pub fn from_link(link: &str) -> Result<Setup, String> {
        let path = link.trim().trim_start_matches('#').trim_start_matches('/');
        let (slug, query) = path.split_once('?').unwrap_or((path, ""));
        let page = LabPage::from_slug(slug).ok_or_else(|| {
            let pages: Vec<&str> = LabPage::ALL.iter().map(|p| p.slug()).collect();
            format!(
                "\"{slug}\" is not a page a lesson can open; pages: {}",
                pages.join(", ")
            )
        })?;
        let query = query
            .split('&')
            .filter(|pair| !pair.is_empty())
            .map(|pair| {
                let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
                Ok((decode(k)?, decode(v)?))
            })
            .collect::<Result<Vec<(String, String)>, String>>()?;
        // A key given twice would leave one of its values unread (which one depends on the
        // reader): the link is refused, naming it.
        for (i, (key, first)) in query.iter().enumerate() {
            if let Some((_, second)) = query[i + 1..].iter().find(|(k, _)| k == key) {
                return Err(format!(
                    "\"{key}\" is given twice in the link ({key}={first}, then {key}={second}); \
                     give each setting once"
                ));
            }
        }
        Ok(Setup { page, query })
    }

    /// Whether the address `current` (a URL hash) already shows this setup: the same page, with
    /// every key of this setup's query at the same value, and no other key — but on the Logs
    /// page, where the other keys are the student's own work on the log (its sample, column,
    /// grouping), any other keys. A step whose setup the page already shows keeps the page as it
    /// is instead of resetting it to the setup's link; on a page of runs another key would be
    /// another experiment than the step's starting point, so it is reset.
    ///
    /// ```
    /// use cutlab::lessons::setup::Setup;
    /// let logs = Setup::from_link("#/logs").unwrap();
    /// assert!(logs.held_by("#/logs?sample=synthetic-kim-step-doc-export.csv&column=S_Strom%20%5BA%5D"));
    /// let sample = Setup::from_link("#/logs?sample=synthetic-kim-step-doc-export.csv").unwrap();
    /// assert!(!sample.held_by("#/logs"));
    /// assert!(!logs.held_by("#/simulate"));
    /// let run = Setup::from_link("#/simulate?preset=kim-step-doc&controller=pi").unwrap();
    /// assert!(run.held_by("#/simulate?controller=pi&preset=kim-step-doc"));
    /// assert!(!run.held_by("#/simulate?preset=kim-step-doc&controller=pi&kp=0.9"));
    /// ```
    pub fn held_by(&self, current: &str) -> bool {
        Setup::from_link(current).is_ok_and(|shown| {
            shown.page == self.page
                && (self.page == LabPage::Logs || shown.query.len() == self.query.len())
                && self
                    .query
                    .iter()
                    .all(|(k, v)| shown.value(k).is_some_and(|s| s == v))
        })
    }

    /// The link this setup opens.
    pub fn link(&self) -> String {
        let query: Vec<String> = self
            .query
            .iter()
            .map(|(k, v)| format!("{}={}", encode(k), encode(v)))
            .collect();
        if query.is_empty() {
            format!("#/{}", self.page.slug())
        } else {
            format!("#/{}?{}", self.page.slug(), query.join("&"))
        }
    }

    /// What the query defines, through the lab's own parsers; a message naming the key at
    /// fault otherwise.
    pub fn define(&self) -> Result<Defined, String> {
        match self.page {
            LabPage::Simulate => Ok(Defined::Runs(vec![self.run(1, &[""])?.remove(0)])),
            LabPage::Compare => {
                let count = match self.value("variants") {
                    None => 2,
                    Some(text) => text
                        .trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|n| (2..=4).contains(n))
                        .ok_or_else(|| {
                            format!("variants: \"{text}\" is not a count from 2 to 4")
                        })?,
                };
                Ok(Defined::Runs(self.run(count, &VARIANT_PREFIXES)?))
            }
            LabPage::SignalChain => {
                use crate::input::table::Table;
                use crate::signal::design_settings::FilterSetting;
                self.refuse_unknown(|key| {
                    key == "preset" || FilterSetting::from_key(key).is_some()
                })?;
                let texts = query_texts(&self.query);
                parse_design(&texts)
                    .map(|(spec, sos)| Defined::Design(spec, sos))
                    .map_err(|errors| {
                        errors
                            .iter()
                            .map(|e| format!("{}: {}", e.setting.row().key, e.problem))
                            .collect::<Vec<_>>()
                            .join("; ")
                    })
            }
            LabPage::Logs => {
                let (link, problems) = LogsLink::parse(&self.query);
                if problems.is_empty() {
                    Ok(Defined::Logs(Box::new(link)))
                } else {
                    Err(problems.join("; "))
                }
            }
            LabPage::Fuzzy | LabPage::Tune | LabPage::Plant => Ok(Defined::Nothing),
        }
    }

    /// The value of `key` in the query, if given.
    pub fn value(&self, key: &str) -> Option<&str> {
        self.query
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    fn refuse_unknown(&self, known: impl Fn(&str) -> bool) -> Result<(), String> {
        match self.query.iter().find(|(k, _)| !known(k)) {
            Some((key, _)) => Err(format!(
                "\"{key}\" is not a setting of the {} page",
                self.page.slug()
            )),
            None => Ok(()),
        }
    }

    /// The runs of `count` controllers (query prefixes `prefixes`) on the query's scenario.
    fn run(&self, count: usize, prefixes: &[&str]) -> Result<Vec<RunSpec>, String> {
        use crate::input::table::Table;
        let prefixes = &prefixes[..count.min(prefixes.len())];
        let preset_name = self
            .value("preset")
            .ok_or("preset: a lesson names the preset its runs are on")?;
        let preset = Preset::from_name(preset_name)
            .ok_or_else(|| format!("preset: \"{preset_name}\" is not a preset"))?;
        // The controller keys: each prefix's `controller` and its kind's parameters.
        let mut kinds = Vec::with_capacity(prefixes.len());
        for prefix in prefixes {
            let key = format!("{prefix}controller");
            let name = self
                .value(&key)
                .ok_or_else(|| format!("{key}: a lesson names each run's controller"))?;
            let kind = name
                .parse::<ControllerKind>()
                .map_err(|e| format!("{key}: {e}"))?;
            kinds.push(kind);
        }
        let is_controller_key = |key: &str| {
            prefixes.iter().zip(&kinds).any(|(prefix, kind)| {
                key.strip_prefix(prefix)
                    .is_some_and(|k| k == "controller" || kind.params().iter().any(|p| p.key == k))
            })
        };
        self.refuse_unknown(|key| {
            key == "preset"
                || key == "variants"
                || RunSetting::from_query_key(key).is_some()
                || is_controller_key(key)
        })?;
        let texts: Vec<(RunSetting, &str)> = self
            .query
            .iter()
            .filter_map(|(k, v)| RunSetting::from_query_key(k).map(|s| (s, v.as_str())))
            .collect();
        let scenario = parse_texts(preset, ControllerConfig::new(ControllerKind::Fixed), &texts)
            .map_err(|errors| {
                errors
                    .iter()
                    .map(|e| format!("{}: {}", e.setting.row().key, e.problem))
                    .collect::<Vec<_>>()
                    .join("; ")
            })?;
        prefixes
            .iter()
            .zip(kinds)
            .map(|(prefix, kind)| {
                let mut controller = preset_controller(preset, kind);
                for param in kind.params() {
                    let key = format!("{prefix}{}", param.key);
                    if let Some(text) = self.value(&key) {
                        let value = parse_number(text).map_err(|e| format!("{key}: {e}"))?;
                        controller
                            .set(param.key, value)
                            .map_err(|e| format!("{key}: {e}"))?;
                    }
                }
                Ok(RunSpec {
                    controller,
                    ..scenario.clone()
                })
            })
            .collect()
    }
}

/// Decodes `%XX` escapes (UTF-8) and `+` as a space.
fn decode(text: &str) -> Result<String, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'%' => {
                let hex = text
                    .get(i + 1..i + 3)
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
                    .ok_or_else(|| format!("\"{text}\": a % not followed by two hex digits"))?;
                out.push(hex);
                i += 3;
            }
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            b => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8(out).map_err(|_| format!("\"{text}\": escapes that are not UTF-8"))
}

/// Encodes what a link's query cannot hold as it is.
fn encode(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for b in text.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'_' | b'.' | b'~' | b',') {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn define(link: &str) -> Result<Defined, String> {
        Setup::from_link(link)?.define()
    }

    #[test]
    fn a_simulate_link_defines_the_run_the_form_would() {
        let Ok(Defined::Runs(runs)) =
            define("#/simulate?preset=kim-step-doc&controller=pi&kp=0.25&target=400")
        else {
            panic!("not a run");
        };
        assert_eq!(runs.len(), 1);
        assert_eq!(runs[0].controller.kind(), ControllerKind::Pi);
        assert_eq!(runs[0].controller.get("kp"), Some(0.25));
        let target = RunSetting::TargetForce.value_in(&runs[0]);
        assert_eq!(target.and_then(|v| v.number()), Some(400.0));
    }

    #[test]
    fn a_compare_link_defines_one_run_per_variant() {
        let link = "#/compare?preset=liu-current-step&variants=2&a.controller=fuzzy-experience\
                    &b.controller=fuzzy-dynamics";
        let Ok(Defined::Runs(runs)) = define(link) else {
            panic!("not runs");
        };
        let kinds: Vec<_> = runs.iter().map(|r| r.controller.kind()).collect();
        assert_eq!(
            kinds,
            [
                ControllerKind::FuzzyExperience,
                ControllerKind::FuzzyDynamics
            ]
        );
    }

    #[test]
    fn unknown_keys_bad_values_and_missing_controllers_name_the_key() {
        let e = define("#/simulate?preset=kim-step-doc&controller=pi&kpp=1").unwrap_err();
        assert!(e.contains("\"kpp\""), "{e}");
        let e = define("#/simulate?preset=kim-step-doc&controller=pi&kp=abc").unwrap_err();
        assert!(e.starts_with("kp: "), "{e}");
        let e = define("#/simulate?preset=kim-step-doc").unwrap_err();
        assert!(e.starts_with("controller: "), "{e}");
        let e = define("#/simulate?preset=kim-step-doc&controller=pi&period=1000").unwrap_err();
        assert!(e.contains("outside"), "{e}");
        assert!(define("#/nowhere").unwrap_err().contains("not a page"));
    }

    #[test]
    fn a_signal_chain_link_defines_its_filter() {
        let Ok(Defined::Design(spec, _)) = define("#/signal?preset=kim-spindle-260hz&order=4")
        else {
            panic!("not a design");
        };
        assert_eq!(spec.order, 4);
        assert!(define("#/signal?order=0").is_err());
    }

    #[test]
    fn a_logs_link_is_read_by_the_logs_pages_parser() {
        let Ok(Defined::Logs(link)) = define(
            "#/logs?sample=synthetic-kim-step-doc-export.csv&replay=threshold%2Cpi&target_a=10.4",
        ) else {
            panic!("not a logs link");
        };
        assert_eq!(
            link.replayed,
            [ControllerKind::Threshold, ControllerKind::Pi]
        );
        assert_eq!(link.target_text, "10.4");
        let e = define("#/logs?sample=mine.csv").unwrap_err();
        assert!(e.starts_with("sample: "), "{e}");
    }

    #[test]
    fn a_link_reads_back_as_it_was_written() {
        let setup = Setup::from_link("#/compare?a.controller=pi&a.kp=0%2C5&note=a%20b").unwrap();
        assert_eq!(Setup::from_link(&setup.link()).unwrap(), setup);
    }
}
