//! Experiments: the data an estimate is computed from.
//!
//! An experiment is a time series of the model's declared signals (states,
//! inputs, heading or rotation columns, measured disturbance components). It
//! is held column by column in memory ([`Experiment`]) or produced on the fly
//! by any [`Source`] (e.g. a simulator streaming 10⁷ samples): estimators only
//! ever visit samples in order, so their memory does not grow with N.
//!
//! CSV loading validates everything and names the place of every problem
//! (`file:row:column`); nothing is silently dropped or reordered.

use leeway_structure::ir::{Ir, Rotation};
use std::path::Path;

/// One sample as estimators read it.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// Measured states.
    pub states: &'a [f64],
    /// Inputs.
    pub inputs: &'a [f64],
    /// Measured heading (planar rotation; 0 otherwise).
    pub heading: f64,
    /// Measured rotation columns (measured `R`; empty otherwise).
    pub rotation: &'a [f64],
    /// Disturbance components by global index; measured ones from the data,
    /// unmeasured ones 0.
    pub disturbances: &'a [f64],
}

/// A sequence of samples that can be visited any number of times, in order.
pub trait Source: Sync {
    /// The experiment's name (file, or value of the `experiment` column).
    fn name(&self) -> &str;
    /// Number of samples.
    fn len(&self) -> usize;
    /// True when there are no samples.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The sample time `h`.
    fn step(&self) -> f64;
    /// Calls `f` on every sample in order.
    fn visit(&self, f: &mut dyn FnMut(&Row));
}

/// An experiment held in memory, column by column.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// Name.
    pub name: String,
    /// Sample time.
    pub h: f64,
    /// `states[i][k]`.
    pub states: Vec<Vec<f64>>,
    /// `inputs[i][k]`.
    pub inputs: Vec<Vec<f64>>,
    /// Heading per sample (planar rotation), else empty.
    pub heading: Vec<f64>,
    /// `rotation[c][k]` for a measured `R`.
    pub rotation: Vec<Vec<f64>>,
    /// `disturbances[c][k]` for measured components; empty for unmeasured ones.
    pub disturbances: Vec<Vec<f64>>,
}

impl Experiment {
    /// An empty experiment shaped for a model.
    pub fn new(ir: &Ir, name: &str, h: f64) -> Experiment {
        Experiment {
            name: name.to_string(),
            h,
            states: vec![Vec::new(); ir.states.len()],
            inputs: vec![Vec::new(); ir.inputs.len()],
            heading: Vec::new(),
            rotation: vec![
                Vec::new();
                if matches!(ir.rotation, Rotation::Measured { .. }) {
                    ir.rotation_vars.len()
                } else {
                    0
                }
            ],
            disturbances: vec![Vec::new(); ir.components.len()],
        }
    }
    /// Appends one sample (`heading` ignored without a planar rotation,
    /// `disturbances` read only for measured components).
    pub fn push(&mut self, ir: &Ir, row: &Row) {
        for (c, v) in self.states.iter_mut().zip(row.states) {
            c.push(*v);
        }
        for (c, v) in self.inputs.iter_mut().zip(row.inputs) {
            c.push(*v);
        }
        if matches!(ir.rotation, Rotation::Planar { .. }) {
            self.heading.push(row.heading);
        }
        for (c, v) in self.rotation.iter_mut().zip(row.rotation) {
            c.push(*v);
        }
        for (i, comp) in ir.components.iter().enumerate() {
            if ir.disturbances[comp.disturbance].measured {
                self.disturbances[i].push(row.disturbances.get(i).copied().unwrap_or(0.0));
            }
        }
    }
    /// The first `n` samples.
    pub fn truncated(&self, n: usize) -> Experiment {
        let cut = |v: &Vec<Vec<f64>>| v.iter().map(|c| c[..n.min(c.len())].to_vec()).collect();
        Experiment {
            name: self.name.clone(),
            h: self.h,
            states: cut(&self.states),
            inputs: cut(&self.inputs),
            heading: self.heading[..n.min(self.heading.len())].to_vec(),
            rotation: cut(&self.rotation),
            disturbances: cut(&self.disturbances),
        }
    }
}

impl Source for Experiment {
    fn name(&self) -> &str {
        &self.name
    }
    fn len(&self) -> usize {
        self.states.first().map_or(0, Vec::len)
    }
    fn step(&self) -> f64 {
        self.h
    }
    fn visit(&self, f: &mut dyn FnMut(&Row)) {
        let mut states = vec![0.0; self.states.len()];
        let mut inputs = vec![0.0; self.inputs.len()];
        let mut rotation = vec![0.0; self.rotation.len()];
        let mut dist = vec![0.0; self.disturbances.len()];
        for k in 0..self.len() {
            for (d, c) in states.iter_mut().zip(&self.states) {
                *d = c[k];
            }
            for (d, c) in inputs.iter_mut().zip(&self.inputs) {
                *d = c[k];
            }
            for (d, c) in rotation.iter_mut().zip(&self.rotation) {
                *d = c[k];
            }
            for (d, c) in dist.iter_mut().zip(&self.disturbances) {
                *d = c.get(k).copied().unwrap_or(0.0);
            }
            let heading = self.heading.get(k).copied().unwrap_or(0.0);
            f(&Row {
                states: &states,
                inputs: &inputs,
                heading,
                rotation: &rotation,
                disturbances: &dist,
            });
        }
    }
}

/// A data problem, with its place.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{location}: {message}")]
pub struct DataError {
    /// `file`, `file:row` or `file:row:column`.
    pub location: String,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: String,
}

impl DataError {
    fn new(
        location: impl Into<String>,
        message: impl Into<String>,
        hint: impl Into<String>,
    ) -> DataError {
        DataError {
            location: location.into(),
            message: message.into(),
            hint: hint.into(),
        }
    }
}

/// The data column a model signal is read from (`data { }` mapping or its own name).
pub fn column_name(ir: &Ir, signal: &str) -> String {
    ir.data_columns
        .get(signal)
        .cloned()
        .unwrap_or_else(|| signal.to_string())
}

/// The signals a model reads from data, as (signal name, role).
#[derive(Clone, Debug, PartialEq, Eq)]
enum Role {
    State(usize),
    Input(usize),
    Heading,
    Rotation(usize),
    Disturbance(usize),
}

fn required_signals(ir: &Ir) -> Vec<(String, Role)> {
    let mut v: Vec<(String, Role)> = Vec::new();
    v.extend(
        ir.states
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), Role::State(i))),
    );
    v.extend(
        ir.inputs
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), Role::Input(i))),
    );
    match &ir.rotation {
        Rotation::Planar { heading, .. } => v.push((heading.clone(), Role::Heading)),
        Rotation::Measured { .. } => v.extend(
            ir.rotation_vars
                .iter()
                .enumerate()
                .map(|(i, s)| (s.clone(), Role::Rotation(i))),
        ),
        Rotation::None => {}
    }
    for (i, c) in ir.components.iter().enumerate() {
        if ir.disturbances[c.disturbance].measured {
            v.push((c.name.clone(), Role::Disturbance(i)));
        }
    }
    v
}

/// The smallest number of samples an experiment may have.
pub const MIN_SAMPLES: usize = 10;

/// The default relative tolerance of each time step against the nominal
/// step: covers a logger's jitter, still catches a dropped sample (a 100 %
/// step error).
pub const DEFAULT_TIME_TOLERANCE: f64 = 0.05;

/// Options of CSV loading.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Sample time to use when the model declares none and there is no time column.
    pub step: Option<f64>,
    /// Largest relative deviation `|Δt − h|/h` of a time step from the nominal
    /// step `h` (the mean step of the experiment), as a fraction.
    pub time_tolerance: f64,
    /// Resample every experiment onto a uniform grid of this step (seconds),
    /// by linear interpolation (needs a time column).
    pub resample: Option<f64>,
}

impl Default for LoadOptions {
    fn default() -> LoadOptions {
        LoadOptions {
            step: None,
            time_tolerance: DEFAULT_TIME_TOLERANCE,
            resample: None,
        }
    }
}

/// What loading a file did besides reading samples, for the user to see:
/// nothing is skipped, tolerated or converted silently.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileNotes {
    /// The file as named in messages.
    pub file: String,
    /// Lines skipped because their first non-blank character is `#`.
    pub comment_lines: usize,
    /// Per experiment of the file, in order.
    pub experiments: Vec<TimeNotes>,
}

/// How one experiment's time stamps were read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimeNotes {
    /// The experiment's name.
    pub experiment: String,
    /// Rows read from the file.
    pub rows: usize,
    /// The largest `|Δt − h|/h` over its steps, when there is a time column
    /// (0 for exactly uniform stamps, up to the tolerance otherwise).
    pub max_step_deviation: Option<f64>,
    /// Samples after resampling (`None` when not resampled).
    pub resampled: Option<usize>,
}

/// A loaded file: its experiments and what was noted while reading it.
#[derive(Clone, Debug)]
pub struct LoadedFile {
    /// The experiments, in file order.
    pub experiments: Vec<Experiment>,
    /// Comment lines, time-stamp jitter, resampling.
    pub notes: FileNotes,
}

/// Loads one CSV file: one experiment, or several when it has an
/// `experiment` column (each experiment's rows contiguous, in file order).
pub fn load_csv(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<Vec<Experiment>, DataError> {
    load_csv_noted(path, ir, options).map(|f| f.experiments)
}

/// [`load_csv`], also returning what was noted on the way ([`FileNotes`]).
pub fn load_csv_noted(
    path: &Path,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    let file = path.display().to_string();
    let text = std::fs::read(path).map_err(|e| {
        DataError::new(
            &file,
            format!("cannot read the file: {e}"),
            "check the path passed to --data",
        )
    })?;
    parse_csv_noted(&file, &text, ir, options)
}

/// Parses CSV text (see [`load_csv`]); `file` names it in errors.
pub fn parse_csv(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
) -> Result<Vec<Experiment>, DataError> {
    parse_csv_noted(file, text, ir, options).map(|f| f.experiments)
}

/// Splits off comment lines (first non-blank character `#`, anywhere in the
/// file, also before the header): the remaining text, and for each of its
/// lines the physical line number in the file, so that every error still
/// names the line an editor shows.
fn strip_comments(text: &[u8]) -> (Vec<u8>, Vec<usize>, usize) {
    let mut kept = Vec::with_capacity(text.len());
    let mut lines = Vec::new();
    let mut comments = 0;
    for (i, line) in text.split_inclusive(|b| *b == b'\n').enumerate() {
        let first = line.iter().find(|b| !b.is_ascii_whitespace());
        if first == Some(&b'#') {
            comments += 1;
            continue;
        }
        kept.extend_from_slice(line);
        lines.push(i + 1);
    }
    (kept, lines, comments)
}

/// [`parse_csv`], also returning what was noted on the way ([`FileNotes`]).
pub fn parse_csv_noted(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    let (text, physical, comment_lines) = strip_comments(text);
    // csv counts lines of the text without comments, from 1; map them back.
    let line_of = |kept_line: u64| -> usize {
        usize::try_from(kept_line)
            .ok()
            .and_then(|l| physical.get(l.checked_sub(1)?).copied())
            .unwrap_or_else(|| physical.last().map_or(1, |l| l + 1))
    };
    let header_line = line_of(1);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(text.as_slice());
    let headers: Vec<String> = reader
        .headers()
        .map_err(|e| {
            DataError::new(
                format!("{file}:{header_line}"),
                format!("cannot read the header row: {e}"),
                "the first row names the columns",
            )
        })?
        .iter()
        .map(str::to_string)
        .collect();
    let find = |name: &str| headers.iter().position(|h| h == name);
    for (i, h) in headers.iter().enumerate() {
        if let Some(j) = headers[..i].iter().position(|g| g == h) {
            return Err(DataError::new(
                format!("{file}:{header_line}:{}", i + 1),
                format!(
                    "column `{h}` appears twice (columns {} and {})",
                    j + 1,
                    i + 1
                ),
                "rename one of them; leeway will not guess which is meant",
            ));
        }
    }
    let mut cols: Vec<(Role, usize, String, f64)> = Vec::new();
    for (signal, role) in required_signals(ir) {
        let col = column_name(ir, &signal);
        match find(&col) {
            Some(i) => cols.push((role, i, col, unit_factor(ir, &signal))),
            None => {
                let mapped = if col != signal {
                    format!(" (mapped from `{signal}` by the model's data block)")
                } else {
                    String::new()
                };
                return Err(DataError::new(
                    format!("{file}:{header_line}"),
                    format!("missing column `{col}`{mapped}"),
                    format!(
                        "the header has: {}. Name the column `{col}`, or map it in the model: data {{ {signal} = \"<column>\" }}",
                        headers.join(", ")
                    ),
                ));
            }
        }
    }
    let time_col = find(&column_name(ir, "time"));
    let time_factor = unit_factor(ir, "time");
    let exp_col = find(&column_name(ir, "experiment"));
    let base_name = Path::new(file)
        .file_stem()
        .map_or(file.to_string(), |s| s.to_string_lossy().to_string());
    // Each experiment with its time stamps and the physical line of every row.
    let mut experiments: Vec<(Experiment, Vec<f64>, Vec<usize>)> = Vec::new();
    let mut finished: Vec<String> = Vec::new();
    let n_comp = ir.components.len();
    let mut states = vec![0.0; ir.states.len()];
    let mut inputs = vec![0.0; ir.inputs.len()];
    let mut rotation = vec![0.0; ir.rotation_vars.len()];
    let mut dist = vec![0.0; n_comp];
    let mut heading = 0.0;
    let mut next_line = header_line + 1;
    for record in reader.records() {
        let record = record.map_err(|e| {
            let at = e.position().map_or(next_line, |p| line_of(p.line()));
            DataError::new(
                format!("{file}:{at}"),
                format!("malformed row: {e}"),
                "every row needs as many cells as the header",
            )
        })?;
        let line = record.position().map_or(next_line, |p| line_of(p.line()));
        next_line = line + 1;
        let cell = |i: usize, name: &str| -> Result<f64, DataError> {
            let raw = record.get(i).unwrap_or("");
            let loc = format!("{file}:{line}:{} ({name})", i + 1);
            match raw.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                Ok(_) => Err(DataError::new(
                    loc,
                    format!("`{raw}` is not a finite number"),
                    "NaN and infinite values are not accepted; remove or repair the sample, leeway does not interpolate",
                )),
                Err(_) if raw.is_empty() => Err(DataError::new(
                    loc,
                    "empty cell",
                    "every sample needs every signal; leeway does not fill gaps",
                )),
                Err(_) => Err(DataError::new(
                    loc,
                    format!("`{raw}` is not a number"),
                    "use a plain decimal such as 0.25 or -1.5e-3",
                )),
            }
        };
        for (role, i, name, factor) in &cols {
            // Declared units are converted here, once, to the model's base units.
            let v = cell(*i, name)? * factor;
            match role {
                Role::State(s) => states[*s] = v,
                Role::Input(s) => inputs[*s] = v,
                Role::Heading => heading = v,
                Role::Rotation(s) => rotation[*s] = v,
                Role::Disturbance(s) => dist[*s] = v,
            }
        }
        let exp_name = match exp_col {
            Some(i) => record.get(i).unwrap_or("").to_string(),
            None => base_name.clone(),
        };
        let t = match time_col {
            Some(i) => Some(cell(i, "time")? * time_factor),
            None => None,
        };
        let start_new = experiments
            .last()
            .is_none_or(|(e, _, _)| e.name != exp_name);
        if start_new {
            if finished.contains(&exp_name)
                || experiments.iter().any(|(e, _, _)| e.name == exp_name)
            {
                return Err(DataError::new(
                    format!(
                        "{file}:{line}:{} (experiment)",
                        exp_col.map_or(0, |i| i + 1)
                    ),
                    format!("experiment `{exp_name}` resumes after another experiment started"),
                    "keep the rows of one experiment together, in time order",
                ));
            }
            if let Some((e, _, _)) = experiments.last() {
                finished.push(e.name.clone());
            }
            experiments.push((Experiment::new(ir, &exp_name, 0.0), Vec::new(), Vec::new()));
        }
        if let Some((e, times, lines)) = experiments.last_mut() {
            e.push(
                ir,
                &Row {
                    states: &states,
                    inputs: &inputs,
                    heading,
                    rotation: &rotation,
                    disturbances: &dist,
                },
            );
            if let Some(t) = t {
                times.push(t);
            }
            lines.push(line);
        }
    }
    if experiments.is_empty() {
        return Err(DataError::new(
            format!("{file}:{}", header_line + 1),
            "the file has a header but no samples",
            "record at least a few hundred samples per experiment",
        ));
    }
    let mut out = Vec::new();
    let mut notes = FileNotes {
        file: file.to_string(),
        comment_lines,
        experiments: Vec::new(),
    };
    for (mut e, times, lines) in experiments {
        let first_line = lines.first().copied().unwrap_or(header_line + 1);
        let n = e.len();
        if n < MIN_SAMPLES {
            return Err(DataError::new(
                format!("{file}:{first_line}"),
                format!(
                    "experiment `{}` has {n} samples; at least {MIN_SAMPLES} are needed",
                    e.name
                ),
                "an estimate needs many more samples than parameters; record a longer experiment",
            ));
        }
        let time_column = time_col.map_or(0, |c| c + 1);
        let (h, deviation) = sample_time(file, ir, &times, &lines, time_column, options)?;
        e.h = h;
        let mut time_notes = TimeNotes {
            experiment: e.name.clone(),
            rows: n,
            max_step_deviation: deviation,
            resampled: None,
        };
        if let Some(step) = options.resample {
            if times.len() != n {
                return Err(DataError::new(
                    format!("{file}:{header_line}"),
                    "--resample needs a time column, and the file has none",
                    format!(
                        "add a `{}` column of time stamps (or map one with data {{ time = \"<column>\" }}), or drop --resample",
                        column_name(ir, "time")
                    ),
                ));
            }
            e = crate::resample::resample(ir, &e, &times, step);
            if e.len() < MIN_SAMPLES {
                return Err(DataError::new(
                    format!("{file}:{first_line}"),
                    format!(
                        "experiment `{}` has {} samples at --resample {step}; at least {MIN_SAMPLES} are needed",
                        e.name,
                        e.len()
                    ),
                    "choose a smaller --resample step",
                ));
            }
            time_notes.resampled = Some(e.len());
        }
        notes.experiments.push(time_notes);
        out.push(e);
    }
    Ok(LoadedFile {
        experiments: out,
        notes,
    })
}

/// The factor converting a signal's declared unit to the base unit (1 when
/// none is declared).
fn unit_factor(ir: &Ir, signal: &str) -> f64 {
    ir.data_units
        .get(signal)
        .map_or(1.0, |u| leeway_structure::units::factor(u))
}

/// The sample time of one experiment and the largest relative deviation of
/// its steps from it (`None` without time stamps). The nominal step is the
/// mean step; every step must lie within `options.time_tolerance` of it, in
/// relative terms. `lines` are the rows' physical line numbers.
fn sample_time(
    file: &str,
    ir: &Ir,
    times: &[f64],
    lines: &[usize],
    time_column: usize,
    options: &LoadOptions,
) -> Result<(f64, Option<f64>), DataError> {
    let declared = ir.step.or(options.step);
    let first_line = lines.first().copied().unwrap_or(0);
    if times.len() < 2 {
        let h = declared.ok_or_else(|| {
            DataError::new(
                file,
                "no sample time: the model declares no `step` and the data have no `time` column",
                "declare `step h` in the model or add a `time` column",
            )
        })?;
        return Ok((h, None));
    }
    // The nominal step is the mean step, the best estimate of a uniform h
    // under jitter. A gap shifts the mean of a short record, so that good
    // steps may fall outside the tolerance too: the error names the worst
    // step, which is the gap.
    let mean = (times[times.len() - 1] - times[0]) / (times.len() - 1) as f64;
    let tol = options.time_tolerance;
    let at = |k: usize| {
        let line = lines.get(k + 1).copied().unwrap_or(first_line);
        format!("{file}:{line}:{time_column} (time)")
    };
    let hint = "leeway needs uniformly sampled data: a larger jitter may be allowed with --time-tolerance, \
                --resample H interpolates onto a uniform grid, or split the log into experiments at the gaps";
    if let Some((k, dt)) = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .enumerate()
        .find(|(_, dt)| *dt <= 0.0)
    {
        return Err(DataError::new(
            at(k),
            format!("time does not increase: step {dt} s here"),
            hint,
        ));
    }
    let (worst_k, worst) = times
        .windows(2)
        .map(|w| ((w[1] - w[0]) - mean).abs() / mean)
        .enumerate()
        .fold(
            (0, 0.0f64),
            |best, (k, d)| if d > best.1 { (k, d) } else { best },
        );
    // Resampling interpolates over any spacing; only the order matters then.
    if options.resample.is_none() && worst > tol {
        let dt = times[worst_k + 1] - times[worst_k];
        return Err(DataError::new(
            at(worst_k),
            format!(
                "inconsistent sample time: step {dt} s here, {:.1} % off the nominal (mean) step {mean} s; the tolerance is {:.1} %",
                100.0 * worst,
                100.0 * tol
            ),
            hint,
        ));
    }
    // Under resampling the grid step is the sample time, checked against the
    // model's step by the caller.
    let h = options.resample.unwrap_or(mean);
    if let Some(d) = declared
        && (h - d).abs() > 1e-3 * d
    {
        let what = if options.resample.is_some() {
            format!("--resample {h} conflicts with the model's step {d}")
        } else {
            format!("the data are sampled every {mean} s but the model declares step {d}")
        };
        return Err(DataError::new(
            format!("{file}:{first_line}:{time_column} (time)"),
            what,
            "make `step` in the model match the data, or resample the data (--resample H)",
        ));
    }
    Ok((declared.unwrap_or(h), Some(worst)))
}

/// Unit check of a heading that integrates a yaw rate: the least-squares gain
/// of `Δψ/h` on `r` (≈ 1 when consistent, ≈ 57.3 when ψ is in degrees and r
/// in rad/s). `None` without a planar heading or with too little yaw motion.
pub fn heading_gain(ir: &Ir, e: &Experiment) -> Option<f64> {
    let Rotation::Planar { integrates, .. } = &ir.rotation else {
        return None;
    };
    let r = &e.states[*integrates];
    // A log may wrap its heading at ±π (radians) or ±180 (degrees), or not at
    // all. Fit the gain of Δψ/h on r under each hypothesis (removing whole
    // periods from every step) and keep the one that explains Δψ/h best: a
    // threshold on the step size would mistake large steps in degrees for
    // wraps in radians.
    let fit = |period: Option<f64>| -> Option<(f64, f64)> {
        let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
        for k in 1..e.heading.len().min(r.len()) {
            let mut d = e.heading[k] - e.heading[k - 1];
            if let Some(p) = period {
                d -= p * (d / p).round();
            }
            let y = d / e.h;
            let x = r[k - 1];
            sxy += x * y;
            sxx += x * x;
            syy += y * y;
        }
        (sxx > 1e-12).then(|| {
            let gain = sxy / sxx;
            (gain, syy - gain * sxy)
        })
    };
    [None, Some(2.0 * std::f64::consts::PI), Some(360.0)]
        .into_iter()
        .filter_map(fit)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(gain, _)| gain)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(data: &str) -> Ir {
        let src = format!(
            "model M {{ state u, r input delta der u = X*u + T*delta der r = N*r {data} }}"
        );
        leeway_structure::compile(&src, &leeway_structure::Options::default())
            .ir
            .unwrap_or_else(|| panic!("the test model compiles"))
    }

    fn rows(from: usize, n: usize) -> String {
        (from..from + n)
            .map(|k| format!("{k}.0,1,0.5,35\n"))
            .collect()
    }

    #[test]
    fn comment_lines_are_skipped_counted_and_rows_keep_their_line_numbers() {
        let ir = model("step 1.0");
        // Comments before the header, between rows (indented too), and a bad
        // cell on physical line 16.
        let mut text = String::from("# logger v2\n# ship: Test\ntime,u,r,delta\n");
        text.push_str(&rows(0, 5));
        text.push_str("  # pause\n");
        text.push_str(&rows(5, 5));
        text.push_str("10.0,1,x,35\n");
        let err = parse_csv("c.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("the cell `x` is an error"));
        assert_eq!(err.location, "c.csv:15:3 (r)");
        let ok = text.replace("10.0,1,x,35\n", "");
        let loaded = parse_csv_noted("c.csv", ok.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(loaded.notes.comment_lines, 3);
        assert_eq!(loaded.experiments[0].len(), 10);
        // A missing column is located on the header's physical line.
        let err = parse_csv(
            "c.csv",
            ok.replace("delta", "rudder").as_bytes(),
            &ir,
            &LoadOptions::default(),
        )
        .err()
        .unwrap_or_else(|| panic!("a missing column is an error"));
        assert_eq!(err.location, "c.csv:3");
    }

    #[test]
    fn declared_units_are_converted_to_base_units() {
        let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
        let mut text = String::from("time,u,r,rudder\n");
        for k in 0..12 {
            text.push_str(&format!("{},1,{k}.5,35\n", 500 * k));
        }
        let e = parse_csv("u.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let e = &e[0];
        assert_eq!(e.h, 0.5);
        assert_eq!(e.inputs[0][0], 35.0f64.to_radians());
        assert_eq!(e.states[1][3], 3.5f64.to_radians());
        assert_eq!(e.states[0][3], 1.0);
    }

    #[test]
    fn a_dropped_sample_is_located_and_names_the_options() {
        let ir = model("");
        let mut text = String::from("time,u,r,delta\n");
        for k in (0..20).filter(|k| *k != 7) {
            text.push_str(&format!("{},1,0,0\n", f64::from(k) * 0.5));
        }
        let err = parse_csv("d.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("a dropped sample is an error"));
        // Rows 0..6 sit on lines 2..8; the row after the gap is on line 9.
        assert_eq!(err.location, "d.csv:9:1 (time)");
        assert!(err.hint.contains("--time-tolerance") && err.hint.contains("--resample"));
    }
}
