//! The input file of `leeway simulate`: a CSV file with a header row, or a
//! Parquet file, one experiment, read by `leeway_data::input` (the reader
//! `leeway.simulate` shares in Python) through the data files' readers
//! (`leeway_data::with_table`: for CSV comment and blank lines
//! skipped, CRLF, quoted cells) and located the same way (`file:row:column
//! (name)`, the physical line; row, row group and column for Parquet). What
//! is left here is the command line's own: `--x0`.
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
use leeway_data::LoadOptions;
use leeway_data::input::OptionNames;
use leeway_data::input::read_input;
use leeway_data::with_table;
use leeway_model::given::MAX_GIVEN_VALUE;
use leeway_structure::ir::{Ir, Rotation};
use std::path::Path;

pub use leeway_data::input::Input;

/// The options of `leeway simulate` as hints name them.
const NAMES: OptionNames = OptionNames {
    x0: |name| format!("--x0 {name}=VALUE"),
    step: "--step H",
};

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
                Ok(v) if v.is_finite() && v.abs() <= MAX_GIVEN_VALUE => v,
                Ok(v) if v.is_finite() => {
                    return Err(Problem::error(
                        "invalid-option",
                        format!(
                            "--x0 `{item}`: `{}` exceeds {:e} in magnitude",
                            value.trim(),
                            MAX_GIVEN_VALUE
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
        read_input(table, ir, options, x0, &NAMES)
    })
    .map_err(|e| Problem::data(&e).into())
}

/// `design --compare`'s names for the same reader: a run starts at its
/// first row (there is no `--x0`), at the design's sample time.
const COMPARE_NAMES: OptionNames = OptionNames {
    x0: |_| "nothing else: `design --compare` has no --x0".to_string(),
    step: "a `step` in the plan",
};

/// Loads an input file given to `design --compare` (as [`load_input`];
/// errors name `--compare`).
pub fn load_compared(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<Input, Failure> {
    with_table(path, "--compare", |table| {
        read_input(table, ir, options, &[], &COMPARE_NAMES)
    })
    .map_err(|e| Problem::data(&e).into())
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
        leeway_data::Records::new(file, text, "--input").map_err(|e| Problem::data(&e))?;
    read_input(&mut records, ir, options, x0, &NAMES).map_err(|e| Problem::data(&e))
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
                "in.csv:4:1 (time): inconsistent sample time: step 2 s here, 1 s at the start",
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
        // Regression: simulate's loader read every line as a record; it now
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
                "in.csv:8:1 (time): inconsistent sample time: step 2 s here, 1 s at the start",
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
