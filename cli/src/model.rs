//! What `estimate`, `simulate` and `validate` share: reading and compiling
//! the model, its data files and parameter files, with every problem located.

use crate::problem::{Failure, Problem};
use leeway_runtime::Experiment;
use leeway_runtime::data::{LoadOptions, heading_gain, load_csv};
use leeway_structure::grammar::{self, Diagnostic, Severity};
use leeway_structure::ir::Ir;
use leeway_structure::{Options, compile};
use std::path::{Path, PathBuf};

/// A compiled model.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The model's IR.
    pub ir: Ir,
    /// The compiler's warnings, one line each (`file:line:col: warning[code]: …`).
    pub warnings: Vec<String>,
}

/// Reads a text file; a problem names the path and what went wrong.
pub fn read_text(path: &Path, what: &str) -> Result<String, Problem> {
    let file = path.display().to_string();
    std::fs::read_to_string(path).map_err(|e| {
        let reason = match e.kind() {
            std::io::ErrorKind::NotFound => "no such file".to_string(),
            std::io::ErrorKind::InvalidData => "it is not UTF-8 text".to_string(),
            _ => e.to_string(),
        };
        Problem::error("io", format!("cannot read {what} `{file}`: {reason}")).at(&file)
    })
}

/// Reads and compiles a model. A model that does not compile is a failure
/// with its rendered diagnostics; one whose θ is not identifiable from any
/// experiment still compiles (the estimator then says why, with the data).
pub fn load(path: &Path, aggregate: bool) -> Result<Loaded, Failure> {
    let file = path.display().to_string();
    let source = read_text(path, "the model")?;
    let compilation = compile(
        &source,
        &Options {
            aggregate,
            patterns: None,
            centring: None,
        },
    );
    let Some(ir) = compilation.ir else {
        return Err(Failure::Model {
            file,
            source,
            diagnostics: compilation.diagnostics,
        });
    };
    let warnings: Vec<Diagnostic> = compilation
        .diagnostics
        .into_iter()
        .filter(|d| d.severity == Severity::Warning)
        .collect();
    let warnings = grammar::render_short(&warnings, &file, &source)
        .lines()
        .map(str::to_string)
        .collect();
    Ok(Loaded { ir, warnings })
}

/// `--step H` against the model's own `step`: a conflict is an error, never
/// silently resolved.
pub fn load_options(ir: &Ir, step: Option<f64>) -> Result<LoadOptions, Problem> {
    if let (Some(declared), Some(given)) = (ir.step, step)
        && (declared - given).abs() > 1e-9 * declared.abs()
    {
        return Err(Problem::error(
            "invalid-option",
            format!("--step {given} conflicts with the model's `step {declared}`"),
        )
        .help("drop --step (the model's step is used), or change `step` in the model"));
    }
    Ok(LoadOptions { step })
}

/// Loads every data file; all files are read and every failing one reported.
pub fn load_data(
    ir: &Ir,
    files: &[PathBuf],
    options: &LoadOptions,
) -> Result<Vec<Experiment>, Failure> {
    let mut experiments = Vec::new();
    let mut problems = Vec::new();
    for path in files {
        match load_csv(path, ir, options) {
            Ok(es) => experiments.extend(es),
            Err(e) => problems.push(Problem::data(&e)),
        }
    }
    if problems.is_empty() {
        Ok(experiments)
    } else {
        Err(Failure::Problems(problems))
    }
}

/// The heading's unit check (SPEC §5): a warning with the measured gain of
/// `Δψ/h` on the yaw rate when it is off by more than 20 %.
pub fn heading_warnings(ir: &Ir, experiments: &[Experiment]) -> Vec<String> {
    let Some(heading) = heading_name(ir) else {
        return Vec::new();
    };
    experiments
        .iter()
        .filter_map(|e| {
            let gain = heading_gain(ir, e)?;
            ((gain - 1.0).abs() > 0.2).then(|| heading_warning(ir, e, &heading, gain))
        })
        .collect()
}

/// The heading gain of every experiment (`None` without a planar heading or
/// with too little yaw motion to tell).
pub fn heading_gains(ir: &Ir, experiments: &[Experiment]) -> Vec<(String, Option<f64>)> {
    experiments
        .iter()
        .map(|e| (e.name.clone(), heading_gain(ir, e)))
        .collect()
}

fn heading_name(ir: &Ir) -> Option<String> {
    match &ir.rotation {
        leeway_structure::ir::Rotation::Planar { heading, .. } => {
            Some(leeway_runtime::data::column_name(ir, heading))
        }
        _ => None,
    }
}

fn heading_warning(ir: &Ir, e: &Experiment, heading: &str, gain: f64) -> String {
    let rate = match &ir.rotation {
        leeway_structure::ir::Rotation::Planar { integrates, .. } => {
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
    format!(
        "experiment `{}`: the heading `{heading}` does not integrate `{rate}`: Δ{heading}/h ≈ {gain:.2}·{rate} (gain {gain:.2}, 1 expected); {why}",
        e.name
    )
}

/// Parses `--disturbance` values (`name=value` or `disturbance.name=value`,
/// comma-separated) into one constant per disturbance component, in the
/// disturbance's own frame (earth for earth-frame media). Only unmeasured
/// components can be given (measured ones come from the data); components
/// not given are zero.
pub fn disturbance_values(ir: &Ir, specs: &[String]) -> Result<Vec<f64>, Problem> {
    let mut values = vec![0.0; ir.components.len()];
    let mut given = vec![false; ir.components.len()];
    let unmeasured: Vec<String> = ir
        .components
        .iter()
        .filter(|c| !ir.disturbances[c.disturbance].measured)
        .map(|c| format!("{}.{}", ir.disturbances[c.disturbance].name, c.name))
        .collect();
    let help = if unmeasured.is_empty() {
        format!("model `{}` has no unmeasured disturbance", ir.name)
    } else {
        format!("the unmeasured components are {}", unmeasured.join(", "))
    };
    for spec in specs {
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let bad = |why: String| {
                Problem::error("invalid-option", format!("--disturbance `{item}`: {why}"))
                    .help(&help)
            };
            let Some((name, value)) = item.split_once('=') else {
                return Err(bad(
                    "expected NAME=VALUE, e.g. current.north=0.2".to_string()
                ));
            };
            let name = name.trim();
            let found = ir.components.iter().position(|c| {
                let d = &ir.disturbances[c.disturbance].name;
                name == c.name || name == format!("{d}.{}", c.name)
            });
            let Some(i) = found else {
                return Err(bad(format!("`{name}` is not a disturbance component")));
            };
            if ir.disturbances[ir.components[i].disturbance].measured {
                return Err(bad(format!(
                    "`{name}` is measured: its values come from the data file"
                )));
            }
            if given[i] {
                return Err(bad(format!("`{name}` is given twice")));
            }
            values[i] = match value.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                _ => return Err(bad(format!("`{}` is not a finite number", value.trim()))),
            };
            given[i] = true;
        }
    }
    Ok(values)
}
