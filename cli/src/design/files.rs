//! What `design --out DIR` writes: per run the input file `simulate` reads
//! (`run-N.csv`: the nominal trajectory beside the inputs, in the model's
//! data columns), its margins over time (`run-N-margins.csv`),
//! `design.json` (the document `--json` prints) and the figure; each
//! created anew, a symbolic link in the way refused (`files::create_output`).

use crate::files::write_output;
use crate::output::io_reason;
use crate::problem::Problem;
use leeway_data::write_csv;
use leeway_design::report::Design;
use leeway_design::trial::margins;
use leeway_design::verify::Verification;
use leeway_model::Interpreter;
use leeway_model::model::Model;
use std::path::Path;

/// Writes every file into `dir` (created if missing); the names written.
pub fn write(
    model: &Interpreter,
    design: &Design,
    verification: Option<&Verification>,
    dir: &Path,
) -> Result<Vec<String>, Problem> {
    let io = |what: &Path, e: &dyn std::fmt::Display| {
        Problem::error("io", format!("cannot write `{}`: {e}", what.display()))
            .at(what.display().to_string())
            .help("choose another directory with --out DIR")
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, &e))?;
    let ir = model.ir();
    let mut written = Vec::new();
    for (e, record) in design.records.iter().enumerate() {
        let path = dir.join(format!("run-{}.csv", e + 1));
        let mut text = Vec::new();
        write_csv(ir, &[record], 0.0, &mut text).map_err(|err| io(&path, &err))?;
        write_output(&path, &text).map_err(|err| io(&path, &io_reason(&err)))?;
        written.push(path.display().to_string());
        let path = dir.join(format!("run-{}-margins.csv", e + 1));
        write_output(&path, margins_csv(model, design, e).as_bytes())
            .map_err(|err| io(&path, &io_reason(&err)))?;
        written.push(path.display().to_string());
    }
    let path = dir.join("design.json");
    let json = leeway_design::document::json(design, verification) + "\n";
    write_output(&path, json.as_bytes()).map_err(|e| io(&path, &io_reason(&e)))?;
    written.push(path.display().to_string());
    for name in ["design.svg", "design.png"] {
        let path = dir.join(name);
        crate::design::figure::save(&path, model, design).map_err(|e| io(&path, &e))?;
        written.push(path.display().to_string());
    }
    Ok(written)
}

/// `time`, then per held argument its value on its side (`sign·argument`)
/// and the band it must clear, along the nominal run from heading 0.
fn margins_csv(model: &Interpreter, design: &Design, e: usize) -> String {
    let held = &design.held[e];
    let truth = &design.nominal[e];
    let run = &design.runs[e];
    let values = margins(model, truth, &run.inputs, held);
    let mut s = String::from("time");
    for h in held {
        s.push_str(&format!(",{},{}_band", h.name, h.name));
    }
    s.push('\n');
    let n = run.inputs.len();
    for k in 0..n {
        s.push_str(&format!("{}", k as f64 * design.step));
        for (h, v) in held.iter().zip(&values) {
            s.push_str(&format!(",{},{}", v[k] + h.band, h.band));
        }
        s.push('\n');
    }
    s
}
