//! The input file of `leeway simulate`: a CSV file with a header row, or a
//! Parquet file, one experiment, read by the data files' readers
//! (`leeway_runtime::data::with_table`: for CSV comment and blank lines
//! skipped, CRLF, quoted cells) and located the same way (`file:row:column
//! (name)`, the physical line; row, row group and column for Parquet).
//!
//! Required columns (after the model's `data { }` mapping): every input, the
//! columns of a measured `R`, and every measured disturbance component, on
//! every row. Optional: `time` (uniform, matching the model's `step`), an
//! `experiment` column (one value only), and the states and the heading. The
//! simulation starts from the first row: of a state or heading column only
//! the first row is read (later rows may hold measurements or be empty), and
//! `--x0 name=value` gives or overrides an initial value. A state without
//! either is an error; nothing is assumed to be zero.

use crate::problem::{Failure, Problem};
use leeway_runtime::DataError;
use leeway_runtime::Experiment;
use leeway_runtime::data::{LoadOptions, Table, column_name, with_table};
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

/// How one required column is read.
#[derive(Clone, Copy, Debug)]
enum Role {
    Input(usize),
    Rotation(usize),
    Disturbance(usize),
}

/// Parses `--x0` values (`name=value`, comma-separated) against the model's
/// states and heading.
pub fn initial_values(ir: &Ir, specs: &[String]) -> Result<Vec<(String, f64)>, Problem> {
    let heading = match &ir.rotation {
        Rotation::Planar { heading, .. } => Some(heading.as_str()),
        _ => None,
    };
    let mut out: Vec<(String, f64)> = Vec::new();
    for spec in specs {
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let Some((name, value)) = item.split_once('=') else {
                return Err(Problem::error(
                    "invalid-option",
                    format!("--x0 `{item}`: expected NAME=VALUE"),
                )
                .help("e.g. --x0 u=5,v=0,r=0.1"));
            };
            let name = name.trim();
            if !ir.states.iter().any(|s| s == name) && heading != Some(name) {
                let mut known: Vec<&str> = ir.states.iter().map(String::as_str).collect();
                known.extend(heading);
                return Err(Problem::error(
                    "invalid-option",
                    format!(
                        "--x0 `{item}`: `{name}` is not a state or the heading of model `{}`",
                        ir.name
                    ),
                )
                .help(format!(
                    "initial values can be given for {}",
                    leeway_structure::grammar::join_capped(&known, ", ")
                )));
            }
            let v = match value.trim().parse::<f64>() {
                Ok(v) if v.is_finite() && v.abs() <= crate::model::MAX_VALUE => v,
                Ok(v) if v.is_finite() => {
                    return Err(Problem::error(
                        "invalid-option",
                        format!(
                            "--x0 `{item}`: `{}` exceeds {:e} in magnitude",
                            value.trim(),
                            crate::model::MAX_VALUE
                        ),
                    )
                    .help(
                        "initial values are physical states; give them in the model's base units",
                    ));
                }
                _ => {
                    return Err(Problem::error(
                        "invalid-option",
                        format!("--x0 `{item}`: `{}` is not a finite number", value.trim()),
                    ));
                }
            };
            if out.iter().any(|(n, _)| n == name) {
                return Err(Problem::error(
                    "invalid-option",
                    format!("--x0 gives `{name}` twice"),
                ));
            }
            out.push((name.to_string(), v));
        }
    }
    Ok(out)
}

/// Loads the input file, reading it record by record (the text is never
/// held: memory is the parsed columns).
pub fn load_input(
    path: &Path,
    ir: &Ir,
    options: &LoadOptions,
    x0: &[(String, f64)],
) -> Result<Input, Failure> {
    with_table(path, "--input", |table| {
        Ok(read_input(table, ir, options, x0))
    })
    .map_err(|e| Problem::data(&e))?
    .map_err(Failure::from)
}

/// Parses the input file's bytes (see [`load_input`]).
#[cfg(test)]
pub fn parse_input(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
    x0: &[(String, f64)],
) -> Result<Input, Problem> {
    let mut records =
        leeway_runtime::data::Records::new(file, text, "--input").map_err(|e| Problem::data(&e))?;
    read_input(&mut records, ir, options, x0)
}

/// Reads the input through a data file's [`Table`] (for CSV comment and
/// blank lines skipped and counted, every problem at its physical line).
fn read_input(
    records: &mut dyn Table,
    ir: &Ir,
    options: &LoadOptions,
    x0: &[(String, f64)],
) -> Result<Input, Problem> {
    let data = |e: DataError| Problem::data(&e);
    let file = records.file().to_string();
    let file = file.as_str();
    let header_at = records.header_at(None);
    let headers = records.headers().to_vec();
    let find = |name: &str| headers.iter().position(|h| h == name);
    let mut required: Vec<(Role, usize, String)> = Vec::new();
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
    for (role, signal) in wanted {
        let col = column_name(ir, &signal);
        match find(&col) {
            Some(i) => required.push((role, i, col)),
            None => {
                return Err(Problem::error("data", format!("missing column `{col}`"))
                    .at(&header_at)
                    .help(format!(
                        "the header has: {}. A simulation needs every input, measured rotation and measured disturbance on every row",
                        leeway_structure::grammar::join_capped(&headers, ", ")
                    )));
            }
        }
    }
    // Initial values: --x0 first, else the first row of the column.
    let mut initial: Vec<(String, Option<f64>, Option<usize>)> = ir
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
            return Err(Problem::error(
                "data",
                format!(
                    "no initial value for `{name}`: the input has no column `{}`",
                    column_name(ir, name)
                ),
            )
            .at(&header_at)
            .help(format!(
                "add a `{}` column (only its first row is read) or pass --x0 {name}=VALUE",
                column_name(ir, name)
            )));
        }
    }
    let time_col = find(&column_name(ir, "time"));
    let time_name = column_name(ir, "time");
    let exp_col = find(&column_name(ir, "experiment"));
    let n_comp = ir.components.len();
    let mut inputs = vec![Vec::new(); ir.inputs.len()];
    let mut rotation = vec![Vec::new(); ir.rotation_vars.len()];
    let mut dist = vec![Vec::new(); n_comp];
    let mut times = TimeSteps::default();
    let mut experiment: Option<String> = None;
    let mut rows = 0usize;
    let mut first_line = records.first_position();
    while records.next_row().map_err(data)? {
        let line = records.position();
        for (role, i, name) in &required {
            // Declared units are converted to base units, as for data files.
            let signal = match role {
                Role::Input(s) => ir.inputs.get(*s),
                Role::Rotation(s) => ir.rotation_vars.get(*s),
                Role::Disturbance(s) => ir.components.get(*s).map(|c| &c.name),
            };
            let v = records.number(*i, name).map_err(data)? * signal.map_or(1.0, |s| unit(ir, s));
            match role {
                Role::Input(s) => inputs[*s].push(v),
                Role::Rotation(s) => rotation[*s].push(v),
                Role::Disturbance(s) => dist[*s].push(v),
            }
        }
        if rows == 0 {
            first_line = line;
            for (name, value, col) in &mut initial {
                if let Some(i) = *col {
                    *value = Some(
                        records.number(i, &column_name(ir, name)).map_err(data)? * unit(ir, name),
                    );
                }
            }
        }
        if let Some(i) = time_col {
            let t = records.number(i, &time_name).map_err(data)? * unit(ir, "time");
            times.push(t, || records.at(line, Some((i, &time_name))))?;
        }
        if let Some(i) = exp_col {
            let name = String::from_utf8_lossy(&records.label(i).map_err(data)?).into_owned();
            match &experiment {
                None => experiment = Some(name),
                Some(first) if *first != name => {
                    return Err(Problem::error(
                        "data",
                        format!("a second experiment `{name}` starts here (after `{first}`)"),
                    )
                    .at(records.at(line, Some((i, "experiment"))))
                    .help("leeway simulate takes one experiment: split the file"));
                }
                Some(_) => {}
            }
        }
        rows += 1;
    }
    if rows == 0 {
        return Err(
            Problem::error("data", "the file has a header but no samples")
                .at(records.at(records.first_position(), None))
                .help("one row per sample of the input"),
        );
    }
    let first_time_at = time_col.map(|i| records.at(first_line, Some((i, &time_name))));
    let h = sample_time(file, ir, &times, first_time_at, options)?;
    let name = experiment.unwrap_or_else(|| {
        Path::new(file)
            .file_stem()
            .map_or(file.to_string(), |s| s.to_string_lossy().to_string())
    });
    let mut e = Experiment::new(ir, &name, h);
    let value = |name: &str| {
        initial
            .iter()
            .find(|(n, _, _)| n == name)
            .and_then(|(_, v, _)| *v)
            .unwrap_or(0.0)
    };
    e.states = ir.states.iter().map(|s| vec![value(s); rows]).collect();
    if let Rotation::Planar { heading, .. } = &ir.rotation {
        e.heading = vec![value(heading); rows];
    }
    e.inputs = inputs;
    if matches!(ir.rotation, Rotation::Measured { .. }) {
        e.rotation = rotation;
    }
    for (i, c) in ir.components.iter().enumerate() {
        if ir.disturbances[c.disturbance].measured {
            e.disturbances[i] = std::mem::take(&mut dist[i]);
        }
    }
    Ok(Input {
        experiment: e,
        t0: times.first.unwrap_or(0.0),
    })
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
    fn push(&mut self, t: f64, at: impl Fn() -> String) -> Result<(), Problem> {
        if self.first.is_some() {
            let dt = t - self.last;
            let h = *self.h.get_or_insert(dt);
            if dt <= 0.0 || (dt - h).abs() > 1e-3 * h.abs() {
                return Err(Problem::error(
                    "data",
                    format!("inconsistent sample time: step {dt} here, {h} at the start"),
                )
                .at(at())
                .help("leeway needs uniformly sampled data; resample the input"));
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
) -> Result<f64, Problem> {
    let declared = ir.step.or(options.step);
    let (Some(first), true) = (times.first, times.count >= 2) else {
        return declared.ok_or_else(|| {
            Problem::error(
                "data",
                "no sample time: the model declares no `step` and the input has no `time` column (or one row)",
            )
            .at(file)
            .help("declare `step h` in the model, add a `time` column, or pass --step H")
        });
    };
    let mean = (times.last - first) / (times.count - 1) as f64;
    if let Some(d) = declared
        && (mean - d).abs() > 1e-3 * d
    {
        return Err(Problem::error(
            "data",
            format!("the input is sampled every {mean} s but the model declares step {d}"),
        )
        .at(first_at.unwrap_or_else(|| file.to_string()))
        .help("make `step` in the model match the data, or resample the input"));
    }
    Ok(declared.unwrap_or(mean))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ship() -> Ir {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/models/ship.som");
        let c = leeway_structure::compile(
            &std::fs::read_to_string(path).unwrap_or_default(),
            &Default::default(),
        );
        c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics))
    }

    fn parse(text: &str, x0: &[(String, f64)]) -> Result<Input, String> {
        parse_input(
            "in.csv",
            text.as_bytes(),
            &ship(),
            &LoadOptions::default(),
            x0,
        )
        .map_err(|p| format!("{}: {}", p.location.unwrap_or_default(), p.message))
    }

    #[test]
    fn states_come_from_the_first_row_or_x0() {
        let text = "time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n\
                    0,5,3,0.1,0.2,50,160,230,1,1\n\
                    1,,,,,50,160,230,1,1\n";
        let i = parse(text, &[]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            i.experiment.states,
            vec![vec![5.0; 2], vec![3.0; 2], vec![0.1; 2]]
        );
        assert_eq!(i.experiment.heading, vec![0.2; 2]);
        assert_eq!(i.experiment.inputs[1], vec![160.0; 2]);
        assert_eq!(i.experiment.h, 1.0);
        let text = "tau1,tau2,tau3,wind_n,wind_e,v\n50,160,230,1,1,2\n";
        let x0 = vec![
            ("u".to_string(), 4.0),
            ("r".to_string(), 0.0),
            ("psi".to_string(), 1.0),
            ("v".to_string(), 3.5),
        ];
        let i = parse(text, &x0).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(i.experiment.states, vec![vec![4.0], vec![3.5], vec![0.0]]);
        assert_eq!(i.experiment.heading, vec![1.0]);
    }

    #[test]
    fn problems_are_located() {
        let ok = "u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n5,3,0.1,0,50,160,230,1,1\n";
        assert!(parse(ok, &[]).is_ok());
        for (text, expect) in [
            (
                "u,v,r,psi,tau1,tau2,wind_n,wind_e\n5,3,0.1,0,50,160,1,1\n",
                "in.csv:1: missing column `tau3`",
            ),
            (
                "v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n3,0.1,0,50,160,230,1,1\n",
                "in.csv:1: no initial value for `u`: the input has no column `u`",
            ),
            (
                "u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n5,3,0.1,0,50,160,230,1,1\n5,3,0.1,0,50,x,230,1,1\n",
                "in.csv:3:6 (tau2): `x` is not a number",
            ),
            (
                "u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n5,,0.1,0,50,160,230,1,1\n",
                "in.csv:2:2 (v): empty cell",
            ),
            (
                "u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n5,3,0.1,0,50,160,inf,1,1\n",
                "in.csv:2:7 (tau3): `inf` is not a finite number",
            ),
            (
                "experiment,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\na,5,3,0.1,0,50,160,230,1,1\nb,5,3,0.1,0,50,160,230,1,1\n",
                "in.csv:3:1 (experiment): a second experiment `b` starts here (after `a`)",
            ),
            (
                "time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n0,5,3,0.1,0,50,160,230,1,1\n1,5,3,0.1,0,50,160,230,1,1\n3,5,3,0.1,0,50,160,230,1,1\n",
                "in.csv:4:1 (time): inconsistent sample time: step 2 here, 1 at the start",
            ),
            (
                "time,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n0,5,3,0.1,0,50,160,230,1,1\n0.5,5,3,0.1,0,50,160,230,1,1\n",
                "in.csv:2:1 (time): the input is sampled every 0.5 s but the model declares step 1",
            ),
            (
                "u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n",
                "in.csv:2: the file has a header but no samples",
            ),
            (
                "u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\n5,3,0.1,0,50,160,230,1\n",
                "in.csv:2: malformed row: 8 cells, the header has 9",
            ),
            (
                "u,v,r,psi,tau1,tau1,tau2,tau3,wind_n,wind_e\n",
                "in.csv:1:6: column `tau1` appears twice (columns 5 and 6)",
            ),
        ] {
            assert_eq!(parse(text, &[]).err().as_deref(), Some(expect), "{text}");
        }
    }

    #[test]
    fn comment_and_blank_lines_are_skipped_and_rows_keep_their_physical_line() {
        // Issue 10: simulate's loader read every line as a record; it now
        // uses the data files' reader (the same rules as `estimate`).
        let head = "# logged by the bridge\n\ntime,u,v,r,psi,tau1,tau2,tau3,wind_n,wind_e\r\n";
        let ok = format!(
            "{head}0,5,3,0.1,0.2,50,160,230,1,1\r\n# pause\n\n1,,,,,51,160,230,1,1\r\n2,,,,,52,160,230,1,1\n"
        );
        let i = parse(&ok, &[]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(i.experiment.inputs[0], vec![50.0, 51.0, 52.0]);
        assert_eq!(i.experiment.h, 1.0);
        for (text, expect) in [
            (
                format!("{head}0,5,3,0.1,0.2,50,160,230,1,1\n\n# pause\n1,,,,,x,160,230,1,1\n"),
                "in.csv:7:6 (tau1): `x` is not a number",
            ),
            (
                format!(
                    "{head}0,5,3,0.1,0.2,50,160,230,1,1\n\n1,,,,,50,160,230,1,1\n\n3,,,,,50,160,230,1,1\n"
                ),
                "in.csv:8:1 (time): inconsistent sample time: step 2 here, 1 at the start",
            ),
            (
                format!("{head}0,5,3,0.1,0.2,50,160,230,1\n"),
                "in.csv:4: malformed row: 9 cells, the header has 10",
            ),
            (
                "# only a comment\n\n".to_string(),
                "in.csv:3: the file has no header row (it is empty, or only comments and blank lines)",
            ),
            (
                format!("{head}# no rows\n"),
                "in.csv:4: the file has a header but no samples",
            ),
        ] {
            assert_eq!(parse(&text, &[]).err().as_deref(), Some(expect), "{text}");
        }
    }

    #[test]
    fn x0_names_states_or_the_heading() {
        let ir = ship();
        assert_eq!(
            initial_values(&ir, &["u=1, psi=0.5".to_string(), "r=-0.1".to_string()])
                .map_err(|p| p.message),
            Ok(vec![
                ("u".to_string(), 1.0),
                ("psi".to_string(), 0.5),
                ("r".to_string(), -0.1)
            ])
        );
        for bad in ["w=1", "u", "u=x", "u=1,u=2"] {
            assert!(initial_values(&ir, &[bad.to_string()]).is_err(), "{bad}");
        }
    }
}
