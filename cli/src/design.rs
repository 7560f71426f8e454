//! `leeway design MODEL --plan PLAN [--target 5%] [--out DIR] [--verify M]
//! [--seed S] [--method iv3|iv2] [--threads T] [--json]`: plan the trial
//! for a craft (leeway-design) — runs from the exact analysis's sign
//! patterns, their operating points and excitation, the predicted standard
//! errors against run length — and with `--verify` check the design by a
//! seeded Monte Carlo study on the study engine `leeway reproduce` uses.
//! With `--out`, per run an input file `simulate` reads (`run-N.csv`, the
//! nominal trajectory beside the inputs), its margins over time
//! (`run-N-margins.csv`), `design.json` and the figure (`design.svg`,
//! `design.png`). Exit 0 for a design that keeps every held sign (and,
//! verified, whose models pass the verdict), 1 when no plan within the
//! limits can or the verified models fall short (the report says what
//! fails and what would help), 2 on a model, plan, option or file error.

pub mod args;
mod figure;
mod files;
mod text;

use crate::design::args::{DesignArgs, MethodArg};
use crate::files::read_text;
use crate::input::load_compared;
use crate::model::load;
use crate::options::load_options;
use crate::output::{Status, err, out, stderr_style};
use crate::problem::{Failure, Problem};
use leeway_design::compare::compare;
use leeway_design::design::DesignOptions;
use leeway_design::document::json_with;
use leeway_design::error::DesignError;
use leeway_design::plan::{MAX_PLAN_BYTES, locate, parse};
use leeway_design::trial::Run;
use leeway_design::verified::design_verified;
use leeway_estimate::Method;
use leeway_model::Interpreter;
use leeway_model::model::Model;

/// Runs `leeway design`.
pub fn run(args: &DesignArgs) -> Status {
    let style = stderr_style();
    match execute(args) {
        Ok(status) => status,
        Err(f) => {
            // A script reading --json gets a document for every outcome.
            if args.json {
                let doc = serde_json::json!({ "feasible": false, "errors": f.json() });
                out(&serde_json::to_string_pretty(&doc).unwrap_or_default());
            }
            err(&f.render(style, "designed"));
            f.status()
        }
    }
}

fn execute(args: &DesignArgs) -> Result<Status, Failure> {
    let loaded = load(&args.model, false)?;
    let model = Interpreter::new(loaded.ir);
    let plan_name = args.plan.display().to_string();
    let text = read_text(&args.plan, "plan", MAX_PLAN_BYTES)?;
    let json = args
        .plan
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    // A plan error at its value's line and column.
    let located = |e: DesignError| problem(&locate(e, &text, json), &plan_name);
    let plan = parse(&text, json).map_err(located)?;
    let conditions = plan.conditions(model.ir()).map_err(located)?;
    let options = DesignOptions {
        method: match args.method {
            MethodArg::Iv3 => Method::Iv3,
            MethodArg::Iv2 => Method::Iv2,
        },
        target: args.target,
        seed: args.seed,
        pilot: args.pilot,
        runs: None,
    };
    let pool = pool(args.threads)?;
    // Verified models that fall short: the design verifies the other runs
    // it tried in turn, and the first whose models pass is the design.
    let verified = pool
        .install(|| {
            with_progress(args.verify, |progress| {
                design_verified(&model, &conditions, &options, args.verify, progress)
            })
        })
        .map_err(located)?;
    let (design, verification) = (verified.design, verified.verification);
    let comparison = if args.compare.is_empty() {
        None
    } else {
        let runs = given_runs(&model, &args.compare, design.step)?;
        pool.install(|| compare(&model, &design, &runs, args.seed, args.pilot))
    };
    if args.json {
        out(&json_with(
            &design,
            verification.as_ref(),
            comparison.as_ref(),
        ));
    } else {
        out(&text::render(&model, &design, verification.as_ref(), args));
        if let Some(c) = &comparison {
            out(&text::comparison(c, &args.compare));
        }
    }
    if let Some(dir) = &args.out {
        let written = files::write(&model, &design, verification.as_ref(), dir)?;
        if !args.json {
            out(&format!("\nwrote {}\n", written.join(", ")));
        }
    }
    // A design whose verified models fall short is not a success.
    let verified_short = verification.as_ref().is_some_and(|v| !v.verdict.passed);
    Ok(if design.feasible && !verified_short {
        Status::Success
    } else {
        Status::Unsupported
    })
}

/// The given input files as runs: the first row's states (the run's
/// start) and every row's inputs.
fn given_runs(
    model: &Interpreter,
    paths: &[std::path::PathBuf],
    h: f64,
) -> Result<Vec<Run>, Failure> {
    let ir = model.ir();
    let options = load_options(ir, Some(h), None)?;
    paths
        .iter()
        .map(|path| {
            let input = load_compared(path, ir, &options)?;
            let e = input.experiment;
            let n = e.inputs.first().map_or(0, Vec::len);
            Ok(Run {
                x0: e
                    .states
                    .iter()
                    .map(|s| s.first().copied().unwrap_or(0.0))
                    .collect(),
                inputs: (0..n)
                    .map(|k| e.inputs.iter().map(|i| i[k]).collect())
                    .collect(),
            })
        })
        .collect()
}

/// Runs `f` with a progress bar on a terminal counting the verification's
/// trials (`runs` per runs option verified: the bar grows when the design
/// verifies another).
fn with_progress<T>(runs: Option<usize>, f: impl FnOnce(&(dyn Fn() + Sync)) -> T) -> T {
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    use std::io::IsTerminal;
    let Some(runs) = runs.filter(|_| std::io::stderr().is_terminal()) else {
        return f(&|| ());
    };
    let bar = ProgressBar::with_draw_target(Some(runs as u64), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template(
        "{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} trials (eta {eta})",
    ) {
        bar.set_style(style);
    }
    bar.set_message("leeway design --verify");
    let out = f(&|| {
        if bar.position() >= bar.length().unwrap_or(0) {
            bar.inc_length(runs as u64);
        }
        bar.inc(1);
    });
    bar.finish_and_clear();
    out
}

fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool, Failure> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        builder = builder.num_threads(t);
    }
    builder.build().map_err(|e| {
        Problem::error(
            "invalid-option",
            format!("cannot start the worker threads: {e}"),
        )
        .into()
    })
}

/// A design error as a located problem: the plan file's line and column
/// when the file is at fault.
fn problem(e: &DesignError, plan: &str) -> Failure {
    let at = match (e.code, e.line, e.column) {
        ("plan", Some(l), Some(c)) => Some(format!("{plan}:{l}:{c}")),
        ("plan", _, _) => Some(plan.to_string()),
        _ => None,
    };
    let mut p = Problem::error(e.code, e.message.clone()).help(e.hint.clone());
    if let Some(at) = at {
        p = p.at(at);
    }
    // A plan the design cannot read or an option out of bounds is an input
    // error (2); a model or conditions no plan can serve is a valid input
    // without a result (1).
    if e.code != "plan" && e.code != "invalid-option" {
        p.status = Status::Unsupported;
    }
    p.into()
}
