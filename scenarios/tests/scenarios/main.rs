//! The integration tests of this crate, one binary (each module was a test
//! binary of its own: one link instead of many keeps the test build lean).

mod delay;
mod distributed;
mod estimation;
mod real_logs;
mod robustness;
mod write_back;

use leeway_model::{Experiment, Row, Source};

/// A record that hides that it is in memory, as a streamed file does.
pub(crate) struct Streamed<'a>(pub(crate) &'a Experiment);

impl Source for Streamed<'_> {
    fn name(&self) -> &str {
        &self.0.name
    }
    fn len(&self) -> usize {
        self.0.len()
    }
    fn step(&self) -> f64 {
        self.0.h
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        self.0.visit(f);
    }
}
