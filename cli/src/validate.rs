//! `leeway validate MODEL --params EST.json [--params OTHER.json]... --data
//! VAL.csv [--plot OUT.svg]`: simulate the model with each θ on recorded
//! experiments (from each experiment's first sample, with its inputs and
//! measured disturbances) and report the fit per output,
//! `100·(1 − ‖y − ŷ‖/‖y − ȳ‖)` %, per model and experiment with the mean over
//! experiments — as MATLAB's `compare` does — and, only when asked with
//! `--plot`, one figure of the measurement against every model. Exit 0 on
//! success (whatever the fit), 1 when a simulation diverges, 2 on any model,
//! data, parameter-file or option error.

use crate::data::{data_notes, load_data};
use crate::disturbances::{self, HeldJson};
use crate::model::load;
use crate::options::positive;
use crate::options::{TimeArgs, load_options};
use crate::output::{
    Ordered, Status, err, out, plain, print_json, stderr_style, table, warning_text,
};
use crate::plot::{Panel, Segment, draw};
use crate::problem::{Failure, JsonError, Problem};
use crate::residuals::{ModelResiduals, ResidArgs, analyse_all, render as render_residuals};
use crate::units::{axis_label, unit_lines};
use leeway_model::Source;
use leeway_model::simulate::{Trajectory, unwrap_heading};
use leeway_model::validation::compare;
use leeway_model::warning::Warning;
use leeway_model::{Experiment, Interpreter};
use leeway_report::{data_files_json, heading_gains, heading_warnings, unit_warnings};
use leeway_structure::ir::{Ir, Rotation};
use serde::Serialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Arguments of `leeway validate`.
#[derive(Debug, clap::Args)]
pub struct ValidateArgs {
    /// The `.som` model file.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// θ: the output of `leeway estimate --json`, or `{"name": value}` with every parameter.
    /// Repeat to compare several estimates on the same data (named by file stem).
    #[arg(long, value_name = "FILE.json", required = true)]
    pub params: Vec<PathBuf>,
    /// Validation data (CSV, the format of `estimate --data`). Repeat for more files.
    #[arg(long = "data", value_name = "VAL.csv", required = true)]
    pub data: Vec<PathBuf>,
    /// Draw measured against simulated into this file (`.svg`, or `.png` for a
    /// bitmap). Without it nothing is written.
    #[arg(long, value_name = "OUT.svg", conflicts_with = "no_plot")]
    pub plot: Option<PathBuf>,
    /// Draw no plot (the default; kept so that older scripts still run).
    #[arg(long)]
    pub no_plot: bool,
    /// Print one JSON document on stdout instead of text (the contract is in docs/json.md).
    #[arg(long)]
    pub json: bool,
    /// A constant unmeasured disturbance component during the simulation, e.g.
    /// `current.north=0.2` (earth frame for earth-fixed media), or `zero` for
    /// none. Components not given take the means of each estimate given as
    /// --params, else zero (with a warning).
    #[arg(long = "disturbance", value_name = "NAME=VALUE,...")]
    pub disturbances: Vec<String>,
    /// Sample time for data without a time column when the model declares no `step`.
    #[arg(long, value_name = "H", value_parser = positive)]
    pub step: Option<f64>,
    /// Time stamps: jitter tolerance and resampling.
    #[command(flatten)]
    pub time: TimeArgs,
    /// One-step-ahead residual analysis.
    #[command(flatten)]
    pub resid: ResidArgs,
}

/// The fit of one experiment.
#[derive(Clone, Debug, Serialize)]
struct ExperimentFit {
    name: String,
    samples: usize,
    /// Fit per output in %, null when undefined (constant measurement, or diverged).
    fit: Ordered<Option<f64>>,
    /// Fit of the integrated heading in % (planar heading only; null when undefined).
    #[serde(skip_serializing_if = "Option::is_none")]
    heading_fit: Option<Option<f64>>,
    /// The simulation left the finite numbers.
    diverged: bool,
}

/// One parameter file's results.
#[derive(Debug, Serialize)]
struct ModelFits {
    /// The parameter file as given.
    params: String,
    /// Its name in tables and the legend: the file stem.
    name: String,
    experiments: Vec<ExperimentFit>,
    /// Mean fit over experiments per output (and `heading`); null when an
    /// experiment diverged or no experiment defines it.
    mean: Ordered<Option<f64>>,
    /// The unmeasured disturbance components held during the simulation,
    /// each with its value and where it comes from.
    disturbances: Ordered<HeldJson>,
    /// The same in words, for the text output.
    #[serde(skip)]
    held: Option<String>,
}

/// The JSON document of `leeway validate --json` (docs/json.md).
/// The fields of the first parameter file stay at the top level as before;
/// `models` holds every file's.
#[derive(Debug, Serialize)]
struct Report {
    model: Option<String>,
    file: String,
    params: String,
    data: Vec<String>,
    experiments: Vec<ExperimentFit>,
    /// Mean fit over experiments of the first parameter file.
    mean: Ordered<Option<f64>>,
    /// Every parameter file, in the order given.
    models: Vec<ModelFits>,
    /// Per data file: comment lines skipped, time-stamp jitter, resampling.
    data_files: Vec<leeway_report::DataFileJson>,
    /// `{signal: unit}` as declared in the model's `data { }`.
    data_units: Ordered<String>,
    /// The plot written, or null.
    plot: Option<String>,
    /// With `--resid`: per parameter file, the residual tests.
    #[serde(skip_serializing_if = "Option::is_none")]
    residuals: Option<Vec<ModelResiduals>>,
    warnings: Vec<String>,
    errors: Vec<JsonError>,
}

struct Outcome {
    model: String,
    /// The outputs in table order: the states, then the heading when integrated.
    outputs: Vec<String>,
    models: Vec<ModelFits>,
    notes: Vec<leeway_data::FileNotes>,
    units: Vec<String>,
    data_units: Vec<(String, String)>,
    plot: Option<PathBuf>,
    /// The plot could not be drawn (the fits are still reported; exit 2).
    plot_problem: Option<Problem>,
    /// Parameter files refused while others were read: each reported, the
    /// others still validated (exit 2).
    refused: Vec<Failure>,
    /// With `--resid`.
    residuals: Option<Vec<ModelResiduals>>,
}

/// A parameter file's name in tables and legends: its stem, made unique by
/// the whole path when two files share a stem.
fn model_names(params: &[PathBuf]) -> Vec<String> {
    let stem = |p: &Path| {
        p.file_stem()
            .map_or(p.display().to_string(), |s| s.to_string_lossy().to_string())
    };
    params
        .iter()
        .map(|p| {
            let name = stem(p);
            if params.iter().filter(|q| stem(q) == name).count() > 1 {
                p.display().to_string()
            } else {
                name
            }
        })
        .collect()
}

/// Runs `leeway validate`.
pub fn run(args: &ValidateArgs) -> Status {
    let mut warnings: Vec<Warning> = Vec::new();
    let result = execute(args, &mut warnings);
    let status = match &result {
        Ok(o) if o.plot_problem.is_some() || !o.refused.is_empty() => Status::Error,
        Ok(o)
            if o.models
                .iter()
                .any(|m| m.experiments.iter().any(|e| e.diverged)) =>
        {
            Status::Unsupported
        }
        Ok(_) => Status::Success,
        Err(f) => f.status(),
    };
    if args.json {
        let mut report = Report {
            model: None,
            file: args.model.display().to_string(),
            params: args
                .params
                .first()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            data: args.data.iter().map(|p| p.display().to_string()).collect(),
            experiments: Vec::new(),
            mean: Ordered::default(),
            models: Vec::new(),
            data_files: Vec::new(),
            data_units: Ordered::default(),
            plot: None,
            residuals: None,
            warnings: warnings.iter().map(|w| w.detail.clone()).collect(),
            errors: Vec::new(),
        };
        match result {
            Ok(mut o) => {
                report.model = Some(o.model);
                report.data_files = data_files_json(&o.notes);
                report.data_units = Ordered(o.data_units);
                if let Some(first) = o.models.first() {
                    report.params = first.params.clone();
                    report.experiments = first.experiments.clone();
                    report.mean = first.mean.clone();
                }
                report.models = std::mem::take(&mut o.models);
                report.residuals = o.residuals.take();
                match o.plot_problem {
                    Some(p) => report.errors = Failure::from(p).json(),
                    None => report.plot = o.plot.map(|p| p.display().to_string()),
                }
                report
                    .errors
                    .extend(o.refused.iter().flat_map(Failure::json));
            }
            Err(f) => report.errors = f.json(),
        }
        print_json(&report);
    } else {
        let style = stderr_style();
        if let Ok(o) = &result {
            out(&render(o));
            out(&o
                .residuals
                .as_deref()
                .map(render_residuals)
                .unwrap_or_default());
        }
        for w in &warnings {
            err(&warning_text(style, w, false));
        }
        if let Ok(o) = &result {
            for f in &o.refused {
                err(&f.render(style, "validated"));
            }
        }
        match &result {
            Err(f) => err(&f.render(style, "validated")),
            Ok(Outcome {
                plot_problem: Some(p),
                ..
            }) => err(&p.render(style)),
            Ok(_) => {}
        }
    }
    status
}

fn execute(args: &ValidateArgs, warnings: &mut Vec<Warning>) -> Result<Outcome, Failure> {
    let loaded = load(&args.model, false)?;
    warnings.extend(plain("model", loaded.warnings));
    let ir = loaded.ir;
    let options = load_options(&ir, args.step, Some(&args.time))?;
    let given = disturbances::given(&ir, &args.disturbances)?;
    let (mut thetas, mut held, mut kept, mut refused) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in &args.params {
        match crate::params::read_file(p, &ir, "--params") {
            Ok(file) => {
                let (h, warning) = disturbances::held(&ir, &given, &file, p);
                warnings.extend(warning);
                thetas.push(file.theta);
                held.push(h);
                kept.push(p.clone());
            }
            Err(f) => refused.push(f),
        }
    }
    // One refused file does not void the comparison of the others.
    if kept.is_empty() && !refused.is_empty() {
        return Err(refused.swap_remove(0));
    }
    let dist: Vec<Vec<f64>> = held.iter().map(|h| h.values.clone()).collect();
    let (experiments, notes) = load_data(&ir, &args.data, &options)?;
    let sources: Vec<&dyn leeway_model::Source> = experiments
        .iter()
        .map(|e| e as &dyn leeway_model::Source)
        .collect();
    warnings.extend(plain("units", unit_warnings(&ir, &sources)));
    warnings.extend(plain(
        "heading",
        heading_warnings(&ir, &heading_gains(&ir, &sources)),
    ));
    let heading = match &ir.rotation {
        Rotation::Planar { heading, .. } => Some(heading.clone()),
        _ => None,
    };
    let mut outputs = ir.states.clone();
    outputs.extend(heading.iter().cloned());
    let names = model_names(&kept);
    let model = Interpreter::new(ir.clone());
    let mut panels = measured_panels(&ir, &outputs, &experiments);
    let comparison = compare(&model, &thetas, &names, &experiments, &dist);
    let residuals = (args.resid.resid)
        .then(|| {
            analyse_all(
                &model,
                &thetas,
                &names,
                &experiments,
                &dist,
                args.resid.lags,
            )
        })
        .transpose()?;
    warnings.extend(plain("validation", comparison.warnings));
    let mut results = Vec::new();
    for (((validations, mean), name), held) in comparison
        .validations
        .iter()
        .zip(comparison.means)
        .zip(&names)
        .zip(&held)
    {
        for (k, v) in validations.iter().enumerate() {
            add_simulated(&mut panels, k, &v.trajectory, ir.states.len());
        }
        let experiments = experiments
            .iter()
            .zip(validations)
            .map(|(e, v)| ExperimentFit {
                name: e.name.clone(),
                samples: e.len(),
                fit: Ordered(ir.states.iter().cloned().zip(v.fits.clone()).collect()),
                heading_fit: v.heading_fit,
                diverged: v.diverged(),
            })
            .collect();
        results.push(ModelFits {
            params: kept
                .get(results.len())
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            name: name.clone(),
            experiments,
            mean: Ordered(outputs.iter().cloned().zip(mean).collect()),
            disturbances: disturbances::json(&ir, held),
            held: disturbances::described(&ir, held),
        });
    }
    title_panels(&mut panels, &results, &outputs, experiments.len());
    let plot = if args.no_plot {
        None
    } else {
        args.plot.clone()
    };
    let plot_problem = plot.as_ref().and_then(|path| {
        draw(path, &panels, &names)
            .err()
            .map(|e| Problem::error("io", format!("cannot draw `{}`: {e}", path.display())))
    });
    Ok(Outcome {
        model: ir.name.clone(),
        outputs,
        models: results,
        notes,
        units: unit_lines(&ir),
        data_units: ir
            .data_units
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect(),
        plot,
        plot_problem,
        refused,
        residuals,
    })
}

/// One panel per output, the experiments end to end, each with its
/// measurement (the simulations are added per model).
fn measured_panels(ir: &Ir, outputs: &[String], experiments: &[Experiment]) -> Vec<Panel> {
    // Panels: one per output, experiments end to end, a line per model.
    let mut panels: Vec<Panel> = outputs
        .iter()
        .map(|o| Panel {
            title: String::new(),
            y_label: axis_label(ir, o),
            segments: Vec::new(),
        })
        .collect();
    let mut offset = 0.0;
    for e in experiments {
        let time: Vec<f64> = (0..e.len()).map(|k| offset + k as f64 * e.h).collect();
        offset += e.len() as f64 * e.h;
        for (o, panel) in panels.iter_mut().enumerate() {
            let measured = if o < ir.states.len() {
                e.states.get(o).cloned().unwrap_or_default()
            } else {
                unwrap_heading(&e.heading)
            };
            panel.segments.push(Segment {
                name: e.name.clone(),
                time: time.clone(),
                measured,
                simulated: Vec::new(),
            });
        }
    }
    panels
}

/// Each panel's title: its output and every model's (mean) fit.
fn title_panels(
    panels: &mut [Panel],
    results: &[ModelFits],
    outputs: &[String],
    n_experiments: usize,
) {
    for (o, panel) in panels.iter_mut().enumerate() {
        let fits: Vec<String> = results
            .iter()
            .map(|m| {
                let f = m.mean.0.get(o).and_then(|(_, v)| *v);
                let diverged = m.experiments.iter().any(|e| e.diverged);
                let value = match f {
                    Some(f) => format!("{f:.1} %"),
                    None if diverged => "diverged".to_string(),
                    None => "undefined".to_string(),
                };
                if results.len() > 1 {
                    format!("{} {value}", m.name)
                } else {
                    value
                }
            })
            .collect();
        let scope = if n_experiments > 1 {
            format!("mean fit over {n_experiments} experiments")
        } else {
            "fit".to_string()
        };
        panel.title = format!("{}: {scope} {}", outputs[o], fits.join(", "));
    }
}

/// A model's simulation of experiment `k` drawn in every output's panel.
fn add_simulated(panels: &mut [Panel], k: usize, sim: &Trajectory, n_states: usize) {
    for (o, panel) in panels.iter_mut().enumerate() {
        let simulated = if o < n_states {
            sim.states.get(o).cloned().unwrap_or_default()
        } else {
            sim.heading.clone()
        };
        if let Some(seg) = panel.segments.get_mut(k) {
            // With dead times the simulation starts `d_max` samples in.
            let late = seg.measured.len().saturating_sub(simulated.len());
            let drawn = std::iter::repeat_n(f64::NAN, late).chain(simulated);
            seg.simulated.push(drawn.collect());
        }
    }
}

fn cell(f: Option<f64>, diverged: bool) -> String {
    match f {
        Some(f) => format!("{f:.2}"),
        None if diverged => "diverged".to_string(),
        None => "-".to_string(),
    }
}

fn render(o: &Outcome) -> String {
    let mut s = String::new();
    // One experiment has no mean row, so no word of one.
    let several = o.models.first().is_some_and(|m| m.experiments.len() > 1);
    let _ = writeln!(
        s,
        "{}: fit = 100·(1 − ‖y − ŷ‖/‖y − ȳ‖), %{}",
        o.model,
        if several {
            " (mean: over experiments)"
        } else {
            ""
        }
    );
    for m in &o.models {
        let _ = writeln!(s, "\n{} ({})", m.name, m.params);
        let mut rows = vec![{
            let mut h = vec!["experiment".to_string(), "samples".to_string()];
            h.extend(o.outputs.iter().cloned());
            h
        }];
        for e in &m.experiments {
            let mut r = vec![e.name.clone(), e.samples.to_string()];
            r.extend(e.fit.0.iter().map(|(_, f)| cell(*f, e.diverged)));
            if let Some(h) = e.heading_fit {
                r.push(cell(h, e.diverged));
            }
            rows.push(r);
        }
        if m.experiments.len() > 1 {
            let diverged = m.experiments.iter().any(|e| e.diverged);
            let mut r = vec!["mean".to_string(), String::new()];
            r.extend(m.mean.0.iter().map(|(_, f)| cell(*f, diverged)));
            rows.push(r);
        }
        s.push_str(&table(&rows));
        if let Some(held) = &m.held {
            let _ = writeln!(s, "disturbances held: {held}");
        }
    }
    let mut extra: Vec<String> = o.units.iter().map(|u| format!("unit: {u}")).collect();
    extra.extend(
        data_notes(&o.notes)
            .into_iter()
            .map(|n| format!("data: {n}")),
    );
    if !extra.is_empty() {
        s.push('\n');
        for line in extra {
            let _ = writeln!(s, "{line}");
        }
    }
    if let (Some(p), None) = (&o.plot, &o.plot_problem) {
        let _ = writeln!(s, "\nplot: {}", p.display());
    }
    s
}
