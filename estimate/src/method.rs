//! The option enums of an estimate: the method, its instruments, how the
//! first instruments start, how experiments combine.

use leeway_structure::ir::PredictorKind;
use serde::{Deserialize, Serialize};

/// Which estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Least squares on IV3's predictor, with an intercept per output and experiment.
    Ls,
    /// IV on the basic predictor `Φ(y, u)`.
    Iv1,
    /// IV on the augmented predictor, every medium unmeasured.
    Iv2,
    /// IV on the augmented predictor plus `Φ2(y + y_aux)` for measured media.
    Iv3,
}

impl Method {
    /// The predictor the method uses.
    pub fn predictor(self) -> PredictorKind {
        match self {
            Method::Iv1 => PredictorKind::Basic,
            Method::Iv2 => PredictorKind::Augmented,
            Method::Ls | Method::Iv3 => PredictorKind::Measured,
        }
    }
    /// `ls`, `iv1`, ...
    pub fn name(self) -> &'static str {
        match self {
            Method::Ls => "ls",
            Method::Iv1 => "iv1",
            Method::Iv2 => "iv2",
            Method::Iv3 => "iv3",
        }
    }
    /// All four, in the paper's order.
    pub const ALL: [Method; 4] = [Method::Ls, Method::Iv1, Method::Iv2, Method::Iv3];
}

/// Where instruments come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Instruments {
    /// Simulated nominal model, refined (default).
    Simulated,
    /// Regressors of the measurement one sample earlier.
    Delayed,
}

/// Where the refined IV's first instrument simulation gets its θ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Initial {
    /// The nominal model (`nominal { }` or `--nominal`).
    Nominal,
    /// An estimate with delayed-measurement instruments (measured disturbances
    /// at their experiment mean): consistent, and close enough to the craft
    /// that the first simulation gives strong instruments.
    Delayed,
}

/// How the experiments' moment equations are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    /// `(Σᵢ Hᵢ) ϑ = Σᵢ gᵢ`: the pooled IV estimator (default). With model
    /// error every run's equations have their own solution; summing weighs
    /// runs by their length and keeps one consistent system.
    Summed,
    /// `[H₁/n₁; …; H_E/n_E] ϑ = [g₁/n₁; …]` solved by least squares: the
    /// paper's eq. (IV_problem) as written.
    Stacked,
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Method, String> {
        match s.to_ascii_lowercase().as_str() {
            "ls" => Ok(Method::Ls),
            "iv1" => Ok(Method::Iv1),
            "iv2" => Ok(Method::Iv2),
            "iv3" => Ok(Method::Iv3),
            other => Err(format!("unknown method `{other}`: use ls, iv1, iv2 or iv3")),
        }
    }
}

impl Combine {
    /// `summed`, `stacked`.
    pub fn name(self) -> &'static str {
        match self {
            Combine::Summed => "summed",
            Combine::Stacked => "stacked",
        }
    }
}
