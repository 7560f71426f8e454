//! The input of a simulation (`leeway simulate --input`, `leeway.simulate`
//! in Python): a CSV table with a header row and one experiment, read by the
//! data files' readers ([`Table`]: for CSV comment and blank lines skipped, CRLF,
//! quoted cells) and located the same way (`file:row:column (name)`, the
//! physical line).
//!
//! Required columns (after the model's `data { }` mapping): every input, the
//! columns of a measured `R`, and every measured disturbance component, on
//! every row. Optional: `time` (uniform, matching the model's `step`), an
//! `experiment` column (one value only), and the states and the heading. The
//! simulation starts from the first row: of a state or heading column only
//! the first row is read (later rows may hold measurements or be empty), and
//! the caller's initial values (`--x0 name=value`) give or override one. A
//! state without either is an error; nothing is assumed to be zero. Declared
//! units are converted to base units, as for data files.

use crate::error::DataError;
use crate::options::LoadOptions;
use crate::validate::Table;
use leeway_model::experiment::{Experiment, column_name};
use leeway_model::number::short_number as num;
use leeway_structure::ir::{Ir, Rotation};
use std::path::Path;

/// A loaded input: the experiment to simulate on, and the time of its first row.
#[derive(Clone, Debug)]
pub struct Input {
    /// States and heading hold their initial value on every row.
    pub experiment: Experiment,
    /// The first row's time (0 without a time column).
    pub t0: f64,
}

/// How the caller spells its options, for hints: the initial value of a
/// signal (`--x0 u=VALUE`) and the sample time (`--step H`).
#[derive(Clone, Copy, Debug)]
pub struct OptionNames {
    /// The option giving `name`'s initial value.
    pub x0: fn(&str) -> String,
    /// The option giving the sample time.
    pub step: &'static str,
}

/// How one required column is read.
#[derive(Clone, Copy, Debug)]
enum Role {
    Input(usize),
    Rotation(usize),
    Disturbance(usize),
}

/// Reads an input through the data files' readers ([`Table`]: for CSV comment and
/// blank lines skipped and counted, every problem at its physical line).
/// `x0` gives or overrides initial values (base units), by state or heading
/// name; `names` says how the caller's options are spelled in hints.
pub fn read_input(
    records: &mut dyn Table,
    ir: &Ir,
    options: &LoadOptions,
    x0: &[(String, f64)],
    names: &OptionNames,
) -> Result<Input, DataError> {
    let file = records.file().to_string();
    let file = file.as_str();
    let header_at = records.header_at(None);
    let headers = records.headers().to_vec();
    let required = required_columns(ir, &headers, &header_at)?;
    let mut initial = initial_values(ir, &headers, &header_at, x0, names)?;
    let time_col = headers.iter().position(|h| *h == column_name(ir, "time"));
    let read = read_rows(records, ir, &required, &mut initial, time_col, &headers)?;
    let time_name = column_name(ir, "time");
    let first_time_at = time_col.map(|i| records.at(read.first_line, Some((i, &time_name))));
    let h = sample_time(file, ir, &read.times, first_time_at, options, names)?;
    let name = read.experiment.clone().unwrap_or_else(|| {
        Path::new(file)
            .file_stem()
            .map_or(file.to_string(), |s| s.to_string_lossy().to_string())
    });
    let t0 = read.times.first.unwrap_or(0.0);
    Ok(Input {
        experiment: read.into_experiment(ir, &name, h, &initial),
        t0,
    })
}

/// A column the simulation reads on every row: its role, index and name.
type Required = (Role, usize, String);

/// An initial value: the state or heading, its value once known, and the
/// column its first row gives it from (none when `x0` gives it).
type Initial = (String, Option<f64>, Option<usize>);

/// Every input, measured rotation and measured disturbance column, or the
/// error naming the first missing one.
fn required_columns(
    ir: &Ir,
    headers: &[String],
    header_at: &str,
) -> Result<Vec<Required>, DataError> {
    let mut wanted: Vec<(Role, String)> = ir
        .inputs
        .iter()
        .enumerate()
        .map(|(i, s)| (Role::Input(i), s.clone()))
        .collect();
    if matches!(ir.rotation, Rotation::Measured { .. }) {
        wanted.extend(
            ir.rotation_vars
                .iter()
                .enumerate()
                .map(|(i, s)| (Role::Rotation(i), s.clone())),
        );
    }
    for (i, c) in ir.components.iter().enumerate() {
        if ir.disturbances[c.disturbance].measured {
            wanted.push((Role::Disturbance(i), c.name.clone()));
        }
    }
    let mut required = Vec::with_capacity(wanted.len());
    for (role, signal) in wanted {
        let col = column_name(ir, &signal);
        let Some(i) = headers.iter().position(|h| *h == col) else {
            return Err(DataError::new(
                header_at,
                format!("missing column `{col}`"),
                format!(
                    "the header has: {}. A simulation needs every input, measured rotation and measured disturbance on every row",
                    leeway_structure::grammar::join_capped(headers, ", ")
                ),
            ));
        };
        required.push((role, i, col));
    }
    Ok(required)
}

/// Initial values: `x0` first, else the first row of the state's column.
fn initial_values(
    ir: &Ir,
    headers: &[String],
    header_at: &str,
    x0: &[(String, f64)],
    names: &OptionNames,
) -> Result<Vec<Initial>, DataError> {
    let find = |name: &str| headers.iter().position(|h| h == name);
    let mut initial: Vec<Initial> = ir
        .states
        .iter()
        .map(|s| (s.clone(), None, find(&column_name(ir, s))))
        .collect();
    if let Rotation::Planar { heading, .. } = &ir.rotation {
        initial.push((heading.clone(), None, find(&column_name(ir, heading))));
    }
    for (name, value, col) in &mut initial {
        if let Some((_, v)) = x0.iter().find(|(n, _)| n == name) {
            *value = Some(*v);
            *col = None;
        } else if col.is_none() {
            return Err(DataError::new(
                header_at,
                format!(
                    "no initial value for `{name}`: the input has no column `{}`",
                    column_name(ir, name)
                ),
                format!(
                    "add a `{}` column (only its first row is read) or pass {}",
                    column_name(ir, name),
                    (names.x0)(name)
                ),
            ));
        }
    }
    Ok(initial)
}

/// What the rows of an input gave.
struct Rows {
    inputs: Vec<Vec<f64>>,
    rotation: Vec<Vec<f64>>,
    disturbances: Vec<Vec<f64>>,
    times: TimeSteps,
    experiment: Option<String>,
    rows: usize,
    first_line: u64,
}

/// Reads every row: the required columns (in base units), the initial
/// values from the first row, the time stamps checked as they come, and the
/// one experiment's label.
fn read_rows(
    records: &mut dyn Table,
    ir: &Ir,
    required: &[Required],
    initial: &mut [Initial],
    time_col: Option<usize>,
    headers: &[String],
) -> Result<Rows, DataError> {
    let time_name = column_name(ir, "time");
    let exp_col = headers
        .iter()
        .position(|h| *h == column_name(ir, "experiment"));
    let mut read = Rows {
        inputs: vec![Vec::new(); ir.inputs.len()],
        rotation: vec![Vec::new(); ir.rotation_vars.len()],
        disturbances: vec![Vec::new(); ir.components.len()],
        times: TimeSteps::default(),
        experiment: None,
        rows: 0,
        first_line: records.first_position(),
    };
    while records.next_row()? {
        let line = records.position();
        read.push_required(records, ir, required)?;
        if read.rows == 0 {
            read.first_line = line;
            for (name, value, col) in initial.iter_mut() {
                if let Some(i) = *col {
                    *value = Some(records.number(i, &column_name(ir, name))? * unit(ir, name));
                }
            }
        }
        if let Some(i) = time_col {
            let t = records.number(i, &time_name)? * unit(ir, "time");
            read.times
                .push(t, || records.at(line, Some((i, &time_name))))?;
        }
        if let Some(i) = exp_col {
            let name = String::from_utf8_lossy(&records.label(i)?).into_owned();
            match &read.experiment {
                None => read.experiment = Some(name),
                Some(first) if *first != name => {
                    return Err(DataError::new(
                        records.at(line, Some((i, "experiment"))),
                        format!("a second experiment `{name}` starts here (after `{first}`)"),
                        "a simulation takes one experiment: split the input",
                    ));
                }
                Some(_) => {}
            }
        }
        read.rows += 1;
    }
    if read.rows == 0 {
        return Err(DataError::new(
            records.at(records.first_position(), None),
            "the file has a header but no samples",
            "one row per sample of the input",
        ));
    }
    Ok(read)
}

impl Rows {
    /// One row's required columns, declared units converted to base units
    /// (as for data files).
    fn push_required(
        &mut self,
        records: &mut dyn Table,
        ir: &Ir,
        required: &[Required],
    ) -> Result<(), DataError> {
        for (role, i, name) in required {
            let signal = match role {
                Role::Input(s) => ir.inputs.get(*s),
                Role::Rotation(s) => ir.rotation_vars.get(*s),
                Role::Disturbance(s) => ir.components.get(*s).map(|c| &c.name),
            };
            let v = records.number(*i, name)? * signal.map_or(1.0, |s| unit(ir, s));
            match role {
                Role::Input(s) => self.inputs[*s].push(v),
                Role::Rotation(s) => self.rotation[*s].push(v),
                Role::Disturbance(s) => self.disturbances[*s].push(v),
            }
        }
        Ok(())
    }

    /// The experiment a simulation starts from: the initial values held on
    /// every row (states, heading), the inputs and measured signals as read.
    fn into_experiment(mut self, ir: &Ir, name: &str, h: f64, initial: &[Initial]) -> Experiment {
        let mut e = Experiment::new(ir, name, h);
        let value = |name: &str| {
            initial
                .iter()
                .find(|(n, _, _)| n == name)
                .and_then(|(_, v, _)| *v)
                .unwrap_or(0.0)
        };
        e.states = ir
            .states
            .iter()
            .map(|s| vec![value(s); self.rows])
            .collect();
        if let Rotation::Planar { heading, .. } = &ir.rotation {
            e.heading = vec![value(heading); self.rows];
        }
        e.inputs = self.inputs;
        if matches!(ir.rotation, Rotation::Measured { .. }) {
            e.rotation = self.rotation;
        }
        for (i, c) in ir.components.iter().enumerate() {
            if ir.disturbances[c.disturbance].measured {
                e.disturbances[i] = std::mem::take(&mut self.disturbances[i]);
            }
        }
        e
    }
}

/// The time stamps of the input, checked as they are read: each step equal
/// to the first within 0.1 % and positive (a simulation steps uniformly),
/// without holding them.
#[derive(Clone, Debug, Default)]
struct TimeSteps {
    first: Option<f64>,
    last: f64,
    /// The first step.
    h: Option<f64>,
    count: usize,
}

impl TimeSteps {
    fn push(&mut self, t: f64, at: impl Fn() -> String) -> Result<(), DataError> {
        if self.first.is_some() {
            let dt = t - self.last;
            let h = *self.h.get_or_insert(dt);
            if dt <= 0.0 || (dt - h).abs() > 1e-3 * h.abs() {
                return Err(DataError::new(
                    at(),
                    format!(
                        "inconsistent sample time: step {} s here, {} s at the start",
                        num(dt),
                        num(h)
                    ),
                    "leeway needs uniformly sampled data; resample the input",
                ));
            }
        } else {
            self.first = Some(t);
        }
        self.last = t;
        self.count += 1;
        Ok(())
    }
}

/// The factor from a signal's declared unit to its base unit (1 without one).
fn unit(ir: &Ir, signal: &str) -> f64 {
    ir.data_units
        .get(signal)
        .map_or(1.0, |u| leeway_structure::units::factor(u))
}

/// The sample time: from the time column (uniform, checked as read, and
/// against the model's `step`), else the model's `step`, else `--step`.
/// `first_at` locates the first row's time cell.
fn sample_time(
    file: &str,
    ir: &Ir,
    times: &TimeSteps,
    first_at: Option<String>,
    options: &LoadOptions,
    names: &OptionNames,
) -> Result<f64, DataError> {
    let declared = ir.step.or(options.step);
    let (Some(first), true) = (times.first, times.count >= 2) else {
        return declared.ok_or_else(|| {
            DataError::new(
                file,
                "no sample time: the model declares no `step` and the input has no `time` column (or one row)",
                format!(
                    "declare `step h` in the model, add a `time` column, or pass {}",
                    names.step
                ),
            )
        });
    };
    let mean = (times.last - first) / (times.count - 1) as f64;
    if let Some(d) = declared
        && (mean - d).abs() > 1e-3 * d
    {
        return Err(DataError::new(
            first_at.unwrap_or_else(|| file.to_string()),
            format!(
                "the input is sampled every {} s but the model declares step {}",
                num(mean),
                num(d)
            ),
            "make `step` in the model match the data, or resample the input",
        ));
    }
    Ok(declared.unwrap_or(mean))
}
