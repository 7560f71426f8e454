//! The option enums of an estimate: the method, its instruments, how the
//! first instruments start, how experiments combine.

use leeway_structure::identify::Centring;
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
        Named::name(self)
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

/// One value of a [`Named`] option: its name and what it means, as the
/// CLI's help and Python's errors show them.
#[derive(Clone, Copy, Debug)]
pub struct Choice<T: 'static> {
    /// The name (`iv3`).
    pub name: &'static str,
    /// The value.
    pub value: T,
    /// One line on what it does.
    pub help: &'static str,
}

/// An option whose values have names: the one table the CLI's flags and
/// Python's keywords are both read through.
pub trait Named: Copy + PartialEq + 'static {
    /// The option's name (`method`, `instruments`, …).
    const OPTION: &'static str;
    /// Every value, in the order help lists them.
    const CHOICES: &'static [Choice<Self>];

    /// The value's name.
    fn name(self) -> &'static str {
        Self::CHOICES
            .iter()
            .find(|c| c.value == self)
            .map_or("", |c| c.name)
    }

    /// The value of a name, exactly as written (`iv3`, not `IV3`).
    fn from_name(name: &str) -> Result<Self, UnknownName> {
        Self::CHOICES
            .iter()
            .find(|c| c.name == name)
            .map(|c| c.value)
            .ok_or_else(|| UnknownName {
                option: Self::OPTION,
                given: name.to_string(),
                names: Self::CHOICES.iter().map(|c| c.name).collect(),
            })
    }
}

/// A name that is not one of an option's values.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("`{given}` is not a {option}: use {}", .names.join(", "))]
pub struct UnknownName {
    /// The option (`method`, …).
    pub option: &'static str,
    /// The name given.
    pub given: String,
    /// The names it may have.
    pub names: Vec<&'static str>,
}

pub(crate) const fn choice<T>(name: &'static str, value: T, help: &'static str) -> Choice<T> {
    Choice { name, value, help }
}

impl Named for Method {
    const OPTION: &'static str = "method";
    const CHOICES: &'static [Choice<Method>] = &[
        choice(
            "ls",
            Method::Ls,
            "Least squares (biased under noise and disturbances; a baseline)",
        ),
        choice(
            "iv1",
            Method::Iv1,
            "IV on the basic predictor (consistent only for zero-mean disturbances)",
        ),
        choice(
            "iv2",
            Method::Iv2,
            "IV on the augmented predictor, every medium unmeasured",
        ),
        choice(
            "iv3",
            Method::Iv3,
            "IV on the augmented predictor plus measured media pointwise",
        ),
    ];
}

impl Named for Instruments {
    const OPTION: &'static str = "instruments";
    const CHOICES: &'static [Choice<Instruments>] = &[
        choice(
            "simulated",
            Instruments::Simulated,
            "Noise-free regressors of a simulated nominal model, refined",
        ),
        choice(
            "delayed",
            Instruments::Delayed,
            "Regressors of the measurements one sample earlier",
        ),
    ];
}

impl Named for Initial {
    const OPTION: &'static str = "initial";
    const CHOICES: &'static [Choice<Initial>] = &[
        choice("delayed", Initial::Delayed, "A delayed-instrument estimate"),
        choice("nominal", Initial::Nominal, "The nominal model"),
    ];
}

impl Named for Combine {
    const OPTION: &'static str = "combine";
    const CHOICES: &'static [Choice<Combine>] = &[
        choice(
            "summed",
            Combine::Summed,
            "`(Σ H_i) ϑ = Σ g_i`: one system over all experiments",
        ),
        choice(
            "stacked",
            Combine::Stacked,
            "`[H_1/n_1; …] ϑ = [g_1/n_1; …]` by least squares",
        ),
    ];
}

impl Named for Centring {
    const OPTION: &'static str = "centring";
    const CHOICES: &'static [Choice<Centring>] = &[
        choice(
            "experiment",
            Centring::Experiment,
            "Zero-mean instruments per experiment",
        ),
        choice(
            "pooled",
            Centring::Pooled,
            "Zero mean over all experiments pooled",
        ),
        choice("none", Centring::None, "No centring"),
    ];
}

impl Combine {
    /// `summed`, `stacked`.
    pub fn name(self) -> &'static str {
        Named::name(self)
    }
}

macro_rules! from_str_by_name {
    ($($t:ty),*) => {$(
        impl std::str::FromStr for $t {
            type Err = UnknownName;
            fn from_str(s: &str) -> Result<$t, UnknownName> {
                <$t as Named>::from_name(s)
            }
        }
    )*};
}
from_str_by_name!(Method, Instruments, Initial, Combine);

#[cfg(test)]
mod tests {
    use super::{Combine, Initial, Instruments, Method, Named};

    fn round_trip<T: Named + std::fmt::Debug>() {
        for c in T::CHOICES {
            assert_eq!(c.value.name(), c.name);
            assert_eq!(T::from_name(c.name), Ok(c.value));
        }
        let e = T::from_name("IV3x").err().map(|e| e.to_string());
        assert!(e.is_some_and(|e| e.starts_with("`IV3x` is not a ")));
    }

    #[test]
    fn every_name_reads_back_and_others_are_refused() {
        round_trip::<Method>();
        round_trip::<Instruments>();
        round_trip::<Initial>();
        round_trip::<Combine>();
        assert_eq!("iv3".parse::<Method>(), Ok(Method::Iv3));
        assert!("IV3".parse::<Method>().is_err());
    }
}
