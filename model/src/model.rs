//! The [`Model`] trait: what every compiled model offers, whether generated
//! by `include_model!` or interpreted from the IR at run time.

use leeway_structure::grammar::EquationKind;
use leeway_structure::ir::{Ir, PredictorKind, Report, Rotation};

/// The signals of one sample, as regressors read them.
#[derive(Clone, Copy, Debug)]
pub struct Signals<'a> {
    /// States (measured `y`, or simulated `x`), in declaration order.
    pub states: &'a [f64],
    /// Inputs.
    pub inputs: &'a [f64],
    /// Rotation variables: `[cos ψ, sin ψ]` for a planar heading, the
    /// declared columns of a measured `R`, empty without rotation.
    pub rotation: &'a [f64],
    /// Disturbance components by global index (earth-frame components in the
    /// earth frame). Regressors read only measured ones; simulation reads all.
    pub disturbances: &'a [f64],
}

/// Some slots of a predictor's regressor buffer ([`Model::regressor_slots`]).
pub trait SlotRegressors: Send + Sync {
    /// Writes the chosen slots of `out` at the signals `sig` and the sign
    /// pattern `signs`, as [`Model::regressors_update`] writes them.
    fn update(&self, sig: &Signals, signs: &[f64], out: &mut [f64]);
    /// Whether [`SlotRegressors::update_block`] evaluates a block at once
    /// (the interpreter's plans); else it is [`SlotRegressors::update`]
    /// sample by sample, and a walk is better off calling that.
    fn evaluates_blocks(&self) -> bool {
        false
    }
    /// The chosen slots of a block of `n = samples.len()` samples,
    /// slot-major: slot `k` of sample `s` at `out[k · n + s]`, bit for bit
    /// what [`SlotRegressors::update`] writes sample by sample; the other
    /// slots of `out` are left as they are. `signs` holds `n_signs` values
    /// per sample. By default sample by sample, through a buffer.
    fn update_block(&self, samples: &[Signals], signs: &[f64], n_signs: usize, out: &mut [f64]) {
        let n = samples.len();
        let slots = out.len() / n.max(1);
        let mut one = vec![0.0; slots];
        for (s, sig) in samples.iter().enumerate() {
            for (k, v) in one.iter_mut().enumerate() {
                *v = out[k * n + s];
            }
            self.update(sig, &signs[s * n_signs..(s + 1) * n_signs], &mut one);
            for (k, v) in one.iter().enumerate() {
                out[k * n + s] = *v;
            }
        }
    }
}

/// A compiled second-order modulus model.
///
/// Regressor buffers are dense, row-major by output: the value of column `j`
/// in output `o` is `out[o * n_columns + j]`. Every method writes every entry
/// of its buffer and allocates nothing.
pub trait Model: Send + Sync {
    /// The model's structure and report as data.
    fn ir(&self) -> &Ir;
    /// IV1's regressors `Φ(y, u)` (θ columns, every modulus pointwise).
    fn basic(&self, sig: &Signals, out: &mut [f64]);
    /// IV2's regressors `[Φ; Φ_ρ; Φ_λ]` for a sign pattern (`±1` per sign argument).
    fn augmented(&self, sig: &Signals, signs: &[f64], out: &mut [f64]);
    /// IV3's regressors: augmented for unmeasured media, `Φ2(y − R·y_aux)`
    /// pointwise for measured ones.
    fn measured(&self, sig: &Signals, signs: &[f64], out: &mut [f64]);
    /// The right-hand side `f(x, u, R, v; θ)` of every equation, moduli pointwise,
    /// with the given disturbance values.
    fn rhs(&self, theta: &[f64], sig: &Signals, out: &mut [f64]);

    /// The model's name.
    fn name(&self) -> &str {
        &self.ir().name
    }
    /// Number of columns of a predictor.
    fn n_columns(&self, kind: PredictorKind) -> usize {
        self.ir().predictors.get(kind).len()
    }
    /// Number of outputs (states).
    fn n_outputs(&self) -> usize {
        self.ir().states.len()
    }
    /// Regressors of any predictor (signs ignored by the basic one).
    fn regressors(&self, kind: PredictorKind, sig: &Signals, signs: &[f64], out: &mut [f64]) {
        match kind {
            PredictorKind::Basic => self.basic(sig, out),
            PredictorKind::Augmented => self.augmented(sig, signs, out),
            PredictorKind::Measured => self.measured(sig, signs, out),
        }
    }
    /// [`Model::regressors`] into a buffer that already holds zeros in the
    /// predictor's structurally zero slots (zeroed once, then only ever
    /// written by this method for the same predictor): only the other slots
    /// are written, which saves a sample's zero fill in a pass that reuses
    /// one buffer. Generated code writes just those slots; the default
    /// writes every slot.
    fn regressors_update(
        &self,
        kind: PredictorKind,
        sig: &Signals,
        signs: &[f64],
        out: &mut [f64],
    ) {
        self.regressors(kind, sig, signs, out);
    }
    /// An evaluator of only the `wanted` slots of `kind`'s regressor buffer
    /// (`n_outputs × n_columns`), for a pass that reads no others: the
    /// other slots are left as they are. `None` (the default) where the
    /// model evaluates every slot as cheaply; the interpreter's evaluator
    /// computes each wanted slot operation for operation as
    /// [`Model::regressors_update`] does, so its values are the same bits.
    fn regressor_slots(
        &self,
        _kind: PredictorKind,
        _wanted: &[bool],
    ) -> Option<Box<dyn SlotRegressors>> {
        None
    }
    /// The compile-time identifiability report.
    fn report(&self) -> &Report {
        &self.ir().report
    }
    /// One simulation step: `x⁺ = x + h f` (`der`) or `x⁺ = f` (`next`), with
    /// `f` evaluated at the given disturbance values.
    fn step(&self, theta: &[f64], h: f64, sig: &Signals, f: &mut [f64], next: &mut [f64]) {
        self.rhs(theta, sig, f);
        for (o, eq) in self.ir().equations.iter().enumerate() {
            next[o] = match eq.kind {
                EquationKind::Der => sig.states[o] + h * f[o],
                EquationKind::Next => f[o],
            };
        }
    }
}

/// `[cos ψ, sin ψ]`: the rotation variables of a planar heading.
pub fn planar_rotation(psi: f64) -> [f64; 2] {
    [psi.cos(), psi.sin()]
}

/// Largest step [`rotated`] takes by its series; larger ones use `sin_cos`.
pub const SMALL_STEP: f64 = 0.5;

/// `sin δ / δ` and `cos δ` as polynomials in `x = δ²`: the Taylor
/// coefficients up to δ¹⁵ and δ¹⁶ (the first omitted terms are below 2⁻⁶⁰
/// relative for |δ| ≤ 1/2).
const SIN_SERIES: [f64; 8] = [
    1.0,
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5040.0,
    1.0 / 362880.0,
    -1.0 / 39916800.0,
    1.0 / 6227020800.0,
    -1.0 / 1307674368000.0,
];
const COS_SERIES: [f64; 9] = [
    1.0,
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40320.0,
    -1.0 / 3628800.0,
    1.0 / 479001600.0,
    -1.0 / 87178291200.0,
    1.0 / 20922789888000.0,
];

/// `Σ c_k x^k` for eight coefficients by Estrin's scheme: a short chain of
/// dependent operations (Horner's would be as slow as a `sincos`).
fn estrin8(c: &[f64], x: f64, x2: f64, x4: f64) -> f64 {
    let p01 = c[0] + c[1] * x;
    let p23 = c[2] + c[3] * x;
    let p45 = c[4] + c[5] * x;
    let p67 = c[6] + c[7] * x;
    (p01 + p23 * x2) + (p45 + p67 * x2) * x4
}

/// `[cos(ψ + δ), sin(ψ + δ)]` from `r = [cos ψ, sin ψ]`: for the small
/// steps of a heading (|δ| ≤ [`SMALL_STEP`]) by the Taylor series of
/// `cos δ`, `sin δ`, which costs a fraction of a `sincos`.
pub fn rotated(r: [f64; 2], delta: f64) -> [f64; 2] {
    let (s, c) = if delta.abs() <= SMALL_STEP {
        let x = delta * delta;
        let x2 = x * x;
        let x4 = x2 * x2;
        let s = delta * estrin8(&SIN_SERIES, x, x2, x4);
        let c = estrin8(&COS_SERIES, x, x2, x4) + COS_SERIES[8] * (x4 * x4);
        (s, c)
    } else {
        delta.sin_cos()
    };
    [r[0] * c - r[1] * s, r[1] * c + r[0] * s]
}

/// `[cos ψ, sin ψ]` of a record's headings, sample by sample: rotated from
/// the previous sample's by the (small) difference, and computed afresh
/// every [`HeadingRotation::REANCHOR`] samples (or after a large jump), so
/// rounding cannot drift — a fraction of the cost of a `sincos` a sample.
#[derive(Clone, Debug)]
pub struct HeadingRotation {
    psi: f64,
    rot: [f64; 2],
    since: usize,
}

impl Default for HeadingRotation {
    fn default() -> HeadingRotation {
        HeadingRotation {
            psi: f64::NAN,
            rot: [1.0, 0.0],
            since: HeadingRotation::REANCHOR,
        }
    }
}

impl HeadingRotation {
    /// Samples between exact evaluations.
    pub const REANCHOR: usize = 8;

    /// The rotation of the next heading.
    pub fn next(&mut self, psi: f64) -> [f64; 2] {
        let delta = psi - self.psi;
        if self.since >= Self::REANCHOR || delta.is_nan() || delta.abs() > SMALL_STEP {
            self.rot = planar_rotation(psi);
            self.since = 0;
        } else {
            self.rot = rotated(self.rot, delta);
            self.since += 1;
        }
        self.psi = psi;
        self.rot
    }
}

/// The heading after one step: `ψ⁺ = ψ + h·r` (planar heading only).
pub fn next_heading(ir: &Ir, psi: f64, h: f64, states: &[f64]) -> f64 {
    match &ir.rotation {
        Rotation::Planar { integrates, .. } => psi + h * states[*integrates],
        _ => psi,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_rotations_match_sincos_to_an_ulp() {
        for &psi in &[0.0, 0.3, -2.0, 40.0, 1e4] {
            for k in -600..=600 {
                let delta = f64::from(k) * 0.001;
                let [c, s] = rotated(planar_rotation(psi), delta);
                let [ce, se] = planar_rotation(psi + delta);
                // psi + delta itself rounds by up to half an ulp of psi.
                let tol = 4.0 * f64::EPSILON * (1.0 + psi.abs());
                assert!(
                    (c - ce).abs() <= tol && (s - se).abs() <= tol,
                    "{psi} {delta}"
                );
            }
        }
    }

    #[test]
    fn heading_rotations_do_not_drift() {
        let mut headings = HeadingRotation::default();
        let mut psi = 0.3;
        for k in 0..10_000 {
            // Small steps of both signs, a jump now and then.
            psi += if k % 997 == 0 {
                2.5
            } else {
                0.4 * (f64::from(k) * 0.37).sin()
            };
            let [c, s] = headings.next(psi);
            let [ce, se] = planar_rotation(psi);
            let tol = 16.0 * f64::EPSILON * (1.0 + psi.abs());
            assert!((c - ce).abs() <= tol && (s - se).abs() <= tol, "sample {k}");
        }
    }
}
