//! `leeway validate MODEL --params EST.json --data VAL.csv [--plot OUT.svg]`:
//! simulate the model with θ on recorded experiments (from each experiment's
//! first sample, with its inputs and measured disturbances) and report the fit
//! per output, `100·(1 − ‖y − ŷ‖/‖y − ȳ‖)` %, with a plot of measured against
//! simulated. Exit 0 on success (whatever the fit), 1 when a simulation
//! diverges, 2 on any model, data, parameter-file or option error.

use crate::model::{disturbance_values, heading_warnings, load, load_data, load_options};
use crate::output::{Ordered, Status, err, headline, out, print_json, stderr_style, table};
use crate::plot::{Panel, draw};
use crate::problem::{Failure, JsonError, Problem};
use leeway_runtime::simulate::{Disturbances, fits, simulate};
use leeway_runtime::{Interpreter, Source};
use serde::Serialize;
use std::fmt::Write;
use std::path::PathBuf;

/// Arguments of `leeway validate`.
#[derive(Debug, clap::Args)]
pub struct ValidateArgs {
    /// The `.som` model file.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// θ: the output of `leeway estimate --json`, or `{"name": value}` with every parameter.
    #[arg(long, value_name = "FILE.json")]
    pub params: PathBuf,
    /// Validation data (CSV, the format of `estimate --data`). Repeat for more files.
    #[arg(long = "data", value_name = "VAL.csv", required = true)]
    pub data: Vec<PathBuf>,
    /// Where to draw measured against simulated (`.svg`, or `.png` for a bitmap).
    /// Default: `<first data file without .csv>-validation.svg`, beside it.
    #[arg(long, value_name = "OUT.svg", conflicts_with = "no_plot")]
    pub plot: Option<PathBuf>,
    /// Draw no plot.
    #[arg(long)]
    pub no_plot: bool,
    /// Print one JSON document on stdout instead of text (the contract is in the README).
    #[arg(long)]
    pub json: bool,
    /// A constant unmeasured disturbance component during the simulation, e.g.
    /// `current.north=0.2` (earth frame for earth-fixed media); others are zero.
    #[arg(long = "disturbance", value_name = "NAME=VALUE,...")]
    pub disturbances: Vec<String>,
    /// Sample time for data without a time column when the model declares no `step`.
    #[arg(long, value_name = "H", value_parser = crate::estimate::positive)]
    pub step: Option<f64>,
}

/// The fit of one experiment.
#[derive(Debug, Serialize)]
struct ExperimentFit {
    name: String,
    samples: usize,
    /// Fit per output in %, null when undefined (constant measurement, or diverged).
    fit: Ordered<Option<f64>>,
    /// The simulation left the finite numbers.
    diverged: bool,
}

/// The JSON document of `leeway validate --json` (README, "Estimating").
#[derive(Debug, Serialize)]
struct Report {
    model: Option<String>,
    file: String,
    params: String,
    data: Vec<String>,
    experiments: Vec<ExperimentFit>,
    /// The plot written, or null.
    plot: Option<String>,
    warnings: Vec<String>,
    errors: Vec<JsonError>,
}

struct Outcome {
    model: String,
    outputs: Vec<String>,
    experiments: Vec<ExperimentFit>,
    plot: Option<PathBuf>,
    /// The plot could not be drawn (the fits are still reported; exit 2).
    plot_problem: Option<Problem>,
}

/// The default plot path: beside the first data file.
fn default_plot(args: &ValidateArgs) -> Option<PathBuf> {
    if args.no_plot {
        return None;
    }
    if let Some(p) = &args.plot {
        return Some(p.clone());
    }
    let first = args.data.first()?;
    let stem = first.file_stem()?.to_string_lossy().to_string();
    Some(first.with_file_name(format!("{stem}-validation.svg")))
}

/// Runs `leeway validate`.
pub fn run(args: &ValidateArgs) -> Status {
    let mut warnings = Vec::new();
    let result = execute(args, &mut warnings);
    let status = match &result {
        Ok(o) if o.plot_problem.is_some() => Status::Error,
        Ok(o) if o.experiments.iter().any(|e| e.diverged) => Status::Unsupported,
        Ok(_) => Status::Success,
        Err(f) => f.status(),
    };
    if args.json {
        let mut report = Report {
            model: None,
            file: args.model.display().to_string(),
            params: args.params.display().to_string(),
            data: args.data.iter().map(|p| p.display().to_string()).collect(),
            experiments: Vec::new(),
            plot: None,
            warnings,
            errors: Vec::new(),
        };
        match result {
            Ok(o) => {
                report.model = Some(o.model);
                report.experiments = o.experiments;
                match o.plot_problem {
                    Some(p) => report.errors = Failure::from(p).json(),
                    None => report.plot = o.plot.map(|p| p.display().to_string()),
                }
            }
            Err(f) => report.errors = f.json(),
        }
        print_json(&report);
    } else {
        let style = stderr_style();
        if let Ok(o) = &result {
            out(&render(args, o));
        }
        for w in &warnings {
            err(&headline(style, "warning", None, w));
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

fn execute(args: &ValidateArgs, warnings: &mut Vec<String>) -> Result<Outcome, Failure> {
    let loaded = load(&args.model, false)?;
    warnings.extend(loaded.warnings);
    let ir = loaded.ir;
    let options = load_options(&ir, args.step)?;
    let theta = crate::params::read(&args.params, &ir, "--params")?;
    let dist = disturbance_values(&ir, &args.disturbances)?;
    let experiments = load_data(&ir, &args.data, &options)?;
    warnings.extend(heading_warnings(&ir, &experiments));
    let model = Interpreter::new(ir.clone());
    let mut results = Vec::new();
    let mut panels = Vec::new();
    for e in &experiments {
        let sim = simulate(&model, &theta, e, Disturbances::Constant(&dist));
        let fit = fits(e, &sim);
        let time: Vec<f64> = (0..e.len()).map(|k| k as f64 * e.h).collect();
        for (o, name) in ir.states.iter().enumerate() {
            let f = fit.get(o).copied().unwrap_or(f64::NAN);
            if !f.is_finite() && !sim.diverged {
                warnings.push(format!(
                    "experiment `{}`: `{name}` is constant in the data, so its fit is undefined",
                    e.name
                ));
            }
            panels.push(Panel {
                title: format!(
                    "{name}: {}{}",
                    if experiments.len() > 1 {
                        format!("{}, ", e.name)
                    } else {
                        String::new()
                    },
                    if f.is_finite() {
                        format!("fit {f:.1} %")
                    } else if sim.diverged {
                        "the simulation diverged".to_string()
                    } else {
                        "fit undefined".to_string()
                    }
                ),
                y_label: name.clone(),
                time: time.clone(),
                measured: e.states.get(o).cloned().unwrap_or_default(),
                simulated: sim.states.get(o).cloned().unwrap_or_default(),
            });
        }
        if sim.diverged {
            warnings.push(format!(
                "experiment `{}`: the simulation diverged (the states left the finite numbers); check the parameters",
                e.name
            ));
        }
        results.push(ExperimentFit {
            name: e.name.clone(),
            samples: e.len(),
            fit: Ordered(
                ir.states
                    .iter()
                    .zip(&fit)
                    .map(|(n, f)| (n.clone(), f.is_finite().then_some(*f)))
                    .collect(),
            ),
            diverged: sim.diverged,
        });
    }
    let plot = default_plot(args);
    let plot_problem = plot.as_ref().and_then(|path| {
        draw(path, &panels)
            .err()
            .map(|e| Problem::error("io", format!("cannot draw `{}`: {e}", path.display())))
    });
    Ok(Outcome {
        model: ir.name.clone(),
        outputs: ir.states.clone(),
        experiments: results,
        plot,
        plot_problem,
    })
}

fn render(args: &ValidateArgs, o: &Outcome) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: simulated with {} (fit = 100·(1 − ‖y − ŷ‖/‖y − ȳ‖), %)\n",
        o.model,
        args.params.display()
    );
    let mut rows = vec![{
        let mut h = vec!["experiment".to_string(), "samples".to_string()];
        h.extend(o.outputs.iter().cloned());
        h
    }];
    for e in &o.experiments {
        let mut r = vec![e.name.clone(), e.samples.to_string()];
        r.extend(e.fit.0.iter().map(|(_, f)| match f {
            Some(f) => format!("{f:.2}"),
            None if e.diverged => "diverged".to_string(),
            None => "-".to_string(),
        }));
        rows.push(r);
    }
    s.push_str(&table(&rows));
    if let (Some(p), None) = (&o.plot, &o.plot_problem) {
        let _ = writeln!(s, "\nplot: {}", p.display());
    }
    s
}
