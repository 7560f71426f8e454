//! The input file of `leeway simulate`: a CSV file with a header row, one
//! experiment, validated like estimation data and located the same way
//! (`file:row:column (name)`).
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
use leeway_runtime::Experiment;
use leeway_runtime::data::{LoadOptions, column_name};
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

/// Loads the input file.
pub fn load_input(
    path: &Path,
    ir: &Ir,
    options: &LoadOptions,
    x0: &[(String, f64)],
) -> Result<Input, Failure> {
    let file = path.display().to_string();
    let text = std::fs::read(path).map_err(|e| {
        Problem::error("data", format!("cannot read the file: {e}"))
            .at(&file)
            .help("check the path passed to --input")
    })?;
    parse_input(&file, &text, ir, options, x0).map_err(Failure::from)
}

fn cell(file: &str, line: usize, i: usize, name: &str, raw: &str) -> Result<f64, Problem> {
    let at = format!("{file}:{line}:{} ({name})", i + 1);
    match raw.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(
            Problem::error("data", format!("`{raw}` is not a finite number"))
                .at(at)
                .help("NaN and infinite values are not accepted; leeway does not interpolate"),
        ),
        Err(_) if raw.is_empty() => Err(Problem::error("data", "empty cell")
            .at(at)
            .help("every sample needs every input; leeway does not fill gaps")),
        Err(_) => Err(Problem::error("data", format!("`{raw}` is not a number"))
            .at(at)
            .help("use a plain decimal such as 0.25 or -1.5e-3")),
    }
}

/// Parses the input file's bytes (see [`load_input`]).
pub fn parse_input(
    file: &str,
    text: &[u8],
    ir: &Ir,
    options: &LoadOptions,
    x0: &[(String, f64)],
) -> Result<Input, Problem> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(text);
    let headers: Vec<String> = reader
        .headers()
        .map_err(|e| {
            Problem::error("data", format!("cannot read the header row: {e}"))
                .at(format!("{file}:1"))
                .help("the first row names the columns")
        })?
        .iter()
        .map(str::to_string)
        .collect();
    for (i, h) in headers.iter().enumerate() {
        if let Some(j) = headers[..i].iter().position(|g| g == h) {
            return Err(Problem::error(
                "data",
                format!(
                    "column `{h}` appears twice (columns {} and {})",
                    j + 1,
                    i + 1
                ),
            )
            .at(format!("{file}:1:{}", i + 1))
            .help("rename one of them; leeway will not guess which is meant"));
        }
    }
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
                    .at(format!("{file}:1"))
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
            .at(format!("{file}:1"))
            .help(format!(
                "add a `{}` column (only its first row is read) or pass --x0 {name}=VALUE",
                column_name(ir, name)
            )));
        }
    }
    let time_col = find(&column_name(ir, "time"));
    let exp_col = find(&column_name(ir, "experiment"));
    let n_comp = ir.components.len();
    let mut inputs = vec![Vec::new(); ir.inputs.len()];
    let mut rotation = vec![Vec::new(); ir.rotation_vars.len()];
    let mut dist = vec![Vec::new(); n_comp];
    let mut times = Vec::new();
    let mut experiment: Option<String> = None;
    let mut rows = 0usize;
    for (ri, record) in reader.records().enumerate() {
        let line = ri + 2;
        let record = record.map_err(|e| {
            let at = e.position().map_or(line as u64, |p| p.line());
            let message = match e.kind() {
                csv::ErrorKind::UnequalLengths {
                    expected_len, len, ..
                } => format!("malformed row: {len} cells, the header has {expected_len}"),
                csv::ErrorKind::Utf8 { .. } => {
                    "malformed row: a cell is not UTF-8 text".to_string()
                }
                _ => format!("malformed row: {e}"),
            };
            Problem::error("data", message)
                .at(format!("{file}:{at}"))
                .help("every row needs as many cells as the header")
        })?;
        let raw = |i: usize| record.get(i).unwrap_or("");
        for (role, i, name) in &required {
            // Declared units are converted to base units, as for data files.
            let signal = match role {
                Role::Input(s) => ir.inputs.get(*s),
                Role::Rotation(s) => ir.rotation_vars.get(*s),
                Role::Disturbance(s) => ir.components.get(*s).map(|c| &c.name),
            };
            let v = cell(file, line, *i, name, raw(*i))? * signal.map_or(1.0, |s| unit(ir, s));
            match role {
                Role::Input(s) => inputs[*s].push(v),
                Role::Rotation(s) => rotation[*s].push(v),
                Role::Disturbance(s) => dist[*s].push(v),
            }
        }
        if rows == 0 {
            for (name, value, col) in &mut initial {
                if let Some(i) = *col {
                    *value =
                        Some(cell(file, line, i, &column_name(ir, name), raw(i))? * unit(ir, name));
                }
            }
        }
        if let Some(i) = time_col {
            times.push(cell(file, line, i, &column_name(ir, "time"), raw(i))? * unit(ir, "time"));
        }
        if let Some(i) = exp_col {
            let name = raw(i).to_string();
            match &experiment {
                None => experiment = Some(name),
                Some(first) if *first != name => {
                    return Err(Problem::error(
                        "data",
                        format!("a second experiment `{name}` starts here (after `{first}`)"),
                    )
                    .at(format!("{file}:{line}:{} (experiment)", i + 1))
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
                .at(format!("{file}:2"))
                .help("one row per sample of the input"),
        );
    }
    let time_at = time_col.map(|i| format!("{}:{} (time)", "{line}", i + 1));
    let h = sample_time(file, ir, &times, time_at.as_deref(), options)?;
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
        t0: times.first().copied().unwrap_or(0.0),
    })
}

/// The factor from a signal's declared unit to its base unit (1 without one).
fn unit(ir: &Ir, signal: &str) -> f64 {
    ir.data_units
        .get(signal)
        .map_or(1.0, |u| leeway_structure::units::factor(u))
}

/// The sample time: from the time column (uniform, checked against the
/// model's `step`), else the model's `step`, else `--step`.
/// `column` is `{line}:C (time)`, a template for a row's time cell.
fn sample_time(
    file: &str,
    ir: &Ir,
    times: &[f64],
    column: Option<&str>,
    options: &LoadOptions,
) -> Result<f64, Problem> {
    let at = |line: usize| {
        let cell = column
            .unwrap_or("{line}")
            .replace("{line}", &line.to_string());
        format!("{file}:{cell}")
    };
    let declared = ir.step.or(options.step);
    if times.len() < 2 {
        return declared.ok_or_else(|| {
            Problem::error(
                "data",
                "no sample time: the model declares no `step` and the input has no `time` column (or one row)",
            )
            .at(file)
            .help("declare `step h` in the model, add a `time` column, or pass --step H")
        });
    }
    let h = times[1] - times[0];
    for (k, w) in times.windows(2).enumerate() {
        let dt = w[1] - w[0];
        if dt <= 0.0 || (dt - h).abs() > 1e-3 * h.abs() {
            return Err(Problem::error(
                "data",
                format!("inconsistent sample time: step {dt} here, {h} at the start"),
            )
            .at(at(k + 3))
            .help("leeway needs uniformly sampled data; resample the input"));
        }
    }
    let mean = (times[times.len() - 1] - times[0]) / (times.len() - 1) as f64;
    if let Some(d) = declared
        && (mean - d).abs() > 1e-3 * d
    {
        return Err(Problem::error(
            "data",
            format!("the input is sampled every {mean} s but the model declares step {d}"),
        )
        .at(at(2))
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
