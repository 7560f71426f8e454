//! The arguments of `leeway design` and their bounds.

use std::path::PathBuf;

/// The estimator a design is made for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// IV on the augmented predictor with measured media pointwise (default).
    Iv3,
    /// IV on the augmented predictor, every medium unmeasured.
    Iv2,
}

/// Arguments of `leeway design`.
#[derive(Debug, clap::Args)]
pub struct DesignArgs {
    /// The `.som` model file.
    #[arg(value_name = "MODEL.som")]
    pub model: PathBuf,
    /// The plan (TOML, or JSON for a `.json` name): what is known before the
    /// trial — actuator limits, sample time, disturbances, noise, budget (docs/design.md).
    #[arg(long, value_name = "PLAN.toml")]
    pub plan: PathBuf,
    /// Relative standard error wanted for every θ, e.g. `5%` or `0.05`:
    /// the report gives the run length that reaches it.
    #[arg(long, value_name = "PRECISION", value_parser = precision)]
    pub target: Option<f64>,
    /// Write the runs' input files, their margins, design.json and the figure here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// An input of your own (the CSV `simulate` reads, one per experiment):
    /// its held signs and standard errors per sample beside the design's.
    #[arg(long, value_name = "IN.csv")]
    pub compare: Vec<PathBuf>,
    /// Verify the design by M Monte Carlo trials (every method), seeded.
    #[arg(long, value_name = "M", value_parser = runs)]
    pub verify: Option<usize>,
    /// Pilot trials that calibrate the predicted standard errors (0: the
    /// estimator's asymptotic ones alone).
    #[arg(long, value_name = "K", default_value_t = 100, value_parser = pilot)]
    pub pilot: usize,
    /// Seed of the excitation, the prediction and the verification.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// The estimator to design for.
    #[arg(long, value_enum, default_value_t = MethodArg::Iv3)]
    pub method: MethodArg,
    /// Worker threads of the verification (default: one per core). The results do not depend on it.
    #[arg(long, value_name = "T", value_parser = threads)]
    pub threads: Option<usize>,
    /// Print the design as JSON (docs/json.md) instead of text.
    #[arg(long)]
    pub json: bool,
}

/// At most `leeway_design::bounds::TRIALS` (Python's `leeway.design` meets
/// the same bound).
fn runs(s: &str) -> Result<usize, String> {
    let m: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a number of runs"))?;
    leeway_design::bounds::trials(m)
}

fn pilot(s: &str) -> Result<usize, String> {
    let k: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a number of trials"))?;
    leeway_design::bounds::pilot(k)
}

fn threads(s: &str) -> Result<usize, String> {
    let t: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a number of threads"))?;
    if (1..=1024).contains(&t) {
        Ok(t)
    } else {
        Err(format!("{t} threads: give 1 to 1024"))
    }
}

/// `5%` → 0.05, `0.05` → 0.05; strictly between 0 and 1.
pub fn precision(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let value = match t.strip_suffix('%') {
        Some(p) => p.trim().parse::<f64>().map(|v| v / 100.0),
        None => t.parse::<f64>(),
    }
    .map_err(|_| format!("`{s}` is not a precision: give e.g. 5% or 0.05"))?;
    if value.is_finite() && value > 0.0 && value < 1.0 {
        Ok(value)
    } else {
        Err(format!(
            "`{s}`: a relative precision is between 0 and 100 %"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precisions_read_as_fractions() {
        assert_eq!(precision("5%"), Ok(0.05));
        assert_eq!(precision("0.05"), Ok(0.05));
        assert!(precision("0").is_err());
        assert!(precision("120%").is_err());
        assert!(precision("five").is_err());
    }
}
