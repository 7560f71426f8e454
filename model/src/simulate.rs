//! Simulation of a model on an input and the normalised fit. [`simulate`]
//! keeps the simulated states; [`simulate_each`] hands each sample's states
//! to a caller instead, in flat memory. Fits are per state and of the
//! unwrapped, integrated heading, `NaN` after a divergence. Validating θ on
//! recorded experiments is [`validation`](crate::validation).

use crate::delay::delayed;
use crate::experiment::{Experiment, Row, Source};
use crate::model::{HeadingRotation, Model, Signals, next_heading};
use leeway_structure::ir::{Ir, Rotation};

/// A simulated trajectory.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// `states[i][k]`.
    pub states: Vec<Vec<f64>>,
    /// Heading per sample (planar rotation), else empty.
    pub heading: Vec<f64>,
    /// True when the simulation left the finite numbers and was stopped.
    pub diverged: bool,
}

/// Disturbance values during a simulation.
#[derive(Clone, Copy, Debug)]
pub enum Disturbances<'a> {
    /// Every component zero (undisturbed).
    None,
    /// Constant values per global component (earth frame for earth disturbances);
    /// measured components are taken from the data when present.
    Constant(&'a [f64]),
    /// Every component, measured or not, as the data's row holds it: a
    /// source that made up the unmeasured ones puts them there.
    Recorded,
}

impl Disturbances<'_> {
    /// The values of every component at one sample: a measured component's
    /// recorded value (`recorded`), an unmeasured one's held value.
    pub fn fill(&self, ir: &Ir, recorded: &[f64], out: &mut [f64]) {
        for (c, value) in out.iter_mut().enumerate() {
            *value = if ir.disturbances[ir.components[c].disturbance].measured {
                recorded[c]
            } else {
                match self {
                    Disturbances::None => 0.0,
                    Disturbances::Constant(v) => v.get(c).copied().unwrap_or(0.0),
                    Disturbances::Recorded => recorded[c],
                }
            };
        }
    }
}

/// Simulates `model` with parameters `theta` from the data's first sample,
/// driven by the data's inputs (and, for a measured `R`, its rotation; for
/// measured disturbances, their recorded values). A planar heading is
/// integrated from the first measured heading. With dead times the
/// simulation runs on the samples the equations see ([`delayed`]): it
/// starts at sample `d_max`, and the trajectory covers the data's last
/// samples, from `d_max` on ([`fits`] aligns them).
pub fn simulate(
    model: &dyn Model,
    theta: &[f64],
    data: &dyn Source,
    disturbances: Disturbances,
) -> Trajectory {
    let ir = model.ir();
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let mut states = vec![Vec::with_capacity(data.len()); ir.states.len()];
    let mut heading = Vec::new();
    let diverged = simulate_each(model, theta, data, disturbances, &mut |_, x, psi| {
        for (s, v) in states.iter_mut().zip(x) {
            s.push(*v);
        }
        if planar {
            heading.push(psi);
        }
    });
    Trajectory {
        states,
        heading,
        diverged,
    }
}

/// Simulates as [`simulate`] does, handing `each` every sample's row with
/// the simulated states and heading at that sample (NaN once diverged)
/// instead of keeping them: memory flat in the samples, for a simulation
/// over a streamed record. Returns whether the simulation diverged. Rows
/// are the samples the equations see (dead times applied, [`delayed`]); a
/// dead time that is no whole number of the data's sample times (a model
/// without `step`, a record its loader did not check) gives no sample and
/// counts as diverged.
pub fn simulate_each(
    model: &dyn Model,
    theta: &[f64],
    data: &dyn Source,
    disturbances: Disturbances,
    each: &mut dyn FnMut(&Row, &[f64], f64),
) -> bool {
    let Ok(view) = delayed(model.ir(), data) else {
        return true;
    };
    let data: &dyn Source = &view;
    let mut run = Stepper::new(model, theta, disturbances, data.step());
    data.visit(&mut |row| run.push(row, &mut *each));
    run.diverged()
}

/// The simulation of [`simulate_each`] fed one row at a time, for a caller
/// that visits the rows itself (a pass that walks them for something else
/// too). The rows must be the samples the equations see (a [`delayed`]
/// view); fed the same rows, it gives what [`simulate_each`] gives, bit for
/// bit.
pub struct Stepper<'a> {
    model: &'a dyn Model,
    theta: &'a [f64],
    disturbances: Disturbances<'a>,
    h: f64,
    planar: bool,
    x: Vec<f64>,
    next: Vec<f64>,
    f: Vec<f64>,
    psi: f64,
    /// The integrated heading's rotation, by small steps (re-anchored).
    headings: HeadingRotation,
    dist: Vec<f64>,
    started: bool,
    diverged: bool,
}

impl<'a> Stepper<'a> {
    /// A simulation of `theta` with step `h`, begun at the first row fed.
    pub fn new(
        model: &'a dyn Model,
        theta: &'a [f64],
        disturbances: Disturbances<'a>,
        h: f64,
    ) -> Stepper<'a> {
        let ir = model.ir();
        let n_out = ir.states.len();
        Stepper {
            model,
            theta,
            disturbances,
            h,
            planar: matches!(ir.rotation, Rotation::Planar { .. }),
            x: vec![0.0; n_out],
            next: vec![0.0; n_out],
            f: vec![0.0; n_out],
            psi: 0.0,
            headings: HeadingRotation::default(),
            dist: vec![0.0; ir.components.len()],
            started: false,
            diverged: false,
        }
    }

    /// Hands `each` the row with the simulated states and heading at it
    /// (NaN once diverged), then steps to the next sample.
    #[inline]
    pub fn push(&mut self, row: &Row, each: impl FnOnce(&Row, &[f64], f64)) {
        let ir = self.model.ir();
        if !self.started {
            self.x.copy_from_slice(row.states);
            self.psi = row.heading;
            self.started = true;
        }
        each(row, &self.x, self.psi);
        self.disturbances.fill(ir, row.disturbances, &mut self.dist);
        let rot_buf;
        let rotation: &[f64] = if self.planar {
            rot_buf = self.headings.next(self.psi);
            &rot_buf
        } else {
            row.rotation
        };
        if !self.diverged {
            let sig = Signals {
                states: &self.x,
                inputs: row.inputs,
                rotation,
                disturbances: &self.dist,
            };
            self.model
                .step(self.theta, self.h, &sig, &mut self.f, &mut self.next);
            self.psi = next_heading(ir, self.psi, self.h, &self.x);
            if self.next.iter().any(|v| !v.is_finite() || v.abs() > 1e12) {
                self.diverged = true;
                self.next.fill(f64::NAN);
            }
            self.x.copy_from_slice(&self.next);
        }
    }

    /// The simulation left the finite numbers.
    pub fn diverged(&self) -> bool {
        self.diverged
    }
}

/// A simulation as `leeway simulate` writes it: the input experiment with
/// the simulated states and heading, cut before the first sample whose
/// states are not finite.
#[derive(Clone, Debug)]
pub struct Written {
    /// The experiment written.
    pub experiment: Experiment,
    /// Its samples (all of the input's unless the simulation diverged).
    pub samples: usize,
    /// The states left the finite numbers at `samples`.
    pub diverged: bool,
}

/// Simulates `model` with `theta` on the input `e` (see [`simulate`]) and
/// keeps the samples before any divergence.
pub fn simulate_written(
    model: &dyn Model,
    theta: &[f64],
    e: &Experiment,
    disturbances: Disturbances,
) -> Written {
    written(e, simulate(model, theta, e, disturbances))
}

/// The input `e` with a simulation's states and heading, cut before the
/// first sample whose states are not finite; with dead times, from sample
/// `d_max` on (the trajectory's first sample), the earlier rows being only
/// the delayed inputs' history.
pub fn written(e: &Experiment, trajectory: Trajectory) -> Written {
    let first = trajectory
        .states
        .first()
        .map_or(0, |s| e.len().saturating_sub(s.len()));
    let shifted;
    let e = if first > 0 {
        shifted = e.from_sample(first);
        &shifted
    } else {
        e
    };
    let samples = trajectory
        .states
        .first()
        .map_or(0, |s| s.iter().take_while(|v| v.is_finite()).count());
    let experiment = Experiment {
        states: trajectory.states,
        heading: trajectory.heading,
        ..e.clone()
    }
    .truncated(samples);
    Written {
        experiment,
        samples,
        diverged: trajectory.diverged,
    }
}

/// The normalised fit `100·(1 − ‖y − ŷ‖ / ‖y − ȳ‖)` (100 is perfect; may be
/// negative). `NaN` when the measurement is constant or the simulation diverged.
pub fn fit(y: &[f64], yhat: &[f64]) -> f64 {
    let n = y.len().min(yhat.len());
    if n == 0 {
        return f64::NAN;
    }
    let mean = y[..n].iter().sum::<f64>() / n as f64;
    let num: f64 = y[..n]
        .iter()
        .zip(&yhat[..n])
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    let den: f64 = y[..n]
        .iter()
        .map(|a| (a - mean) * (a - mean))
        .sum::<f64>()
        .sqrt();
    if den == 0.0 || !num.is_finite() {
        return f64::NAN;
    }
    100.0 * (1.0 - num / den)
}

/// Fit of every output of a simulation against an experiment, in the
/// model's state order: [`fit`] of each measured state against its
/// simulation, as `leeway validate` reports it. A trajectory shorter than
/// the data (dead times: it starts at sample `d_max`) is compared with the
/// data's last samples.
pub fn fits(data: &Experiment, sim: &Trajectory) -> Vec<f64> {
    data.states
        .iter()
        .zip(&sim.states)
        .map(|(y, s)| fit(tail(y, s.len()), s))
        .collect()
}

/// The last `n` values of `y` (all of them when it is shorter).
fn tail(y: &[f64], n: usize) -> &[f64] {
    &y[y.len().saturating_sub(n)..]
}

/// Fit of the integrated heading of a simulation against the measured one
/// ([`unwrap_heading`]), as `leeway validate` reports it; `NaN` when the
/// model has no planar heading (the simulation integrates none). Aligned
/// as [`fits`] aligns the states.
pub fn heading_fit(data: &Experiment, sim: &Trajectory) -> f64 {
    fit(
        &unwrap_heading(tail(&data.heading, sim.heading.len())),
        &sim.heading,
    )
}

/// The measured heading unwrapped (steps taken along the short arc), so that
/// it compares with a simulation, which integrates the yaw rate without
/// wrapping.
pub fn unwrap_heading(heading: &[f64]) -> Vec<f64> {
    use std::f64::consts::PI;
    let mut out = Vec::with_capacity(heading.len());
    let mut acc = 0.0;
    for (k, psi) in heading.iter().enumerate() {
        if k == 0 {
            acc = *psi;
        } else {
            let d = psi - heading[k - 1];
            acc += d - 2.0 * PI * ((d + PI) / (2.0 * PI)).floor();
        }
        out.push(acc);
    }
    out
}
