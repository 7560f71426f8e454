//! Experiments back to CSV: the inverse of [`crate::csv::parse_csv`].
//!
//! The file has a header row naming the model's data columns (after the
//! model's `data { }` mapping): `time`, `experiment` when there is more than
//! one experiment, the states, the heading (or the measured rotation
//! columns), the inputs and the measured disturbance components. Numbers are
//! written in Rust's shortest round-trip form, so reading the file back gives
//! the same values bit for bit. [`columns`] gives what a row holds, for the
//! CLI's file and Python's DataFrame alike.

use leeway_model::experiment::{Experiment, column_name};
use leeway_structure::ir::{Ir, Rotation};
use std::io::Write;

/// The header [`write_csv`] writes for `experiments` experiments.
pub fn header(ir: &Ir, experiments: usize) -> Vec<String> {
    let mut h = vec![column_name(ir, "time")];
    if experiments > 1 {
        h.push(column_name(ir, "experiment"));
    }
    h.extend(ir.states.iter().map(|s| column_name(ir, s)));
    match &ir.rotation {
        Rotation::Planar { heading, .. } => h.push(column_name(ir, heading)),
        Rotation::Measured { .. } => h.extend(ir.rotation_vars.iter().map(|s| column_name(ir, s))),
        Rotation::None => {}
    }
    h.extend(ir.inputs.iter().map(|s| column_name(ir, s)));
    for c in &ir.components {
        if ir.disturbances[c.disturbance].measured {
            h.push(column_name(ir, &c.name));
        }
    }
    h
}

/// The columns [`write_csv`] writes for one experiment, aligned with
/// [`header`]`(ir, 1)`: the time stamps `t0 + k·h`, then every value back in
/// the unit the model declares for it (`data { r in deg/s }`), so that the
/// file reads back as the data it stands for. A value missing from a column
/// shorter than the states is `NaN`.
pub fn columns(ir: &Ir, e: &Experiment, t0: f64) -> Vec<Vec<f64>> {
    let unit = |signal: &str| {
        ir.data_units
            .get(signal)
            .map_or(1.0, |u| leeway_structure::units::factor(u))
    };
    let n = e.states.first().map_or(0, Vec::len);
    let scaled = |c: Option<&Vec<f64>>, f: f64| -> Vec<f64> {
        (0..n)
            .map(|k| c.and_then(|c| c.get(k)).copied().unwrap_or(f64::NAN) / f)
            .collect()
    };
    let time = unit("time");
    let mut out = vec![(0..n).map(|k| (t0 + k as f64 * e.h) / time).collect()];
    for (c, s) in e.states.iter().zip(&ir.states) {
        out.push(scaled(Some(c), unit(s)));
    }
    match &ir.rotation {
        Rotation::Planar { heading, .. } => out.push(scaled(Some(&e.heading), unit(heading))),
        Rotation::Measured { .. } => {
            for c in &e.rotation {
                out.push(scaled(Some(c), 1.0));
            }
        }
        Rotation::None => {}
    }
    for (c, s) in e.inputs.iter().zip(&ir.inputs) {
        out.push(scaled(Some(c), unit(s)));
    }
    for (i, c) in ir.components.iter().enumerate() {
        if ir.disturbances[c.disturbance].measured {
            out.push(scaled(e.disturbances.get(i), unit(&c.name)));
        }
    }
    out
}

/// Writes experiments shaped for `ir` as one CSV file: per experiment the
/// [`columns`] (sample `k` stamped `t0 + k·h`), with the experiment's name
/// after the time when there are several. Values are written as held (a
/// non-finite value is written as `NaN`/`inf` and would be rejected when
/// read back).
pub fn write_csv(
    ir: &Ir,
    experiments: &[&Experiment],
    t0: f64,
    out: &mut dyn Write,
) -> std::io::Result<()> {
    let header = header(ir, experiments.len());
    writeln!(out, "{}", header.join(","))?;
    let mut line = String::new();
    for e in experiments {
        let columns = columns(ir, e, t0);
        let n = columns.first().map_or(0, Vec::len);
        for k in 0..n {
            line.clear();
            for (j, c) in columns.iter().enumerate() {
                if j > 0 {
                    line.push(',');
                }
                push(&mut line, c[k]);
                if j == 0 && experiments.len() > 1 {
                    line.push(',');
                    line.push_str(&e.name);
                }
            }
            writeln!(out, "{line}")?;
        }
    }
    out.flush()
}

/// Shortest round-trip form (`{:?}` switches to exponents for tiny and huge values).
fn push(line: &mut String, v: f64) {
    use std::fmt::Write as _;
    let _ = write!(line, "{v:?}");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csv::parse_csv;
    use crate::options::LoadOptions;

    fn ir(src: &str) -> Ir {
        let c = leeway_structure::compile(src, &Default::default());
        c.ir.unwrap_or_else(|| panic!("{:?}", c.diagnostics))
    }

    #[test]
    fn several_experiments_get_an_experiment_column_and_mapped_names() {
        let path = format!(
            "{}/../examples/models/hovercraft.som",
            env!("CARGO_MANIFEST_DIR")
        );
        let ir = ir(&std::fs::read_to_string(path).unwrap_or_default());
        let mut a = Experiment::new(&ir, "a", 0.2);
        let mut b = Experiment::new(&ir, "b", 0.2);
        for k in 0..12 {
            let x = k as f64;
            let row = leeway_model::experiment::Row {
                states: &[x, 0.5 * x, 1e-9 * x],
                inputs: &[100.0 + x, -x],
                heading: 0.0,
                rotation: &[],
                disturbances: &[0.1 * x, -0.2 * x],
            };
            a.push(&ir, &row);
            b.push(&ir, &row);
        }
        let mut buf = Vec::new();
        write_csv(&ir, &[&a, &b], 10.0, &mut buf).unwrap_or_else(|err| panic!("{err}"));
        let text = String::from_utf8_lossy(&buf).into_owned();
        assert!(
            text.starts_with("t,run,u,v,r,thrust,rudder_moment,anemo_u,anemo_v\n10.0,a,"),
            "{text}"
        );
        let back = parse_csv("two.csv", &buf, &ir, &LoadOptions::default())
            .unwrap_or_else(|err| panic!("{err}"));
        assert_eq!(back, vec![a, b]);
    }

    #[test]
    fn declared_units_are_written_back_in_those_units() {
        let ir = ir(
            "model M { state u, r input delta der u = X*u + T*delta der r = N*r
            data { delta = \"rudder_deg\" in deg, u in knots, time in ms } }",
        );
        let mut e = Experiment::new(&ir, "m", 0.5);
        for k in 0..12 {
            e.states[0].push(1.0);
            e.states[1].push(0.0);
            e.inputs[0].push(0.1 * f64::from(k));
        }
        let mut buf = Vec::new();
        write_csv(&ir, &[&e], 0.0, &mut buf).unwrap_or_else(|e| panic!("{e}"));
        let text = String::from_utf8(buf).unwrap_or_default();
        assert!(text.starts_with("time,u,r,rudder_deg\n0.0,"), "{text}");
        // 0.5 s as 500 ms, 1 m/s in knots, 0.1 rad in degrees.
        let second: Vec<f64> = text
            .lines()
            .nth(2)
            .unwrap_or_default()
            .split(',')
            .map(|c| c.parse().unwrap_or(f64::NAN))
            .collect();
        assert_eq!(second[0], 500.0);
        assert!((second[1] - 3600.0 / 1852.0).abs() < 1e-12);
        assert!((second[3] - 0.1f64.to_degrees()).abs() < 1e-12);
        let back = parse_csv("m.csv", text.as_bytes(), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back[0].h, 0.5);
        for (a, b) in back[0].inputs[0].iter().zip(&e.inputs[0]) {
            assert!((a - b).abs() < 1e-15, "{a} vs {b}");
        }
    }
}
