//! The core's [`Work`] run by the browser's [`Runner`](super::runner::Runner): a trivial adapter
//! to the runner's [`Job`] until the runner takes `Work` itself.

use std::sync::Arc;

use super::runner::Job;
use crate::work::Work;

/// `work` as a [`Job`]; its output is shared (`Arc`) so the page's signals clone it cheaply.
pub struct WorkJob<W>(pub W);

impl<W: Work> Job for WorkJob<W> {
    type Output = Arc<W::Output>;

    fn advance(&mut self, budget: usize) -> Result<bool, String> {
        self.0.advance(budget).map_err(|e| e.to_string())
    }

    fn progress(&self) -> (String, f64) {
        let p = self.0.progress();
        (p.stage, p.fraction)
    }

    fn finish(&mut self) -> Result<Self::Output, String> {
        self.0.finish().map(Arc::new).map_err(|e| e.to_string())
    }
}
