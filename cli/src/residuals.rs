//! `leeway validate --resid`: the residual analysis of each θ's free-run
//! simulation on the validation data (`leeway_model::residuals`, the code
//! `leeway.residuals` runs) — independence of the inputs (the verdict) and
//! whiteness (information), printed as a table after the fits, and as
//! `residuals` in `--json`.

use crate::output::table;
use crate::problem::Problem;
use leeway_model::Experiment;
use leeway_model::Model;
use leeway_model::residuals::{DEFAULT_LAGS, ResidualTests, analyse};
use serde::Serialize;
use std::fmt::Write;

/// The residual options of `leeway validate`.
#[derive(Debug, clap::Args)]
pub struct ResidArgs {
    /// Analyse the simulation errors (MATLAB's `resid` on an output-error
    /// model): each θ's free run from the first measured state; its errors
    /// are tested for independence of the inputs (the verdict) and for
    /// whiteness (information: white for the true model only when the
    /// disturbances do not vary).
    #[arg(long)]
    pub resid: bool,
    /// The largest lag the residual tests use.
    #[arg(long = "resid-lags", value_name = "M", default_value_t = DEFAULT_LAGS, requires = "resid")]
    pub lags: usize,
}

/// One θ's residual tests, as `--json` prints them (docs/json.md).
#[derive(Debug, Serialize)]
pub struct ModelResiduals {
    /// The parameter file's name in tables (its stem).
    pub name: String,
    /// The tests over every experiment.
    pub tests: ResidualTests,
}

/// The residual analysis of every θ on the experiments, unmeasured
/// disturbances held at `disturbances[m]` for `thetas[m]` (as the
/// validation holds them).
pub fn analyse_all(
    model: &dyn Model,
    thetas: &[Vec<f64>],
    names: &[String],
    experiments: &[Experiment],
    disturbances: &[Vec<f64>],
    lags: usize,
) -> Result<Vec<ModelResiduals>, Problem> {
    thetas
        .iter()
        .zip(names)
        .zip(disturbances)
        .map(|((theta, name), disturbances)| {
            let analysis = analyse(model, theta, experiments, disturbances, lags).map_err(|m| {
                Problem::error("invalid-option", format!("--resid-lags {lags}: {m}"))
                    .help("give fewer lags, e.g. --resid-lags 10, or more data")
            })?;
            Ok(ModelResiduals {
                name: name.clone(),
                tests: analysis.tests,
            })
        })
        .collect()
}

fn number(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |v| format!("{v:.digits$}"))
}

fn lags<T: ToString>(outside: &[T]) -> String {
    let mut shown: Vec<String> = outside.iter().take(10).map(T::to_string).collect();
    if outside.len() > 10 {
        shown.push(format!("… ({} lags)", outside.len()));
    }
    if shown.is_empty() {
        "-".into()
    } else {
        shown.join(", ")
    }
}

/// The residual tables of every θ, for the text output.
pub fn render(results: &[ModelResiduals]) -> String {
    let mut s = String::new();
    for m in results {
        let t = &m.tests;
        let _ = writeln!(
            s,
            "\n{}: free-run simulation errors, N = {}, lags 1..{}; 99 % band ±{:.4} per lag for a white error",
            m.name, t.samples, t.lags, t.band
        );
        let _ = writeln!(
            s,
            "verdict: independent of the inputs, at 1 % over all lags (±{:.4}·√P, P for the colour of error and input); whiteness is information (±{:.4})",
            t.input_band, t.white_band
        );
        let mut rows = vec![
            [
                "state",
                "std",
                "max |r|",
                "white",
                "Ljung-Box Q",
                "p",
                "lags outside",
                "independent",
            ]
            .map(String::from)
            .to_vec(),
        ];
        for st in &t.states {
            rows.push(vec![
                st.state.clone(),
                number(st.std, 5),
                number(st.max_abs, 3),
                if st.white { "yes" } else { "no" }.into(),
                number(st.ljung_box, 1),
                number(st.p_value, 3),
                lags(&st.outside),
                if st.independent { "yes" } else { "NO" }.into(),
            ]);
        }
        s.push_str(&table(&rows));
        let mut rows = vec![
            [
                "state",
                "input",
                "max |r|",
                "band",
                "independent",
                "lags outside",
            ]
            .map(String::from)
            .to_vec(),
        ];
        for st in &t.states {
            for i in &st.inputs {
                rows.push(vec![
                    st.state.clone(),
                    i.input.clone(),
                    number(i.max_abs, 3),
                    number(i.band, 3),
                    if i.independent { "yes" } else { "NO" }.into(),
                    lags(&i.outside),
                ]);
            }
        }
        if rows.len() > 1 {
            s.push('\n');
            s.push_str(&table(&rows));
        }
        if !t.diverged.is_empty() {
            let _ = writeln!(
                s,
                "diverged: {} (the simulation left the finite numbers: not independent)",
                t.diverged.join(", ")
            );
        }
    }
    s
}
