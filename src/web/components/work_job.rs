//! A core [`Work`] whose output the browser shares: the page's signals clone their value on
//! every read, and a recording is megabytes, so the runner hands out an `Arc` of it.

use std::sync::Arc;

use crate::work::{Progress, Work};

/// `work` with its output behind an [`Arc`].
pub struct Shared<W>(pub W);

impl<W: Work> Work for Shared<W> {
    type Output = Arc<W::Output>;
    type Error = W::Error;

    fn advance(&mut self, budget: usize) -> Result<bool, W::Error> {
        self.0.advance(budget)
    }

    fn progress(&self) -> Progress {
        self.0.progress()
    }

    fn finish(&mut self) -> Result<Self::Output, W::Error> {
        self.0.finish().map(Arc::new)
    }
}
