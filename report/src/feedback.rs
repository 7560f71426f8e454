//! The closed-loop check's warnings ([`leeway_estimate::feedback`]).

use leeway_estimate::feedback::{Feedback, feedback_each};
use leeway_model::experiment::Source;
use leeway_model::number::short_number as num;
use leeway_model::warning::Warning;
use leeway_structure::ir::Ir;

/// What the estimators assume, and what feedback does to it.
const ASSUMES: &str = "the estimators assume the inputs independent of the disturbances (paper A1); under feedback an input also answers the disturbance the motion carries, which the instruments then share unless the equation error is white: the estimate can be biased, the more so the larger the disturbance";

/// The stretches of every experiment where the motion predicts an input.
pub fn closed_loop(ir: &Ir, experiments: &[&dyn Source]) -> Vec<Feedback> {
    feedback_each(ir, experiments)
}

/// An experiment with more flagged stretches than this gets one warning
/// for all of them: a long record of smoothed random inputs can have dozens
/// of windows a controller seems to explain, and a terminal is not flooded.
pub const STRETCHES_APART: usize = 3;

/// Stretches named in the detail of an experiment's one warning.
const STRETCHES_LISTED: usize = 20;

/// One warning per stretch of [`closed_loop`], or one per experiment with
/// more than [`STRETCHES_APART`] of them, in experiment order.
pub fn closed_loop_alerts(stretches: &[Feedback]) -> Vec<Warning> {
    let mut out = Vec::new();
    for one in stretches.chunk_by(|a, b| a.experiment == b.experiment) {
        if one.len() > STRETCHES_APART {
            out.push(stretches_alert(one));
        } else {
            out.extend(one.iter().map(stretch_alert));
        }
    }
    out
}

fn stretch_alert(f: &Feedback) -> Warning {
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
        format!(
            "{CONTROLLER}; if the craft met disturbances, leave the stretch out: keep the rest, `--keep ..{}` and `--keep {}..` in seconds from the experiment's start (for a piece of a log, add the piece's start, which the data notes print), or the same as [[keep]] windows in the log's manifest (docs/logs.md)",
            num(f.from),
            num(f.to)
        ),
        format!(
            "experiment `{}`, samples {}–{} (t = {} to {} s from its start): the past motion explains {share} of what the inputs' own past leaves of {inputs}; {ASSUMES}",
            f.experiment,
            f.first,
            f.last,
            num(f.from),
            num(f.to)
        ),
    )
}

/// The help of a closed-loop warning.
const HELP: &str = "a controller was in the loop there (dynamic positioning, an autopilot); if the craft met disturbances, keep only the open-loop stretches (`--keep`, or [[keep]] windows in the log's manifest, docs/logs.md)";

/// What a closed-loop warning's help starts with.
const CONTROLLER: &str = "a controller was in the loop there (dynamic positioning, an autopilot)";

/// One warning for an experiment's many stretches (at least one).
fn stretches_alert(all: &[Feedback]) -> Warning {
    let mut inputs: Vec<&str> = Vec::new();
    for name in all.iter().flat_map(|f| &f.inputs) {
        if !inputs.contains(&name.as_str()) {
            inputs.push(name);
        }
    }
    let inputs = inputs.join(", ");
    let most = all.iter().map(|f| f.explained).fold(0.0, f64::max);
    let share = format!("{:.0} %", 100.0 * most);
    let (first, last) = (&all[0], &all[all.len() - 1]);
    let mut listed: Vec<String> = all
        .iter()
        .take(STRETCHES_LISTED)
        .map(|f| {
            format!(
                "samples {}–{} ({} to {} s, {}: {:.0} %)",
                f.first,
                f.last,
                num(f.from),
                num(f.to),
                f.inputs.join(", "),
                100.0 * f.explained
            )
        })
        .collect();
    if all.len() > STRETCHES_LISTED {
        listed.push(format!("and {} more", all.len() - STRETCHES_LISTED));
    }
    Warning::new(
        "closed-loop",
        format!(
            "experiment `{}`, {} stretches from {} to {} s from its start: {inputs} follow the measured motion (closed loop, up to {share} explained)",
            first.experiment,
            all.len(),
            num(first.from),
            num(last.to)
        ),
        HELP,
        format!(
            "experiment `{}`: the past motion explains at least half of what the inputs' own past leaves in {} stretches: {}; {ASSUMES}",
            first.experiment,
            all.len(),
            listed.join("; ")
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stretch(experiment: &str, k: usize, input: &str) -> Feedback {
        Feedback {
            experiment: experiment.to_string(),
            inputs: vec![input.to_string()],
            first: 1000 * k,
            last: 1000 * k + 99,
            from: 1000.0 * k as f64,
            to: 1000.0 * k as f64 + 99.0,
            explained: 0.5 + 0.01 * k as f64,
        }
    }

    #[test]
    fn many_stretches_of_one_experiment_are_one_warning() {
        let mut all: Vec<Feedback> = (0..45)
            .map(|k| stretch("long", k, if k % 2 == 0 { "tau1" } else { "tau2" }))
            .collect();
        all.extend((0..2).map(|k| stretch("short", k, "tau3")));
        let alerts = closed_loop_alerts(&all);
        assert_eq!(alerts.len(), 3, "{alerts:?}");
        assert_eq!(
            alerts[0].summary,
            "experiment `long`, 45 stretches from 0 to 44099 s from its start: tau1, tau2 follow the measured motion (closed loop, up to 94 % explained)"
        );
        let detail = &alerts[0].detail;
        assert!(!detail.contains("samples 20000–20099"), "{detail}");
        assert!(
            detail.contains("samples 19000–19099 (19000 to 19099 s, tau2: 69 %); and 25 more"),
            "{detail}"
        );
        assert!(
            alerts[1]
                .summary
                .starts_with("experiment `short`, 0 to 99 s")
        );
        assert!(alerts[0].help.contains("[[keep]]"), "{}", alerts[0].help);
        // A stretch alone names the windows that leave it out.
        assert!(
            alerts[1].help.contains("`--keep ..0` and `--keep 99..`")
                && alerts[1].help.contains("[[keep]]"),
            "{}",
            alerts[1].help
        );
        // Three stretches still get a warning each.
        assert_eq!(closed_loop_alerts(&all[..3]).len(), 3);
    }
}
