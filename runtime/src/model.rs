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

/// `[cos(ψ + δ), sin(ψ + δ)]` from `r = [cos ψ, sin ψ]`: for the small
/// steps of a simulated heading (|δ| ≤ 1/16) by the Taylor series of
/// `cos δ`, `sin δ` to below an ulp, which costs a fraction of a `sincos`.
pub fn rotated(r: [f64; 2], delta: f64) -> [f64; 2] {
    let (s, c) = if delta.abs() <= 0.0625 {
        let d2 = delta * delta;
        // Horner form; the first omitted terms are below 2⁻⁶⁴ relative.
        let s = delta
            * (1.0
                - d2 / 6.0
                    * (1.0
                        - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0 * (1.0 - d2 / 110.0)))));
        let c = 1.0
            - d2 / 2.0
                * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 * (1.0 - d2 / 90.0))));
        (s, c)
    } else {
        delta.sin_cos()
    };
    [r[0] * c - r[1] * s, r[1] * c + r[0] * s]
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
            for k in -200..=200 {
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
}
