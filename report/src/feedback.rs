//! The closed-loop check's warnings ([`leeway_estimate::feedback`]).

use leeway_estimate::feedback::{Feedback, feedback};
use leeway_model::experiment::Source;
use leeway_model::number::short_number as num;
use leeway_model::warning::Warning;
use leeway_structure::ir::Ir;

/// What the estimators assume, and what feedback does to it.
const ASSUMES: &str = "the estimators assume the inputs independent of the disturbances (paper A1); under feedback an input also answers the disturbance the motion carries, which the instruments then share unless the equation error is white: the estimate can be biased, the more so the larger the disturbance";

/// The stretches of every experiment where the motion predicts an input.
pub fn closed_loop(ir: &Ir, experiments: &[&dyn Source]) -> Vec<Feedback> {
    experiments.iter().flat_map(|e| feedback(ir, *e)).collect()
}

/// One warning per stretch of [`closed_loop`].
pub fn closed_loop_alerts(stretches: &[Feedback]) -> Vec<Warning> {
    stretches
        .iter()
        .map(|f| {
            let inputs = f.inputs.join(", ");
            let share = format!("{:.0} %", 100.0 * f.explained);
            Warning::new(
                "closed-loop",
                format!(
                    "experiment `{}`, {} to {} s from its start: {inputs} follow the measured motion (closed loop, {share} explained)",
                    f.experiment,
                    num(f.from),
                    num(f.to)
                ),
                "a controller was in the loop there (dynamic positioning, an autopilot); leave the stretch out if the craft met disturbances",
                format!(
                    "experiment `{}`, samples {}–{} (t = {} to {} s from its start): the past motion explains {share} of what the inputs' own past leaves of {inputs}; {ASSUMES}",
                    f.experiment,
                    f.first,
                    f.last,
                    num(f.from),
                    num(f.to)
                ),
            )
        })
        .collect()
}
