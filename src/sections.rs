//! The lab's sections and their place in the URL hash (`#/signal`): one list, which the browser's
//! router shows and a lesson's links name (`lessons::setup::LabPage` is the sections a lesson can
//! set up).

/// A section of the lab. Only sections that work are listed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Page {
    /// What the lab is for, the loop, where to start, the papers.
    Home,
    /// Filter design and the signal chain.
    SignalChain,
    /// Run one closed loop on a preset.
    Simulate,
    /// Compare controllers on one preset.
    Compare,
    /// Edit paper 002's fuzzy rules and see the control surface.
    Fuzzy,
    /// The simulated machine on its own.
    Plant,
    /// Teach-in, sweeps and automatic tuning.
    Tune,
    /// A real machine over WebSerial, or the virtual device.
    Hardware,
    /// Engineers' own machine logs: analysis, calibration, replay.
    Logs,
    /// The guided path through the ideas.
    Learn,
    /// Guided experiments with checks, and a lesson opened by its link (`#/lessons/ID`).
    Lessons,
}

impl Page {
    /// Every page, in navigation order.
    pub const ALL: [Page; 11] = [
        Page::Home,
        Page::Simulate,
        Page::Compare,
        Page::Tune,
        Page::Hardware,
        Page::Logs,
        Page::Fuzzy,
        Page::Plant,
        Page::SignalChain,
        Page::Learn,
        Page::Lessons,
    ];

    /// The page shown for an empty or unknown hash.
    pub const HOME: Page = Page::Home;

    /// The URL hash fragment after `#/`.
    pub fn slug(self) -> &'static str {
        match self {
            Page::Home => "home",
            Page::SignalChain => "signal",
            Page::Simulate => "simulate",
            Page::Compare => "compare",
            Page::Fuzzy => "fuzzy",
            Page::Plant => "plant",
            Page::Tune => "tune",
            Page::Hardware => "hardware",
            Page::Logs => "logs",
            Page::Learn => "learn",
            Page::Lessons => "lessons",
        }
    }

    /// The navigation label.
    pub fn label(self) -> &'static str {
        match self {
            Page::Home => "Home",
            Page::SignalChain => "Signal chain",
            Page::Simulate => "Simulate",
            Page::Compare => "Compare",
            Page::Fuzzy => "Fuzzy rules",
            Page::Plant => "Machine",
            Page::Tune => "Tune",
            Page::Hardware => "Hardware",
            Page::Logs => "Logs",
            Page::Learn => "Learn",
            Page::Lessons => "Lessons",
        }
    }

    /// The page whose slug is `slug`.
    pub fn from_slug(slug: &str) -> Option<Page> {
        Page::ALL.into_iter().find(|p| p.slug() == slug)
    }

    /// The page a hash such as `#/signal?order=4` selects, if any.
    pub fn from_hash(hash: &str) -> Option<Page> {
        let path = hash.trim_start_matches('#').trim_start_matches('/');
        Page::from_slug(path.split(['?', '/']).next().unwrap_or_default())
    }

    /// The link target for this page.
    pub fn href(self) -> String {
        format!("#/{}", self.slug())
    }
}

#[cfg(test)]
mod tests {
    use super::Page;

    #[test]
    fn every_section_has_its_own_slug_and_a_hash_finds_it() {
        for page in Page::ALL {
            assert_eq!(
                Page::ALL.iter().filter(|p| p.slug() == page.slug()).count(),
                1,
                "{page:?}"
            );
            assert_eq!(Page::from_hash(&page.href()), Some(page));
            assert_eq!(
                Page::from_hash(&format!("{}?preset=kim-step-doc", page.href())),
                Some(page)
            );
        }
        assert_eq!(Page::from_hash("#/lessons/own-log"), Some(Page::Lessons));
        assert_eq!(Page::from_hash("#/nowhere"), None);
    }
}
