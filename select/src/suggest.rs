//! What the chosen model may lack: the one-step residual of each equation
//! correlated with simple regressors the model does not declare in it
//! (`s`, `s*|s|`, `s*t`, `s*|t|` of the states, and the inputs), each
//! evaluated on the model's own free run — an instrument, uncorrelated with
//! the disturbances in open loop, so a residual that a coloured current
//! drives does not make a term look missing (as least-squares residual
//! analysis would). Regressors the data cannot tell apart (equal
//! correlations) are listed once. A suggestion to consider as a candidate,
//! not a selection.

use leeway_model::experiment::{Experiment, Row, Source};
use leeway_model::model::{Model, Signals, planar_rotation};
use leeway_model::simulate::{Disturbances, simulate};
use leeway_structure::grammar::EquationKind;
use leeway_structure::ir::{Ir, Rotation, Signal};
use serde::Serialize;

/// The previous sample: measured states, inputs, heading, disturbances.
type Previous = (Vec<f64>, Vec<f64>, f64, Vec<f64>);

/// Suggestions listed, the strongest first.
pub const SUGGESTIONS: usize = 5;

/// A regressor the model lacks in one equation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Suggestion {
    /// The state whose equation lacks it.
    pub equation: String,
    /// The term, in the model's names (`r*|r|`).
    pub term: String,
    /// Correlation of the equation's one-step residual with it, over every sample.
    pub correlation: f64,
}

/// One undeclared regressor: its text, the signals it multiplies (state or
/// input, with a modulus flag), sorted as the model's terms are compared.
struct Library {
    text: String,
    factors: Vec<(Signal, bool)>,
}

fn library(ir: &Ir) -> Vec<Library> {
    let n = ir.states.len();
    let s = |i: usize| ir.states[i].clone();
    let mut out = Vec::new();
    for i in 0..n {
        out.push(Library {
            text: s(i),
            factors: vec![(Signal::State(i), false)],
        });
        out.push(Library {
            text: format!("{}*|{}|", s(i), s(i)),
            factors: vec![(Signal::State(i), false), (Signal::State(i), true)],
        });
        for j in 0..n {
            if j > i {
                out.push(Library {
                    text: format!("{}*{}", s(i), s(j)),
                    factors: vec![(Signal::State(i), false), (Signal::State(j), false)],
                });
            }
            if j != i {
                out.push(Library {
                    text: format!("{}*|{}|", s(i), s(j)),
                    factors: vec![(Signal::State(i), false), (Signal::State(j), true)],
                });
            }
        }
    }
    for (k, name) in ir.inputs.iter().enumerate() {
        out.push(Library {
            text: name.clone(),
            factors: vec![(Signal::Input(k), false)],
        });
    }
    for l in &mut out {
        l.factors.sort_by_key(|f| key(*f));
    }
    out
}

fn key((signal, modulus): (Signal, bool)) -> (usize, usize, bool) {
    match signal {
        Signal::State(i) => (0, i, modulus),
        Signal::Input(i) => (1, i, modulus),
    }
}

/// Whether output `o` already has a term on these signals (a relative
/// velocity counts as its state: `water.u*|water.u|` is `u*|u|`).
fn declared(ir: &Ir, o: usize, factors: &[(Signal, bool)]) -> bool {
    ir.terms.iter().filter(|t| t.output == o).any(|t| {
        let mut f: Vec<(Signal, bool)> = t
            .factors
            .iter()
            .map(|f| (f.arg.signal, f.modulus))
            .collect();
        f.sort_by_key(|x| key(*x));
        f == factors
    })
}

fn value(row: &Row, factors: &[(Signal, bool)]) -> f64 {
    factors.iter().fold(1.0, |acc, (signal, modulus)| {
        let x = match signal {
            Signal::State(i) => row.states[*i],
            Signal::Input(i) => row.inputs[*i],
        };
        acc * if *modulus { x.abs() } else { x }
    })
}

/// The strongest correlations of the equations' one-step residuals (θ,
/// unmeasured disturbances at `means`) with undeclared regressors. Empty
/// for a model with dead times or a measured rotation (whose one-step
/// residual this does not form).
pub fn missing_terms(
    model: &dyn Model,
    theta: &[f64],
    means: &[f64],
    experiments: &[Experiment],
) -> Vec<Suggestion> {
    let ir = model.ir();
    if !ir.delays.is_empty() || matches!(ir.rotation, Rotation::Measured { .. }) {
        return Vec::new();
    }
    let lib = library(ir);
    let n_out = ir.states.len();
    let wanted: Vec<(usize, usize)> = (0..n_out)
        .flat_map(|o| (0..lib.len()).map(move |l| (o, l)))
        .filter(|(o, l)| !declared(ir, *o, &lib[*l].factors))
        .collect();
    // Per (output, regressor): Σx, Σy, Σx², Σy², Σxy.
    let mut sums = vec![[0.0f64; 5]; wanted.len()];
    let planar = matches!(ir.rotation, Rotation::Planar { .. });
    let held = Disturbances::Constant(means);
    let mut dist = vec![0.0; ir.components.len()];
    let mut f = vec![0.0; n_out];
    for e in experiments {
        let h = e.h;
        let run = simulate(model, theta, e, held);
        if run.diverged {
            continue;
        }
        let mut previous: Option<Previous> = None;
        let mut k = 0usize;
        let mut sim = vec![0.0; n_out];
        e.visit(&mut |row| {
            if let Some((y, u, psi, d)) = &previous {
                let rot = planar_rotation(*psi);
                let sig = Signals {
                    states: y,
                    inputs: u,
                    rotation: if planar { &rot } else { &[] },
                    disturbances: d,
                };
                model.rhs(theta, &sig, &mut f);
                for (i, v) in sim.iter_mut().enumerate() {
                    *v = run.states[i][k - 1];
                }
                let prev = Row {
                    states: &sim,
                    inputs: u,
                    heading: *psi,
                    rotation: &[],
                    disturbances: d,
                };
                for ((o, l), s) in wanted.iter().zip(sums.iter_mut()) {
                    let target = match ir.equations[*o].kind {
                        EquationKind::Der => (row.states[*o] - y[*o]) / h,
                        EquationKind::Next => row.states[*o],
                    };
                    let eps = target - f[*o];
                    let x = value(&prev, &lib[*l].factors);
                    s[0] += x;
                    s[1] += eps;
                    s[2] += x * x;
                    s[3] += eps * eps;
                    s[4] += x * eps;
                }
            }
            held.fill(ir, row.disturbances, &mut dist);
            previous = Some((
                row.states.to_vec(),
                row.inputs.to_vec(),
                row.heading,
                dist.clone(),
            ));
            k += 1;
        });
    }
    let count: usize = experiments.iter().map(|e| e.len().saturating_sub(1)).sum();
    let n = count.max(1) as f64;
    let mut out: Vec<Suggestion> = wanted
        .iter()
        .zip(&sums)
        .filter_map(|((o, l), s)| {
            let (mx, my) = (s[0] / n, s[1] / n);
            let vx = s[2] / n - mx * mx;
            let vy = s[3] / n - my * my;
            let c = (s[4] / n - s[0] * s[1] / (n * n)) / (vx * vy).sqrt();
            c.is_finite().then(|| Suggestion {
                equation: ir.states[*o].clone(),
                term: lib[*l].text.clone(),
                correlation: c,
            })
        })
        .collect();
    // The strongest first; of regressors equal on these data, the first written.
    out.sort_by(|a, b| b.correlation.abs().total_cmp(&a.correlation.abs()));
    out.dedup_by(|b, a| a.equation == b.equation && a.correlation == b.correlation);
    out.truncate(SUGGESTIONS);
    out
}
