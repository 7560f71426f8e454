//! The nominal steady state under constant inputs in calm conditions: where
//! a static input offset holds the craft (its body-frame velocities; the
//! heading may keep turning), and how fast it gets there.

use leeway_model::model::{Model, Signals, planar_rotation};
use leeway_structure::ir::Rotation;

/// A steady state and the time it takes to reach it.
#[derive(Clone, Debug, PartialEq)]
pub struct Steady {
    /// The states once settled.
    pub states: Vec<f64>,
    /// Samples until every state is within 37 % of its last change from
    /// the start (a first-order time constant's worth), at least 1.
    pub time_constant: usize,
}

/// Most samples a steady state may take.
pub const MAX_SAMPLES: usize = 20_000;

/// The steady state of `model` with `theta`, step `h`, constant `inputs`,
/// every disturbance zero, from rest; `None` when the simulation leaves the
/// finite numbers or does not settle within [`MAX_SAMPLES`].
pub fn steady_state(model: &dyn Model, theta: &[f64], h: f64, inputs: &[f64]) -> Option<Steady> {
    let ir = model.ir();
    let n = ir.states.len();
    let mut x = vec![0.0; n];
    let mut next = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    let dist = vec![0.0; ir.components.len()];
    // Without disturbances the rotation does not enter the body-frame
    // dynamics; any heading will do.
    let rotation = match ir.rotation {
        Rotation::Planar { .. } => planar_rotation(0.0).to_vec(),
        _ => Vec::new(),
    };
    let mut path: Vec<Vec<f64>> = Vec::new();
    for k in 0..MAX_SAMPLES {
        let sig = Signals {
            states: &x,
            inputs,
            rotation: &rotation,
            disturbances: &dist,
        };
        model.step(theta, h, &sig, &mut rhs, &mut next);
        if next.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let scale = next.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        let moved = x
            .iter()
            .zip(&next)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        std::mem::swap(&mut x, &mut next);
        path.push(x.clone());
        if moved <= 1e-9 * scale && k > 2 {
            return Some(Steady {
                time_constant: time_constant(&path, &x),
                states: x,
            });
        }
    }
    None
}

/// Samples until every state has covered 63 % of its way to `last`.
fn time_constant(path: &[Vec<f64>], last: &[f64]) -> usize {
    let mut tau = 1;
    for (i, target) in last.iter().enumerate() {
        if target.abs() < 1e-12 {
            continue;
        }
        let reached = path
            .iter()
            .position(|x| (x[i] / target) >= 0.632)
            .unwrap_or(path.len());
        tau = tau.max(reached + 1);
    }
    tau
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_model::Interpreter;

    fn model(src: &str) -> Interpreter {
        let c = leeway_structure::compile(src, &Default::default());
        Interpreter::new(c.ir.expect("compiles"))
    }

    #[test]
    fn a_first_order_surge_settles_at_its_balance() {
        // u' = -0.5 u + 0.1 f: steady u = 0.2 f, time constant 1/0.5 = 2 s = 20 samples.
        let m = model(
            "model M { step 0.1 state u input f der u = A*u + B*f nominal { A = -0.5, B = 0.1 } }",
        );
        let s = steady_state(&m, &[-0.5, 0.1], 0.1, &[3.0]).expect("settles");
        assert!((s.states[0] - 0.6).abs() < 1e-6, "{s:?}");
        // (1 − 0.05)^k ≤ 0.368 at k = 20.
        assert_eq!(s.time_constant, 20);
    }

    #[test]
    fn an_unstable_craft_has_no_steady_state() {
        let m = model("model M { step 0.1 state u input f der u = A*u + B*f }");
        assert_eq!(steady_state(&m, &[0.5, 0.1], 0.1, &[1.0]), None);
    }
}
