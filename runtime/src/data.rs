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

/// Options of CSV loading.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Sample time to use when the model declares none and there is no time column.
    pub step: Option<f64>,
}

/// Loads one CSV file: one experiment, or several when it has an
/// `experiment` column (each experiment's rows contiguous, in file order).
pub fn load_csv(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<Vec<Experiment>, DataError> {
    let file = path.display().to_string();
    let text = std::fs::read(path).map_err(|e| {
        DataError::new(
            &file,
            format!("cannot read the file: {e}"),
            "check the path passed to --data",
        )
    })?;
    parse_csv(&file, &text, ir, options)
}

/// Parses CSV text (see [`load_csv`]); `file` names it in errors.
pub fn parse_csv(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
) -> Result<Vec<Experiment>, DataError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(text);
    let headers: Vec<String> = reader
        .headers()
        .map_err(|e| {
            DataError::new(
                format!("{file}:1"),
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
                format!("{file}:1:{}", i + 1),
                format!(
                    "column `{h}` appears twice (columns {} and {})",
                    j + 1,
                    i + 1
                ),
                "rename one of them; leeway will not guess which is meant",
            ));
        }
    }
    let mut cols: Vec<(Role, usize, String)> = Vec::new();
    for (signal, role) in required_signals(ir) {
        let col = column_name(ir, &signal);
        match find(&col) {
            Some(i) => cols.push((role, i, col)),
            None => {
                let mapped = if col != signal {
                    format!(" (mapped from `{signal}` by the model's data block)")
                } else {
                    String::new()
                };
                return Err(DataError::new(
                    format!("{file}:1"),
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
    let exp_col = find(&column_name(ir, "experiment"));
    let base_name = Path::new(file)
        .file_stem()
        .map_or(file.to_string(), |s| s.to_string_lossy().to_string());
    let mut experiments: Vec<(Experiment, Vec<f64>, usize)> = Vec::new();
    let mut finished: Vec<String> = Vec::new();
    let n_comp = ir.components.len();
    let mut states = vec![0.0; ir.states.len()];
    let mut inputs = vec![0.0; ir.inputs.len()];
    let mut rotation = vec![0.0; ir.rotation_vars.len()];
    let mut dist = vec![0.0; n_comp];
    let mut heading = 0.0;
    for (ri, record) in reader.records().enumerate() {
        let line = ri + 2;
        let record = record.map_err(|e| {
            let at = e.position().map_or(line as u64, |p| p.line());
            DataError::new(
                format!("{file}:{at}"),
                format!("malformed row: {e}"),
                "every row needs as many cells as the header",
            )
        })?;
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
        for (role, i, name) in &cols {
            let v = cell(*i, name)?;
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
            Some(i) => Some(cell(i, "time")?),
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
            experiments.push((Experiment::new(ir, &exp_name, 0.0), Vec::new(), line));
        }
        if let Some((e, times, _)) = experiments.last_mut() {
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
        }
    }
    if experiments.is_empty() {
        return Err(DataError::new(
            format!("{file}:2"),
            "the file has a header but no samples",
            "record at least a few hundred samples per experiment",
        ));
    }
    let mut out = Vec::new();
    for (mut e, times, first_line) in experiments {
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
        e.h = sample_time(
            file,
            ir,
            &times,
            first_line,
            time_col.map_or(0, |c| c + 1),
            options,
        )?;
        out.push(e);
    }
    Ok(out)
}

fn sample_time(
    file: &str,
    ir: &Ir,
    times: &[f64],
    first_line: usize,
    time_column: usize,
    options: &LoadOptions,
) -> Result<f64, DataError> {
    let declared = ir.step.or(options.step);
    if times.len() < 2 {
        return declared.ok_or_else(|| {
            DataError::new(
                file,
                "no sample time: the model declares no `step` and the data have no `time` column",
                "declare `step h` in the model or add a `time` column",
            )
        });
    }
    let h = times[1] - times[0];
    for (k, w) in times.windows(2).enumerate() {
        let dt = w[1] - w[0];
        if dt <= 0.0 || (dt - h).abs() > 1e-3 * h.abs() {
            return Err(DataError::new(
                format!("{file}:{}:{time_column} (time)", first_line + k + 1),
                format!("inconsistent sample time: step {dt} here, {h} at the start"),
                "leeway needs uniformly sampled data; resample the log or split it into experiments at the gaps",
            ));
        }
    }
    // The mean step is the best estimate of a uniform h.
    let mean = (times[times.len() - 1] - times[0]) / (times.len() - 1) as f64;
    if let Some(d) = declared
        && (mean - d).abs() > 1e-3 * d
    {
        return Err(DataError::new(
            format!("{file}:{first_line}:{time_column} (time)"),
            format!("the data are sampled every {mean} s but the model declares step {d}"),
            "make `step` in the model match the data, or resample the data",
        ));
    }
    Ok(declared.unwrap_or(mean))
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
