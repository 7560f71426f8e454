//! `leeway select MODEL.som --data RUN.csv... --out CHOSEN.som [--validate
//! VAL.csv]... [--plot FIGURE.png] [--json]`: which of the model's candidate terms (`?name`) the
//! data need. Prints the path (each step's dropped term, its Wald
//! statistic, J and the held-out criterion) and writes the chosen model,
//! ready for `leeway estimate`. Exit 0 on success, 2 on any model, data or
//! option error, 1 when the estimate cannot be made from these data.

mod figure;

use crate::data::load_data;
use crate::model::{compiled, load};
use crate::options::{TimeArgs, choices, load_options};
use crate::output::{Status, err, headline, out, print_json, stderr_style, warning_text};
use crate::problem::{Failure, JsonError, Problem};
use leeway_estimate::{EstimateOptions, MAX_LAGS, Method};
use leeway_model::Experiment;
use leeway_model::Source;
use leeway_model::number::short_number;
use leeway_model::warning::Warning;
use leeway_report::checks::{data_checks, heading_alerts, unit_alerts_from_peaks};
use leeway_report::feedback::closed_loop_alerts;
use leeway_select::{SelectOptions, Selection, select};
use serde::Serialize;
use std::fmt::Write;
use std::path::PathBuf;

/// Arguments of `leeway select`.
#[derive(Debug, clap::Args)]
pub struct SelectArgs {
    /// The candidate model: a `.som` file whose candidate terms' parameters are written `?name`.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// Estimation data (CSV or Parquet, the format of `estimate --data`). Repeat for more files;
    /// with two experiments or more and no --validate, each is held out in turn.
    #[arg(long = "data", value_name = "RUN.csv", required = true)]
    pub data: Vec<PathBuf>,
    /// Held-out data for the free-run criterion, instead of leaving each experiment out.
    #[arg(long = "validate", value_name = "VAL.csv")]
    pub validate: Vec<PathBuf>,
    /// Write the chosen model here (kept candidates without their `?`, dropped ones removed).
    #[arg(long, value_name = "CHOSEN.som")]
    pub out: PathBuf,
    /// The estimator (an IV method).
    #[arg(long, default_value = "iv3", value_parser = choices::<Method>())]
    pub method: Method,
    /// Lags of the long-run covariance behind the Wald statistics and J: at least the
    /// correlation time of the disturbances, in samples.
    #[arg(long, default_value_t = 1)]
    pub lags: usize,
    /// A model is within reach of the best held-out criterion c* when its own is at most
    /// c*·(1 + TOLERANCE·c*).
    #[arg(long, default_value_t = 0.5)]
    pub tolerance: f64,
    /// Sample time for data without a time column when the model declares no `step`.
    #[arg(long, value_name = "H", value_parser = crate::options::positive)]
    pub step: Option<f64>,
    /// Time stamps: jitter tolerance and resampling.
    #[command(flatten)]
    pub time: TimeArgs,
    /// Draw the criteria against model size (J and the score above, the held-out criterion
    /// below) into this file: PNG for a `.png` name, SVG otherwise.
    #[arg(long, value_name = "FIGURE.png")]
    pub plot: Option<PathBuf>,
    /// Print one JSON document on stdout instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The JSON document of `leeway select --json`.
#[derive(Serialize)]
struct Report<'a> {
    file: String,
    out: String,
    selection: Option<&'a Selection>,
    /// The chosen estimate's warnings in full, as `estimate --json`'s `warnings`.
    warnings: Vec<String>,
    errors: Vec<JsonError>,
}

/// Runs `leeway select`.
pub fn run(args: &SelectArgs) -> Status {
    let result = execute(args);
    let status = match &result {
        Ok(_) => Status::Success,
        Err(f) => f.status(),
    };
    if args.json {
        let (selection, warnings, errors) = match &result {
            Ok((s, w)) => (
                Some(s),
                w.iter().map(|w| w.detail.clone()).collect(),
                Vec::new(),
            ),
            Err(f) => (None, Vec::new(), f.json()),
        };
        print_json(&Report {
            file: args.model.display().to_string(),
            out: args.out.display().to_string(),
            selection,
            warnings,
            errors,
        });
    } else {
        let style = stderr_style();
        match &result {
            Ok((s, warnings)) => {
                out(&render(s, &args.out.display().to_string()));
                // The chosen estimate's warnings and notes, as `estimate` words them.
                for w in warnings {
                    err(&warning_text(style, w, false));
                }
                for n in &s.estimate.notes {
                    err(&headline(style, "note", None, n));
                }
            }
            Err(f) => err(&f.render(style, "selected")),
        }
    }
    status
}

/// The selection and the chosen estimate's warnings: the chosen model's,
/// the data checks' and the estimator's, in `estimate`'s order.
fn execute(args: &SelectArgs) -> Result<(Selection, Vec<Warning>), Failure> {
    if !(1..=MAX_LAGS).contains(&args.lags) {
        return Err(Problem::error(
            "invalid-option",
            format!("--lags {} is outside 1..={MAX_LAGS}", args.lags),
        )
        .help("give the disturbances' correlation time in samples")
        .into());
    }
    if !(args.tolerance >= 0.0 && args.tolerance.is_finite()) {
        return Err(Problem::error(
            "invalid-option",
            format!(
                "--tolerance {} is not a non-negative number",
                args.tolerance
            ),
        )
        .help("give a fraction such as 0.1")
        .into());
    }
    // The candidate model compiled as `estimate` would (identifiability
    // problems are the selection's to handle: it drops exchangeable candidates).
    let loaded = load(&args.model, true)?;
    let source = std::fs::read_to_string(&args.model).map_err(|e| {
        Problem::error("io", format!("cannot read the model: {e}"))
            .at(args.model.display().to_string())
    })?;
    let options = load_options(&loaded.ir, args.step, Some(&args.time))?;
    let (experiments, _) = load_data(&loaded.ir, &args.data, &options)?;
    let validation: Vec<Experiment> = if args.validate.is_empty() {
        Vec::new()
    } else {
        load_data(&loaded.ir, &args.validate, &options)?.0
    };
    let select_options = SelectOptions {
        estimate: EstimateOptions {
            method: args.method,
            lags: args.lags,
            ..EstimateOptions::default()
        },
        tolerance: args.tolerance,
        threads: 0,
    };
    let selection = select(&source, &experiments, &validation, &select_options).map_err(|e| {
        let status = if e.code == "estimate-failed" {
            Status::Unsupported
        } else {
            Status::Error
        };
        let mut p = Problem::error(e.code, e.message).help(e.hint);
        // The model's problems are located at it; an option's or the data's are not.
        if matches!(
            e.code,
            "invalid-candidates" | "invalid-model" | "no-candidates"
        ) {
            p = p.at(args.model.display().to_string());
        }
        p.status = status;
        Failure::from(p)
    })?;
    std::fs::write(&args.out, &selection.chosen_source).map_err(|e| {
        Problem::error("io", format!("cannot write the chosen model: {e}"))
            .at(args.out.display().to_string())
    })?;
    if let Some(path) = &args.plot {
        figure::draw(path, &selection)
            .map_err(|e| Problem::error("io", format!("cannot draw `{}`: {e}", path.display())))?;
    }
    let warnings = chosen_warnings(args, &selection, &experiments)?;
    Ok((selection, warnings))
}

/// What `leeway estimate CHOSEN.som` on the same data warns of: the chosen
/// model's compiler warnings (located in the written file), the data
/// checks on its terms, the estimator's warnings.
fn chosen_warnings(
    args: &SelectArgs,
    selection: &Selection,
    experiments: &[Experiment],
) -> Result<Vec<Warning>, Failure> {
    let chosen = compiled(
        args.out.display().to_string(),
        selection.chosen_source.clone(),
        false,
    )?;
    let mut warnings: Vec<Warning> = chosen
        .warnings
        .into_iter()
        .map(|w| Warning::plain("model", w))
        .collect();
    let sources: Vec<&dyn Source> = experiments.iter().map(|e| e as &dyn Source).collect();
    let checks = data_checks(&chosen.ir, &sources);
    warnings.extend(unit_alerts_from_peaks(&chosen.ir, &checks.input_peaks));
    warnings.extend(heading_alerts(&chosen.ir, &checks.heading_gains));
    warnings.extend(closed_loop_alerts(&checks.closed_loop));
    warnings.extend(selection.estimate.warning_summaries.iter().cloned());
    Ok(warnings)
}

fn number(v: Option<f64>) -> String {
    v.map_or("-".to_string(), short_number)
}

/// The path as a table, then the choice.
fn render(s: &Selection, out_file: &str) -> String {
    let mut t = String::new();
    let _ = writeln!(t, "held-out criterion: {}", s.held_out);
    let _ = writeln!(
        t,
        "{:>4}  {:<14} {:<26} {:>9} {:>9} {:>5} {:>9} {:>5} {:>11}",
        "step", "dropped", "why", "Wald", "p", "kept", "J", "df", "criterion"
    );
    for (k, st) in s.steps.iter().enumerate() {
        let mark = if k == s.chosen { "*" } else { " " };
        let _ = writeln!(
            t,
            "{:>3}{mark}  {:<14} {:<26} {:>9} {:>9} {:>5} {:>9} {:>5} {:>11}",
            k,
            st.dropped.as_deref().unwrap_or("-"),
            st.reason,
            number(st.wald),
            number(st.p_value),
            st.size,
            short_number(st.j),
            st.j_df,
            number(st.criterion),
        );
    }
    let _ = writeln!(
        t,
        "chosen: step {} — kept {} of {} candidates: {}",
        s.chosen,
        s.kept.len(),
        s.candidates.len(),
        if s.kept.is_empty() {
            "none".to_string()
        } else {
            s.kept.join(", ")
        }
    );
    let _ = writeln!(
        t,
        "written: {out_file} (estimate it with `leeway estimate {out_file} --data ...`)"
    );
    let _ = writeln!(t, "its estimate ({}):", s.estimate.method.name());
    for (i, name) in s.estimate.parameters.iter().enumerate() {
        let _ = writeln!(
            t,
            "  {name:<10} {:>12}  ± {}",
            short_number(s.estimate.theta[i]),
            number(s.estimate.std_errors[i])
        );
    }
    if !s.suggestions.is_empty() {
        let _ = writeln!(
            t,
            "it may lack (residual correlation with terms it does not declare):"
        );
        for g in &s.suggestions {
            let _ = writeln!(
                t,
                "  {:<12} in the equation of {:<6} {:>7}",
                g.term,
                g.equation,
                format!("{:+.2}", g.correlation)
            );
        }
    }
    t
}
