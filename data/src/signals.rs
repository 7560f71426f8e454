//! The signals a model reads from data, their roles and units.

use leeway_model::experiment::{Row, Source};
use leeway_structure::ir::{Ir, Rotation};

/// What a signal read from data is to the model (an index into its list).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Role {
    /// A state.
    State(usize),
    /// An input.
    Input(usize),
    /// The planar heading.
    Heading,
    /// An entry of a measured rotation.
    Rotation(usize),
    /// A component of a measured disturbance.
    Disturbance(usize),
}

/// The signals a model reads from data, as (signal name, role), in the
/// order of a row.
pub fn required_signals(ir: &Ir) -> Vec<(String, Role)> {
    let mut v: Vec<(String, Role)> = Vec::new();
    v.extend(
        ir.states
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), Role::State(i))),
    );
    v.extend(
        ir.inputs
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), Role::Input(i))),
    );
    match &ir.rotation {
        Rotation::Planar { heading, .. } => v.push((heading.clone(), Role::Heading)),
        Rotation::Measured { .. } => v.extend(
            ir.rotation_vars
                .iter()
                .enumerate()
                .map(|(i, s)| (s.clone(), Role::Rotation(i))),
        ),
        Rotation::None => {}
    }
    for (i, c) in ir.components.iter().enumerate() {
        if ir.disturbances[c.disturbance].measured {
            v.push((c.name.clone(), Role::Disturbance(i)));
        }
    }
    v
}

/// The factor converting a signal's declared unit to the base unit (1 when
/// none is declared).
pub fn unit_factor(ir: &Ir, signal: &str) -> f64 {
    ir.data_units
        .get(signal)
        .map_or(1.0, |u| leeway_structure::units::factor(u))
}

/// Unit check of a heading that integrates a yaw rate: the least-squares gain
/// of `Δψ/h` on `r` (≈ 1 when consistent, ≈ 57.3 when ψ is in degrees and r
/// in rad/s). `None` without a planar heading or with too little yaw motion.
pub fn heading_gain(ir: &Ir, e: &dyn Source) -> Option<f64> {
    let mut sums = HeadingGainSums::new(ir, e.step())?;
    e.visit(&mut |row| sums.push(row));
    sums.gain()
}

/// Wrapping hypotheses of a logged heading: none, ±π (radians), ±180
/// (degrees).
const HEADING_PERIODS: [Option<f64>; 3] = [None, Some(2.0 * std::f64::consts::PI), Some(360.0)];

/// The sums of [`heading_gain`] as an experiment's rows go by, so that the
/// check can share a visit with the others: [`HeadingGainSums::push`] every
/// row in order, then [`HeadingGainSums::gain`].
///
/// A log may wrap its heading at ±π (radians) or ±180 (degrees), or not at
/// all. The gain of `Δψ/h` on `r` is fitted under each hypothesis (removing
/// whole periods from every step) and the one that explains `Δψ/h` best is
/// kept: a threshold on the step size would mistake large steps in degrees
/// for wraps in radians.
pub struct HeadingGainSums {
    /// The state the heading integrates.
    integrates: usize,
    /// The sample time.
    h: f64,
    /// `(Σ r·y, Σ r², Σ y²)` per hypothesis, `y = Δψ/h`.
    sums: [(f64, f64, f64); 3],
    /// The previous row's heading and yaw rate.
    prev: Option<(f64, f64)>,
}

impl HeadingGainSums {
    /// Empty sums for samples `h` apart; `None` without a planar heading.
    pub fn new(ir: &Ir, h: f64) -> Option<HeadingGainSums> {
        let Rotation::Planar { integrates, .. } = &ir.rotation else {
            return None;
        };
        Some(HeadingGainSums {
            integrates: *integrates,
            h,
            sums: [(0.0, 0.0, 0.0); 3],
            prev: None,
        })
    }

    /// The next row of the experiment.
    pub fn push(&mut self, row: &Row) {
        let r = row.states.get(self.integrates).copied().unwrap_or(0.0);
        if let Some((psi1, r1)) = self.prev {
            for (period, (sxy, sxx, syy)) in HEADING_PERIODS.iter().zip(self.sums.iter_mut()) {
                let mut d = row.heading - psi1;
                if let Some(p) = period {
                    d -= p * (d / p).round();
                }
                let y = d / self.h;
                *sxy += r1 * y;
                *sxx += r1 * r1;
                *syy += y * y;
            }
        }
        self.prev = Some((row.heading, r));
    }

    /// The gain of the best hypothesis (`None` with too little yaw motion).
    pub fn gain(self) -> Option<f64> {
        self.sums
            .into_iter()
            .filter(|(_, sxx, _)| *sxx > 1e-12)
            .map(|(sxy, sxx, syy)| {
                let gain = sxy / sxx;
                (gain, syy - gain * sxy)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(gain, _)| gain)
    }
}
