//! What `estimate`, `simulate` and `validate` share: reading and compiling
//! the model, its data files and parameter files, with every problem located.

use crate::problem::{Failure, Problem};
use leeway_data::FileNotes;
use leeway_data::FileSource;
use leeway_data::LoadOptions;
use leeway_data::load_file_noted;
use leeway_data::open_file;
use leeway_model::Experiment;
use leeway_model::Source;
use leeway_structure::grammar::source::Refused;
use leeway_structure::grammar::{self, Diagnostic, Severity};
use leeway_structure::ir::Ir;
use leeway_structure::{CompileOptions, compile};
use std::path::{Path, PathBuf};

// The data checks and the JSON of the loading notes live in the runtime, so
// that the Python package reports exactly what the CLI does.
pub use leeway_report::DataFileJson;
pub use leeway_report::data_files_json;
pub use leeway_report::heading_gains;
pub use leeway_report::heading_warnings;
pub use leeway_report::unit_warnings;

/// Largest magnitude of a value given on the command line (`--x0`,
/// `--disturbance`): squares of larger values approach f64's range inside
/// the regressors.
pub const MAX_VALUE: f64 = 1e12;

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

/// Reads a model file: its size is checked before reading (a file over
/// [`grammar::MAX_SOURCE_BYTES`] is never read whole: at most one byte more is
/// read), then the bytes are decoded, a non-UTF-8 file refused with the
/// line and column of its first invalid byte. `Err` is an IO failure.
pub fn read_model(path: &Path) -> std::io::Result<Result<String, Box<Refused>>> {
    use std::io::Read;
    let file = std::fs::File::open(path)?;
    let size = file.metadata()?.len();
    let limit = grammar::MAX_SOURCE_BYTES as u64;
    if size > limit {
        return Ok(Err(Box::new(Refused {
            text: String::new(),
            diagnostic: grammar::source::too_large(size),
        })));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes)?;
    Ok(grammar::source::decode(bytes))
}

/// Why a model file cannot be read, as the CLI says it.
pub fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".to_string(),
        std::io::ErrorKind::IsADirectory => "it is a directory".to_string(),
        _ => e.to_string(),
    }
}

/// Reads and compiles a model. A model that does not compile is a failure
/// with its rendered diagnostics; one whose θ is not identifiable from any
/// experiment still compiles (the estimator then says why, with the data).
pub fn load(path: &Path, aggregate: bool) -> Result<Loaded, Failure> {
    let file = path.display().to_string();
    let source = match read_model(path) {
        Ok(Ok(source)) => source,
        Ok(Err(refused)) => {
            return Err(Failure::Model {
                file,
                source: refused.text,
                diagnostics: vec![refused.diagnostic],
            });
        }
        Err(e) => {
            return Err(Problem::error(
                "io",
                format!("cannot read the model `{file}`: {}", io_reason(&e)),
            )
            .at(&file)
            .into());
        }
    };
    let compilation = compile(
        &source,
        &CompileOptions {
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

/// How data files with time stamps are read: shared by `estimate` and `validate`.
#[derive(Debug, Clone, clap::Args)]
pub struct TimeArgs {
    /// Largest relative deviation of a time step from the nominal (mean) step,
    /// as a fraction in (0, 0.5): 0.05 accepts ±5 % logger jitter and still
    /// rejects a dropped sample (a 100 % step).
    #[arg(long, value_name = "TOL", default_value_t = leeway_data::DEFAULT_TIME_TOLERANCE, value_parser = tolerance)]
    pub time_tolerance: f64,
    /// Interpolate every experiment linearly onto a uniform grid of H seconds
    /// from its first time stamp (needs a time column; the heading along the short arc).
    #[arg(long, value_name = "H", value_parser = crate::estimate::positive)]
    pub resample: Option<f64>,
}

/// `--time-tolerance`: a fraction in (0, 0.5). Beyond one half a dropped
/// sample could pass for jitter.
pub fn tolerance(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v < 0.5 => Ok(v),
        Ok(v) if (0.5..50.0).contains(&v) => Err(format!(
            "`{s}` is not a fraction in (0, 0.5) (write 0.05 for 5 %; 0.5 or more would accept a dropped sample)"
        )),
        _ => Err(format!(
            "`{s}` is not a fraction in (0, 0.5): the relative step tolerance, e.g. 0.05 for 5 %"
        )),
    }
}

/// `--step H` against the model's own `step`: a conflict is an error, never
/// silently resolved; so is `--resample H` against it.
pub fn load_options(
    ir: &Ir,
    step: Option<f64>,
    time: Option<&TimeArgs>,
) -> Result<LoadOptions, Problem> {
    if let (Some(declared), Some(given)) = (ir.step, step)
        && (declared - given).abs() > 1e-9 * declared.abs()
    {
        return Err(Problem::error(
            "invalid-option",
            format!("--step {given} conflicts with the model's `step {declared}`"),
        )
        .help("drop --step (the model's step is used), or change `step` in the model"));
    }
    if let (Some(declared), Some(given)) = (ir.step.or(step), time.and_then(|t| t.resample))
        && (declared - given).abs() > 1e-9 * declared.abs()
    {
        return Err(Problem::error(
            "invalid-option",
            format!("--resample {given} conflicts with the sample time {declared} (the model's `step` or --step)"),
        )
        .help(format!("resample at the model's step: --resample {declared}")));
    }
    let mut options = LoadOptions {
        step,
        ..LoadOptions::default()
    };
    if let Some(t) = time {
        options.time_tolerance = t.time_tolerance;
        options.resample = t.resample;
    }
    Ok(options)
}

/// Loads every data file (CSV, or Parquet: extension `.parquet` or the
/// magic `PAR1`); all files are read and every failing one reported.
/// What was noted while reading (comment lines, jitter, resampling) comes back
/// per file, for the output.
pub fn load_data(
    ir: &Ir,
    files: &[PathBuf],
    options: &LoadOptions,
) -> Result<(Vec<Experiment>, Vec<FileNotes>), Failure> {
    load_files(ir, files, options).map(|(e, n)| (e.experiments, n))
}

/// Experiments held in memory, each with its file as messages name it.
struct Held {
    experiments: Vec<Experiment>,
    files: Vec<String>,
}

/// [`load_data`], with each experiment's file.
fn load_files(
    ir: &Ir,
    files: &[PathBuf],
    options: &LoadOptions,
) -> Result<(Held, Vec<FileNotes>), Failure> {
    let mut experiments = Vec::new();
    let mut names = Vec::new();
    let mut notes = Vec::new();
    let mut problems = Vec::new();
    for path in files {
        match load_file_noted(path, ir, options) {
            Ok(f) => {
                let name = path.display().to_string();
                names.extend(f.experiments.iter().map(|_| name.clone()));
                experiments.extend(f.experiments);
                notes.push(f.notes);
            }
            Err(e) => problems.push(Problem::data(&e)),
        }
    }
    if problems.is_empty() {
        let held = Held {
            experiments,
            files: names,
        };
        Ok((held, notes))
    } else {
        Err(Failure::Problems(problems))
    }
}

/// Experiments for an estimate: streamed from their files (validated once,
/// then read on every pass from a binary copy, flat memory in N), or held in
/// memory under `--resample`, which interpolates over a whole experiment.
pub enum DataSet {
    /// Read per pass from the validated copy.
    Streamed(Vec<FileSource>),
    /// Loaded (resampled), with each experiment's file.
    Held(Vec<Experiment>, Vec<String>),
}

impl DataSet {
    /// Every experiment as a source, in file order.
    pub fn sources(&self) -> Vec<&dyn Source> {
        match self {
            DataSet::Streamed(v) => v.iter().map(|e| e as &dyn Source).collect(),
            DataSet::Held(v, _) => v.iter().map(|e| e as &dyn Source).collect(),
        }
    }
    /// Each experiment's file, as named in messages.
    pub fn files(&self) -> Vec<&str> {
        match self {
            DataSet::Streamed(v) => v.iter().map(FileSource::file).collect(),
            DataSet::Held(_, files) => files.iter().map(String::as_str).collect(),
        }
    }
    /// A problem met by a later pass (the validated copy could not be read).
    pub fn failure(&self) -> Option<Problem> {
        match self {
            DataSet::Streamed(v) => v
                .iter()
                .find_map(FileSource::failure)
                .map(|e| Problem::data(&e)),
            DataSet::Held(..) => None,
        }
    }
}

/// [`load_data`] for an estimate: streamed unless `--resample` is given.
pub fn open_data(
    ir: &Ir,
    files: &[PathBuf],
    options: &LoadOptions,
) -> Result<(DataSet, Vec<FileNotes>), Failure> {
    if options.resample.is_some() {
        return load_files(ir, files, options)
            .map(|(h, n)| (DataSet::Held(h.experiments, h.files), n));
    }
    let mut sources = Vec::new();
    let mut notes = Vec::new();
    let mut problems = Vec::new();
    for path in files {
        match open_file(path, ir, options) {
            Ok(f) => {
                sources.extend(f.sources);
                notes.push(f.notes);
            }
            Err(e) => problems.push(Problem::data(&e)),
        }
    }
    if problems.is_empty() {
        Ok((DataSet::Streamed(sources), notes))
    } else {
        Err(Failure::Problems(problems))
    }
}

/// Below this relative step deviation, time stamps count as uniform: decimal
/// stamps such as 0.1·k carry rounding of order 1e-15.
const JITTER_FLOOR: f64 = 1e-6;

/// What loading did, one line each, for the text output: comment lines
/// skipped, jitter tolerated, experiments resampled.
pub fn data_notes(notes: &[FileNotes]) -> Vec<String> {
    let mut lines = Vec::new();
    for f in notes {
        if f.comment_lines > 0 {
            lines.push(format!(
                "{}: {} comment line{} skipped",
                f.file,
                f.comment_lines,
                if f.comment_lines == 1 { "" } else { "s" }
            ));
        }
        if f.blank_lines > 0 {
            lines.push(format!(
                "{}: {} blank line{} skipped",
                f.file,
                f.blank_lines,
                if f.blank_lines == 1 { "" } else { "s" }
            ));
        }
        for e in &f.experiments {
            if let Some(n) = e.resampled {
                lines.push(format!(
                    "{}: experiment `{}` resampled from {} rows to {n} samples",
                    f.file, e.experiment, e.rows
                ));
            }
            if let Some(d) = e.max_step_deviation.filter(|d| *d > JITTER_FLOOR) {
                lines.push(format!(
                    "{}: experiment `{}` time steps deviate up to {:.2} % from the nominal step{}",
                    f.file,
                    e.experiment,
                    100.0 * d,
                    if e.resampled.is_some() {
                        " (before resampling)"
                    } else {
                        " (within --time-tolerance)"
                    }
                ));
            }
        }
    }
    lines
}

/// The declared units, one line each: `delta: column rudder_deg in deg, converted to rad`.
pub fn unit_lines(ir: &Ir) -> Vec<String> {
    ir.data_units
        .iter()
        .map(|(signal, unit)| {
            let column = leeway_model::experiment::column_name(ir, signal);
            let base = leeway_structure::units::unit(unit).map_or("?", |(k, _)| k.base());
            if base == unit {
                format!("{signal}: column {column} in {unit}, read as is")
            } else {
                format!("{signal}: column {column} in {unit}, converted to {base}")
            }
        })
        .collect()
}

/// The unit an axis shows for a signal: the base unit its declared unit
/// converts to, or none (then the axis names the signal only: leeway does
/// not assume what an undeclared column measures).
pub fn axis_label(ir: &Ir, signal: &str) -> String {
    match ir
        .data_units
        .get(signal)
        .and_then(|u| leeway_structure::units::unit(u))
    {
        Some((kind, _)) => format!("{signal} ({})", kind.base()),
        None => signal.to_string(),
    }
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
        format!(
            "the unmeasured components are {}",
            leeway_structure::grammar::join_capped(&unmeasured, ", ")
        )
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
                Ok(v) if v.is_finite() && v.abs() <= MAX_VALUE => v,
                Ok(v) if v.is_finite() => {
                    return Err(bad(format!(
                        "`{}` exceeds {MAX_VALUE:e} in magnitude",
                        value.trim()
                    )));
                }
                _ => return Err(bad(format!("`{}` is not a finite number", value.trim()))),
            };
            given[i] = true;
        }
    }
    Ok(values)
}
