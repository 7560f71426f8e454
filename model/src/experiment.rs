//! Samples as estimators read them ([`Row`], [`Source`]) and experiments
//! held in memory ([`Experiment`]). A source is anything visited in order —
//! held in memory, generated, or streamed from a file — and names where each
//! sample came from ([`Source::locate`]); its samples are visited in passes
//! ([`Source::visit`]), so a streamed one is never collected whole.

use leeway_structure::ir::{Ir, Rotation};

/// The smallest number of samples an experiment may have.
pub const MIN_SAMPLES: usize = 10;

/// The data column a model signal is read from (`data { }` mapping or its own name).
pub fn column_name(ir: &Ir, signal: &str) -> String {
    ir.data_columns
        .get(signal)
        .cloned()
        .unwrap_or_else(|| signal.to_string())
}

/// One sample as estimators read it.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// Measured states.
    pub states: &'a [f64],
    /// Inputs.
    pub inputs: &'a [f64],
    /// Measured heading (planar rotation; 0 otherwise).
    pub heading: f64,
    /// Measured rotation columns (measured `R`; empty otherwise).
    pub rotation: &'a [f64],
    /// Disturbance components by global index; measured ones from the data,
    /// unmeasured ones 0.
    pub disturbances: &'a [f64],
}

/// A sequence of samples that can be visited any number of times, in order.
pub trait Source: Sync {
    /// The experiment's name (file, or value of the `experiment` column).
    fn name(&self) -> &str;
    /// Number of samples.
    fn len(&self) -> usize;
    /// True when there are no samples.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The sample time `h`.
    fn step(&self) -> f64;
    /// Calls `f` on every sample in order.
    fn visit(&self, f: &mut dyn FnMut(&Row));
    /// Calls `f` on the first `n` samples in order (every sample, if fewer):
    /// what a [`Head`] of the record visits. A streamed source stops reading
    /// after them; this default visits every sample and passes on the first `n`.
    fn visit_head(&self, n: usize, f: &mut dyn FnMut(&Row)) {
        let mut k = 0usize;
        self.visit(&mut |row| {
            if k < n {
                f(row);
            }
            k += 1;
        });
    }
    /// Where sample `k` (from 0) comes from, for messages: `file:line` for a
    /// file, the experiment and sample otherwise.
    fn locate(&self, k: usize) -> String {
        format!("experiment `{}`, sample {}", self.name(), k + 1)
    }
    /// The experiment itself when its samples are held in memory: passes
    /// then walk its columns directly, and an estimate may keep what its
    /// passes compute per sample for its later passes (its memory then
    /// grows with the record, as the record's own does). Streamed sources
    /// say `None`.
    fn in_memory(&self) -> Option<&Experiment> {
        None
    }
    /// True for a view that already gives the model's dead times
    /// ([`Delayed`](crate::delay::Delayed)): its samples are the equations'.
    /// Note that the [`Experiment`] an in-memory view holds says `false`:
    /// hand consumers the view, not its columns.
    fn dead_time_applied(&self) -> bool {
        false
    }
}

/// An experiment held in memory, column by column.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// Name.
    pub name: String,
    /// Sample time.
    pub h: f64,
    /// `states[i][k]`.
    pub states: Vec<Vec<f64>>,
    /// `inputs[i][k]`.
    pub inputs: Vec<Vec<f64>>,
    /// Heading per sample (planar rotation), else empty.
    pub heading: Vec<f64>,
    /// `rotation[c][k]` for a measured `R`.
    pub rotation: Vec<Vec<f64>>,
    /// `disturbances[c][k]` for measured components; empty for unmeasured ones.
    pub disturbances: Vec<Vec<f64>>,
}

impl Experiment {
    /// An empty experiment shaped for a model.
    pub fn new(ir: &Ir, name: &str, h: f64) -> Experiment {
        Experiment {
            name: name.to_string(),
            h,
            states: vec![Vec::new(); ir.states.len()],
            inputs: vec![Vec::new(); ir.inputs.len()],
            heading: Vec::new(),
            rotation: vec![
                Vec::new();
                if matches!(ir.rotation, Rotation::Measured { .. }) {
                    ir.rotation_vars.len()
                } else {
                    0
                }
            ],
            disturbances: vec![Vec::new(); ir.components.len()],
        }
    }
    /// Appends one sample (`heading` ignored without a planar rotation,
    /// `disturbances` read only for measured components).
    pub fn push(&mut self, ir: &Ir, row: &Row) {
        for (c, v) in self.states.iter_mut().zip(row.states) {
            c.push(*v);
        }
        for (c, v) in self.inputs.iter_mut().zip(row.inputs) {
            c.push(*v);
        }
        if matches!(ir.rotation, Rotation::Planar { .. }) {
            self.heading.push(row.heading);
        }
        for (c, v) in self.rotation.iter_mut().zip(row.rotation) {
            c.push(*v);
        }
        for (i, comp) in ir.components.iter().enumerate() {
            if ir.disturbances[comp.disturbance].measured {
                self.disturbances[i].push(row.disturbances.get(i).copied().unwrap_or(0.0));
            }
        }
    }
    /// True when this experiment's first samples are `prefix`'s samples,
    /// bit for bit (same step, same columns).
    pub fn begins_with(&self, prefix: &Experiment) -> bool {
        let same = |a: &[f64], b: &[f64]| {
            b.len() <= a.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
        };
        let columns = |a: &[Vec<f64>], b: &[Vec<f64>]| {
            a.len() == b.len() && a.iter().zip(b).all(|(a, b)| same(a, b))
        };
        self.h.to_bits() == prefix.h.to_bits()
            && prefix.len() <= self.len()
            && columns(&self.states, &prefix.states)
            && columns(&self.inputs, &prefix.inputs)
            && same(&self.heading, &prefix.heading)
            && self.heading.is_empty() == prefix.heading.is_empty()
            && columns(&self.rotation, &prefix.rotation)
            && columns(&self.disturbances, &prefix.disturbances)
    }

    /// The samples from sample `first` on.
    pub fn from_sample(&self, first: usize) -> Experiment {
        let cut = |c: &Vec<f64>| c.get(first.min(c.len())..).unwrap_or(&[]).to_vec();
        Experiment {
            name: self.name.clone(),
            h: self.h,
            states: self.states.iter().map(cut).collect(),
            inputs: self.inputs.iter().map(cut).collect(),
            heading: cut(&self.heading),
            rotation: self.rotation.iter().map(cut).collect(),
            disturbances: self.disturbances.iter().map(cut).collect(),
        }
    }

    /// The first `n` samples.
    pub fn truncated(&self, n: usize) -> Experiment {
        self.slice(0..n)
    }

    /// The samples `range` (clamped to the experiment).
    pub fn slice(&self, range: std::ops::Range<usize>) -> Experiment {
        let cut = |c: &[f64]| {
            let end = range.end.min(c.len());
            c[range.start.min(end)..end].to_vec()
        };
        let cut_all = |v: &Vec<Vec<f64>>| v.iter().map(|c| cut(c)).collect();
        Experiment {
            name: self.name.clone(),
            h: self.h,
            states: cut_all(&self.states),
            inputs: cut_all(&self.inputs),
            heading: cut(&self.heading),
            rotation: cut_all(&self.rotation),
            disturbances: cut_all(&self.disturbances),
        }
    }
}

impl Source for Experiment {
    fn name(&self) -> &str {
        &self.name
    }
    fn len(&self) -> usize {
        self.states.first().map_or(0, Vec::len)
    }
    fn step(&self) -> f64 {
        self.h
    }
    fn in_memory(&self) -> Option<&Experiment> {
        Some(self)
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        self.rows(f);
    }
    fn visit_head(&self, n: usize, f: &mut dyn FnMut(&Row)) {
        self.head_rows(n, f);
    }
}

/// The first samples of a record, as a record of its own: what a
/// refinement on a subsample reads (`EstimateOptions::refine_subsample`).
/// A streamed record is read only as far as its head; one held in memory
/// is copied that far, so that passes walk its columns as they walk the
/// whole record's.
pub struct Head<'a> {
    source: &'a dyn Source,
    n: usize,
    memory: Option<Experiment>,
}

impl<'a> Head<'a> {
    /// The first `n` samples of `source` (all of them, if it has fewer).
    pub fn new(source: &'a dyn Source, n: usize) -> Head<'a> {
        let n = n.min(source.len());
        Head {
            source,
            n,
            memory: source.in_memory().map(|x| x.truncated(n)),
        }
    }
}

impl Source for Head<'_> {
    fn name(&self) -> &str {
        self.source.name()
    }
    fn len(&self) -> usize {
        self.n
    }
    fn step(&self) -> f64 {
        self.source.step()
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        self.source.visit_head(self.n, f);
    }
    fn visit_head(&self, n: usize, f: &mut dyn FnMut(&Row)) {
        self.source.visit_head(n.min(self.n), f);
    }
    fn locate(&self, k: usize) -> String {
        self.source.locate(k)
    }
    fn in_memory(&self) -> Option<&Experiment> {
        self.memory.as_ref()
    }
    fn dead_time_applied(&self) -> bool {
        self.source.dead_time_applied()
    }
}

impl Experiment {
    /// Calls `f` on every sample in order, as [`Source::visit`] does;
    /// generic, so that `f` is inlined into the loop.
    pub fn rows<F: FnMut(&Row)>(&self, f: F) {
        self.rows_from(0, f);
    }

    /// Calls `f` on every sample from sample `start` on, in order.
    pub fn rows_from<F: FnMut(&Row)>(&self, start: usize, f: F) {
        self.rows_between(start, self.len(), f);
    }

    /// Calls `f` on the first `n` samples, in order.
    fn head_rows<F: FnMut(&Row)>(&self, n: usize, f: F) {
        self.rows_between(0, n.min(self.len()), f);
    }

    /// Calls `f` on the samples `start..end`, in order.
    fn rows_between<F: FnMut(&Row)>(&self, start: usize, end: usize, mut f: F) {
        let mut states = vec![0.0; self.states.len()];
        let mut inputs = vec![0.0; self.inputs.len()];
        let mut rotation = vec![0.0; self.rotation.len()];
        let mut dist = vec![0.0; self.disturbances.len()];
        for k in start..end {
            for (d, c) in states.iter_mut().zip(&self.states) {
                *d = c[k];
            }
            for (d, c) in inputs.iter_mut().zip(&self.inputs) {
                *d = c[k];
            }
            for (d, c) in rotation.iter_mut().zip(&self.rotation) {
                *d = c[k];
            }
            for (d, c) in dist.iter_mut().zip(&self.disturbances) {
                *d = c.get(k).copied().unwrap_or(0.0);
            }
            let heading = self.heading.get(k).copied().unwrap_or(0.0);
            f(&Row {
                states: &states,
                inputs: &inputs,
                heading,
                rotation: &rotation,
                disturbances: &dist,
            });
        }
    }
}
