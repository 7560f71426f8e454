//! The checks of the data that come with an estimate: inputs named like
//! angles whose values look like degrees, a heading that does not integrate
//! its yaw rate, and stretches in closed loop ([`crate::feedback`]). Each
//! has a function of its own; [`data_checks`] makes all three in one visit
//! of each experiment, the experiments on the machine's cores.

use leeway_data::{HeadingGainSums, heading_gain};
use leeway_estimate::feedback::{Feedback, FeedbackScan};
use leeway_estimate::parallel::{in_order, threads_for};
use leeway_model::experiment::{Row, Source};
use leeway_model::warning::Warning;
use leeway_structure::ir::{Ir, Rotation};

/// What the three checks measure of a set of experiments.
#[derive(Clone, Debug, PartialEq)]
pub struct DataChecks {
    /// [`input_peaks`].
    pub input_peaks: Vec<f64>,
    /// [`heading_gains`].
    pub heading_gains: Vec<(String, Option<f64>)>,
    /// The closed-loop stretches ([`crate::feedback::closed_loop`]).
    pub closed_loop: Vec<Feedback>,
}

/// [`input_peaks`], [`heading_gains`] and the closed-loop stretches in one
/// visit of each experiment (each on a thread of its own), with the same
/// numbers as each alone: every check sees the same rows in the same order,
/// and peaks combine by their maximum, exactly.
pub fn data_checks(ir: &Ir, experiments: &[&dyn Source]) -> DataChecks {
    let angle_like = angle_like_inputs(ir);
    let heading = heading_name(ir).is_some();
    let threads = threads_for(experiments.len());
    let each = in_order(experiments.len(), threads, |i| {
        one_visit(ir, experiments[i], &angle_like)
    });
    let mut checks = DataChecks {
        input_peaks: vec![0.0f64; ir.inputs.len()],
        heading_gains: Vec::new(),
        closed_loop: Vec::new(),
    };
    for (e, (peaks, gain, stretches)) in experiments.iter().zip(each) {
        for (p, v) in checks.input_peaks.iter_mut().zip(peaks) {
            *p = p.max(v);
        }
        if heading {
            checks.heading_gains.push((e.name().to_string(), gain));
        }
        checks.closed_loop.extend(stretches);
    }
    checks
}

/// One experiment's peaks (of the `angle_like` inputs), heading gain and
/// closed-loop stretches, from one visit (none when no check reads it).
fn one_visit(
    ir: &Ir,
    e: &dyn Source,
    angle_like: &[usize],
) -> (Vec<f64>, Option<f64>, Vec<Feedback>) {
    let mut peaks = vec![0.0f64; ir.inputs.len()];
    let mut gain = HeadingGainSums::new(ir, e.step());
    let mut scan = FeedbackScan::new(ir, e);
    if !angle_like.is_empty() || gain.is_some() || scan.is_some() {
        e.visit(&mut |row: &Row| {
            for &i in angle_like {
                if let Some(v) = row.inputs.get(i) {
                    peaks[i] = peaks[i].max(v.abs());
                }
            }
            if let Some(g) = &mut gain {
                g.push(row);
            }
            if let Some(s) = &mut scan {
                s.push(row);
            }
        });
    }
    (
        peaks,
        gain.and_then(HeadingGainSums::gain),
        scan.map_or_else(Vec::new, FeedbackScan::finish),
    )
}

/// Words in an input's name or column that say it is an angle.
const ANGLE_WORDS: [&str; 5] = ["delta", "rudder", "angle", "deg", "azimuth"];

/// An input without a declared unit, named like an angle (`delta`,
/// `rudder_deg`, ...), whose values exceed π in magnitude is probably an
/// angle logged in degrees: say so, with the declaration that fixes it. Only
/// the name can tell an angle from a force of the same magnitude, so inputs
/// named otherwise are left alone rather than warned about on every run.
pub fn unit_warnings(ir: &Ir, experiments: &[&dyn Source]) -> Vec<String> {
    details(unit_alerts_from_peaks(ir, &input_peaks(ir, experiments)))
}

/// [`unit_warnings`] with their summaries and help lines.
pub fn unit_alerts(ir: &Ir, experiments: &[&dyn Source]) -> Vec<Warning> {
    unit_alerts_from_peaks(ir, &input_peaks(ir, experiments))
}

/// Each warning's full text.
fn details(warnings: Vec<Warning>) -> Vec<String> {
    warnings.into_iter().map(|w| w.detail).collect()
}

/// The inputs whose name or column reads like an angle without a declared unit.
fn angle_like_inputs(ir: &Ir) -> Vec<usize> {
    ir.inputs
        .iter()
        .enumerate()
        .filter(|(_, name)| {
            let column = leeway_model::experiment::column_name(ir, name).to_lowercase();
            let angle_like = ANGLE_WORDS
                .iter()
                .any(|w| name.to_lowercase().contains(w) || column.contains(w));
            !ir.data_units.contains_key(*name) && angle_like
        })
        .map(|(i, _)| i)
        .collect()
}

/// The largest magnitude of every angle-like input over the experiments (0
/// for the other inputs): what [`unit_warnings`] judges. Peaks of disjoint
/// sets of experiments combine by their maximum, exactly.
pub fn input_peaks(ir: &Ir, experiments: &[&dyn Source]) -> Vec<f64> {
    let angle_like = angle_like_inputs(ir);
    let mut peaks = vec![0.0f64; ir.inputs.len()];
    if angle_like.is_empty() {
        return peaks;
    }
    // One visit of every experiment for all such inputs.
    for e in experiments {
        e.visit(&mut |row| {
            for &i in &angle_like {
                if let Some(v) = row.inputs.get(i) {
                    peaks[i] = peaks[i].max(v.abs());
                }
            }
        });
    }
    peaks
}

/// [`unit_warnings`] from the peaks of [`input_peaks`].
pub fn unit_warnings_from_peaks(ir: &Ir, peaks: &[f64]) -> Vec<String> {
    details(unit_alerts_from_peaks(ir, peaks))
}

/// [`unit_alerts`] from the peaks of [`input_peaks`].
pub fn unit_alerts_from_peaks(ir: &Ir, peaks: &[f64]) -> Vec<Warning> {
    let mut out = Vec::new();
    for i in angle_like_inputs(ir) {
        let (name, peak) = (&ir.inputs[i], peaks.get(i).copied().unwrap_or(0.0));
        if peak > std::f64::consts::PI {
            out.push(
                Warning::new(
                    "angle-unit",
                    format!("input `{name}` reaches {peak:.1}, more than π: it looks like an angle in degrees"),
                    format!("if it is, declare `{name} in deg` in data {{ }}"),
                    format!(
                        "input `{name}` reaches {peak:.1}: if it is an angle in degrees declare `{name} in deg` in data {{ }}"
                    ),
                )
                .biasing(),
            );
        }
    }
    out
}

/// The heading gain of every experiment (`None` without a planar heading or
/// with too little yaw motion to tell), one visit each.
pub fn heading_gains(ir: &Ir, experiments: &[&dyn Source]) -> Vec<(String, Option<f64>)> {
    if heading_name(ir).is_none() {
        return Vec::new();
    }
    experiments
        .iter()
        .map(|e| (e.name().to_string(), heading_gain(ir, *e)))
        .collect()
}

/// The heading's unit check (SPEC §5): a warning with the measured gain of
/// `Δψ/h` on the yaw rate when it is off by more than 20 %, from the gains of
/// [`heading_gains`].
pub fn heading_warnings(ir: &Ir, gains: &[(String, Option<f64>)]) -> Vec<String> {
    details(heading_alerts(ir, gains))
}

/// [`heading_warnings`] with their summaries and help lines.
pub fn heading_alerts(ir: &Ir, gains: &[(String, Option<f64>)]) -> Vec<Warning> {
    let Some(heading) = heading_name(ir) else {
        return Vec::new();
    };
    gains
        .iter()
        .filter_map(|(name, gain)| {
            let gain = (*gain)?;
            ((gain - 1.0).abs() > 0.2).then(|| heading_warning(ir, name, &heading, gain))
        })
        .collect()
}

fn heading_name(ir: &Ir) -> Option<String> {
    match &ir.rotation {
        Rotation::Planar { heading, .. } => {
            Some(leeway_model::experiment::column_name(ir, heading))
        }
        _ => None,
    }
}

fn heading_warning(ir: &Ir, experiment: &str, heading: &str, gain: f64) -> Warning {
    let rate = match &ir.rotation {
        Rotation::Planar { integrates, .. } => {
            ir.states.get(*integrates).map_or("r", String::as_str)
        }
        _ => "r",
    };
    // Far above 1 points at degrees (57.3 = 180/π); the figure itself is
    // reported as measured, whatever it is.
    let why = if gain > 20.0 {
        "a gain near 57.3 (180/π) means the heading is in degrees while the model works in radians"
    } else {
        "check the units and frame of both columns"
    };
    let help = if gain > 20.0 {
        format!("if `{heading}` is in degrees, declare `{heading} in deg` in data {{ }}")
    } else {
        "check the units and frame of both columns".to_string()
    };
    Warning::new(
        "heading-gain",
        format!(
            "experiment `{experiment}`: the heading `{heading}` does not integrate `{rate}` (gain {gain:.2}, 1 expected)"
        ),
        help,
        format!(
            "experiment `{experiment}`: the heading `{heading}` does not integrate `{rate}`: Δ{heading}/h ≈ {gain:.2}·{rate} (gain {gain:.2}, 1 expected); {why}"
        ),
    )
    .biasing()
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway_model::experiment::Experiment;

    fn ir() -> Ir {
        let src = "model M { step 0.1 state u, r input delta, tau heading psi integrates r \
                   der u = X*u + T*tau der r = N*r + D*delta }";
        leeway_structure::compile(src, &leeway_structure::CompileOptions::default())
            .ir
            .unwrap_or_else(|| panic!("the test model compiles"))
    }

    /// `n` samples: random held inputs (`delta` in degrees when `degrees`),
    /// `tau` set from the measured `u` from sample `closed` on, the heading
    /// integrating `r` (in degrees when `degrees`).
    fn record(name: &str, n: usize, closed: usize, degrees: bool, seed: u64) -> Experiment {
        let ir = ir();
        let mut e = Experiment::new(&ir, name, 0.1);
        let mut seed = seed;
        let mut noise = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (mut u, mut r, mut psi, mut level, mut rudder) = (0.0, 0.0, 0.0, 1.0, 0.1);
        let scale = if degrees {
            180.0 / std::f64::consts::PI
        } else {
            1.0
        };
        for k in 0..n {
            if k % 47 == 0 {
                (level, rudder) = (2.0 * noise(), 0.6 * noise());
            }
            let measured = u + 0.01 * noise();
            let tau = if k >= closed { -3.0 * measured } else { level };
            e.states[0].push(measured);
            e.states[1].push(r);
            e.inputs[0].push(rudder * scale);
            e.inputs[1].push(tau);
            e.heading.push(psi * scale);
            u += 0.1 * (-0.2 * u + tau);
            psi += 0.1 * r;
            r += 0.1 * (-0.5 * r + rudder);
        }
        e
    }

    #[test]
    fn one_visit_gives_each_check_its_own_numbers() {
        let ir = ir();
        let runs = [
            record("calm", 3000, usize::MAX, false, 3),
            record("degrees", 2000, usize::MAX, true, 5),
            record("controlled", 6000, 3000, false, 7),
            record("short", 50, usize::MAX, false, 11),
        ];
        let sources: Vec<&dyn Source> = runs.iter().map(|e| e as &dyn Source).collect();
        let checks = data_checks(&ir, &sources);
        assert_eq!(checks.input_peaks, input_peaks(&ir, &sources));
        assert_eq!(checks.heading_gains, heading_gains(&ir, &sources));
        assert_eq!(
            checks.closed_loop,
            crate::feedback::closed_loop(&ir, &sources)
        );
        // Each check found what it looks for, so the comparison is not empty.
        assert!(checks.input_peaks[0] > 10.0, "{:?}", checks.input_peaks);
        let gain = |name: &str| {
            let found = checks.heading_gains.iter().find(|(n, _)| n == name);
            found.and_then(|(_, g)| *g).unwrap_or(f64::NAN)
        };
        assert!(
            (gain("calm") - 1.0).abs() < 0.05,
            "{:?}",
            checks.heading_gains
        );
        assert!(
            (gain("degrees") - 57.3).abs() < 3.0,
            "{:?}",
            checks.heading_gains
        );
        assert_eq!(checks.closed_loop.len(), 1, "{:?}", checks.closed_loop);
        assert_eq!(checks.closed_loop[0].experiment, "controlled");
        assert_eq!(checks.closed_loop[0].first, 3000);
    }
}
