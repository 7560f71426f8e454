//! Dead times of inputs, applied in one place: the [`Delayed`] view of a
//! record, which starts at sample `d_max` (the model's longest dead time) and
//! gives each input from its dead time `d` earlier, so that the equation at
//! sample k sees `u(k − d)`. Estimators, simulation, validation and residuals
//! all read records through it ([`delayed`]); a view of a view is the view
//! itself, so a consumer handing a view to another never shifts twice.
//!
//! A record's first `d_max` samples thus have no equation: they only supply
//! the delayed inputs. An in-memory record's view is an in-memory record (the
//! shifted columns, built once), so passes keep their fast paths; a streamed
//! one's view holds the last `d_max + 1` input rows, nothing more.

use crate::experiment::{Experiment, Row, Source};
use crate::number::short_number;
use leeway_structure::ir::{Ir, LagProblem};

/// A dead time that is no whole number of a record's sample times.
#[derive(Clone, Debug, PartialEq)]
pub struct DelayError {
    /// The record.
    pub experiment: String,
    /// The input whose dead time it is.
    pub input: String,
    /// One sentence: what is wrong.
    pub message: String,
}

impl std::fmt::Display for DelayError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "experiment `{}`: {}", self.experiment, self.message)
    }
}

/// What a record's dead times are at its sample time.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeadTimes {
    /// Samples per input (0: none).
    pub lags: Vec<usize>,
    /// The longest: the samples at the record's start that have no equation.
    pub max: usize,
}

/// The dead times of `ir`'s inputs on a record `experiment` sampled at `h`,
/// or why they are not whole numbers of samples there.
pub fn dead_times(ir: &Ir, experiment: &str, h: f64) -> Result<DeadTimes, DelayError> {
    let lags = ir.dead_times(h).map_err(|(input, p)| DelayError {
        experiment: experiment.to_string(),
        message: match p {
            LagProblem::NotWhole { ratio } => format!(
                "the dead time of `{input}` is {ratio:.3} sample times of {} s, not a whole number",
                short_number(h)
            ),
            LagProblem::TooLong { samples } => format!(
                "the dead time of `{input}` is {samples} samples of {} s, more than {}",
                short_number(h),
                leeway_structure::ir::MAX_DELAY_SAMPLES
            ),
        },
        input,
    })?;
    let max = lags.iter().copied().max().unwrap_or(0);
    Ok(DeadTimes { lags, max })
}

/// A record as the model's equations see it: see the module's docs.
pub struct Delayed<'a> {
    inner: &'a dyn Source,
    /// `None` when the view is the record itself (no dead time, or a view).
    lags: Option<DeadTimes>,
    /// The shifted columns of an in-memory record.
    shifted: Option<Experiment>,
}

/// The view of `source` for `ir`'s dead times: `source` itself when the
/// model declares none or `source` is already a view.
pub fn delayed<'a>(ir: &Ir, source: &'a dyn Source) -> Result<Delayed<'a>, DelayError> {
    if ir.delays.is_empty() || source.dead_time_applied() {
        return Ok(Delayed {
            inner: source,
            lags: None,
            shifted: None,
        });
    }
    let lags = dead_times(ir, source.name(), source.step())?;
    let shifted = source.in_memory().map(|e| shift(e, &lags));
    Ok(Delayed {
        inner: source,
        lags: Some(lags),
        shifted,
    })
}

/// An in-memory record shifted: every column from sample `max`, each input
/// from `lag` samples earlier; empty when the record is no longer than `max`.
pub fn shift(e: &Experiment, lags: &DeadTimes) -> Experiment {
    let n = e.len();
    let m = lags.max;
    let tail = |c: &Vec<f64>| c.get(m.min(c.len())..).unwrap_or(&[]).to_vec();
    let inputs = e
        .inputs
        .iter()
        .zip(&lags.lags)
        .map(|(c, d)| {
            // d ≤ m; a column shorter than the record gives what it has.
            c.get(m.saturating_sub(*d)..n.saturating_sub(*d).max(m.saturating_sub(*d)))
                .map_or_else(Vec::new, <[f64]>::to_vec)
        })
        .collect();
    Experiment {
        name: e.name.clone(),
        h: e.h,
        states: e.states.iter().map(tail).collect(),
        inputs,
        heading: tail(&e.heading),
        rotation: e.rotation.iter().map(tail).collect(),
        disturbances: e.disturbances.iter().map(tail).collect(),
    }
}

impl Delayed<'_> {
    /// The samples at the record's start that have no equation (0 without
    /// a dead time).
    pub fn dropped(&self) -> usize {
        self.lags.as_ref().map_or(0, |l| l.max)
    }
}

impl Source for Delayed<'_> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn len(&self) -> usize {
        match &self.lags {
            Some(l) => self.inner.len().saturating_sub(l.max),
            None => self.inner.len(),
        }
    }
    fn step(&self) -> f64 {
        self.inner.step()
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        let Some(lags) = &self.lags else {
            return self.inner.visit(f);
        };
        if let Some(e) = &self.shifted {
            return e.rows(f);
        }
        // The last `max + 1` input rows, by sample modulo `max + 1`.
        let ring = lags.max + 1;
        let n_in = lags.lags.len();
        let mut past = vec![0.0; ring * n_in];
        let mut inputs = vec![0.0; n_in];
        let mut k = 0usize;
        self.inner.visit(&mut |row| {
            let slot = (k % ring) * n_in;
            for (p, u) in past[slot..slot + n_in].iter_mut().zip(row.inputs) {
                *p = *u;
            }
            if k >= lags.max {
                for (i, (u, d)) in inputs.iter_mut().zip(&lags.lags).enumerate() {
                    *u = past[((k - d) % ring) * n_in + i];
                }
                f(&Row {
                    inputs: &inputs,
                    ..*row
                });
            }
            k += 1;
        });
    }
    fn locate(&self, k: usize) -> String {
        self.inner.locate(k + self.dropped())
    }
    fn in_memory(&self) -> Option<&Experiment> {
        match &self.lags {
            Some(_) => self.shifted.as_ref(),
            None => self.inner.in_memory(),
        }
    }
    fn dead_time_applied(&self) -> bool {
        self.lags.is_some() || self.inner.dead_time_applied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_structure::{CompileOptions, compile};

    fn ir() -> Ir {
        compile(
            "model M { step 1 state u input a, b delay a 2 steps der u = X*u + A*a + B*b }",
            &CompileOptions::default(),
        )
        .ir
        .expect("an IR")
    }

    fn record() -> Experiment {
        Experiment {
            name: "e".into(),
            h: 1.0,
            states: vec![(0..6).map(f64::from).collect()],
            inputs: vec![
                (10..16).map(f64::from).collect(),
                (20..26).map(f64::from).collect(),
            ],
            heading: Vec::new(),
            rotation: Vec::new(),
            disturbances: Vec::new(),
        }
    }

    /// A source that hides that it is in memory, as a file does.
    struct Streamed(Experiment);
    impl Source for Streamed {
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

    fn rows(s: &dyn Source) -> Vec<(f64, f64, f64)> {
        let mut out = Vec::new();
        s.visit(&mut |r| out.push((r.states[0], r.inputs[0], r.inputs[1])));
        out
    }

    #[test]
    fn the_equation_at_k_sees_the_input_d_samples_earlier_in_memory_and_streamed() {
        let ir = ir();
        let e = record();
        let want = vec![
            (2.0, 10.0, 22.0),
            (3.0, 11.0, 23.0),
            (4.0, 12.0, 24.0),
            (5.0, 13.0, 25.0),
        ];
        let view = delayed(&ir, &e).expect("whole");
        assert_eq!(rows(&view), want);
        assert_eq!(view.len(), 4);
        assert!(view.in_memory().is_some());
        let streamed = Streamed(e.clone());
        let view = delayed(&ir, &streamed).expect("whole");
        assert_eq!(rows(&view), want);
        assert!(view.in_memory().is_none());
        assert_eq!(view.locate(0), "experiment `e`, sample 3");
        // A view of a view is the view.
        let again = delayed(&ir, &view).expect("whole");
        assert_eq!(rows(&again), want);
    }

    #[test]
    fn a_record_no_longer_than_the_dead_time_has_no_equation() {
        let short = record().truncated(2);
        let view = delayed(&ir(), &short).expect("whole");
        assert_eq!(view.len(), 0);
        assert!(rows(&view).is_empty());
    }
}
