//! Turning the solution into the returned `Estimate`: column statuses, standard errors, warnings, diagnostics.

use crate::estimator::Estimator;
use crate::method::{Initial, Instruments, Method};
use crate::outcome::{ColumnEstimate, Diagnostics, DroppedAtStart, Estimate, EstimateError};
use crate::solve::{BlockSolution, CONDITION_WARNING};
use leeway_model::signs::ExperimentSigns;
use leeway_model::warning::{Warning, names_capped};
use leeway_structure::identify::Centring;
use leeway_structure::ir::{ColumnKind, PredictorKind, Rotation};
use std::collections::BTreeMap;

/// The equations every method leaves out at an experiment's start: the
/// first (regressors at sample 0), so that no instrument — the delayed
/// measurement of IV's bootstrap included — uses a same-sample measurement.
const METHOD_DROPS: usize = 1;

impl Estimator<'_> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn finish(
        &mut self,
        sign_patterns: Vec<ExperimentSigns>,
        sol: &[BlockSolution],
        values: BTreeMap<usize, f64>,
        theta: Vec<f64>,
        cov: Option<BTreeMap<(usize, usize), f64>>,
        refinements: usize,
        converged: bool,
    ) -> Result<Estimate, EstimateError> {
        let cols = self.ir.predictors.get(self.kind);
        let estimated: Vec<usize> = sol.iter().flat_map(|s| s.kept.iter().copied()).collect();
        let numeric_held: BTreeMap<usize, f64> =
            sol.iter().flat_map(|s| s.held.iter().copied()).collect();
        let columns = self.column_estimates(&estimated, &values, &numeric_held, cov.as_ref());
        let (std_errors, covariance) = self.theta_covariance(&estimated, cov.as_ref());
        let disturbances = if self.kind == PredictorKind::Basic {
            Vec::new()
        } else {
            self.disturbance_means(&values, &theta, cov.as_ref())
        };
        let condition = sol.iter().map(|s| s.condition).fold(0.0, f64::max);
        self.warn_ill_conditioned(sol);
        let structural_kept: usize = self.blocks.iter().map(|b| b.cols.len()).sum();
        let (centring, instruments) = (self.centring_text(), self.instruments_text());
        let equations = self.facts.iter().map(|f| f.len.saturating_sub(2)).sum();
        Ok(Estimate {
            moment_system: None,
            method: self.options.method,
            parameters: self.ir.parameters.iter().map(|p| p.name.clone()).collect(),
            theta,
            std_errors,
            covariance,
            columns,
            disturbances,
            sign_patterns,
            diagnostics: Diagnostics {
                predictor: format!("{:?}", self.kind).to_lowercase(),
                experiments: self.facts.len(),
                equations,
                columns: cols.len(),
                estimated: estimated.len(),
                rank: estimated.len().min(structural_kept),
                condition_number: condition,
                refinements,
                converged,
                instruments,
                centring,
                combine: if self.options.method == Method::Ls {
                    "summed (least squares: the normal equations of all experiments)".to_string()
                } else {
                    self.combine().name().to_string()
                },
                lags: self.options.lags,
                unexcited: self.unexcited.clone(),
                aggregates: self.aggregates.clone(),
                own_simulation: None,
                dropped_at_start: self.dropped_at_start(),
                subsample: None,
            },
            warnings: self.warnings.iter().map(|w| w.detail.clone()).collect(),
            warning_summaries: self.warnings.clone(),
            notes: Vec::new(),
            instrument_simulation: None,
        })
    }

    /// Each column's estimate and status: `estimated`, or held (by the
    /// structure, or `numeric_held`), or dropped.
    fn column_estimates(
        &self,
        estimated: &[usize],
        values: &BTreeMap<usize, f64>,
        numeric_held: &BTreeMap<usize, f64>,
        cov: Option<&Covariance>,
    ) -> Vec<ColumnEstimate> {
        let cols = self.ir.predictors.get(self.kind);
        let structural_held: BTreeMap<usize, f64> = self.held.iter().copied().collect();
        cols.iter()
            .enumerate()
            .map(|(c, col)| {
                let kind = match col.kind {
                    ColumnKind::Theta { .. } => "theta",
                    ColumnKind::Rho { .. } => "rho",
                    ColumnKind::Lambda { .. } => "lambda",
                };
                let (value, status) = if estimated.contains(&c) {
                    (values.get(&c).copied(), "estimated".to_string())
                } else if let Some(v) = structural_held.get(&c) {
                    (
                        Some(*v),
                        "held at nominal (not identifiable; aggregated)".to_string(),
                    )
                } else if let Some(v) = numeric_held.get(&c) {
                    (
                        Some(*v),
                        if col.kind.is_nuisance() {
                            "held at 0 (not excited)".to_string()
                        } else {
                            "held at nominal (not excited)".to_string()
                        },
                    )
                } else {
                    (
                        None,
                        "dropped (structurally dependent: absorbed by kept columns)".to_string(),
                    )
                };
                let mut estimates = self.column_texts[c].clone();
                let mut status = status;
                if kind == "theta" && status == "estimated" {
                    // A parameter that estimates a sum says so in its
                    // status, in every output (text, JSON, Python).
                    if let Some(sum) = self.numeric_aggregate(&col.name) {
                        estimates = sum;
                    }
                    if estimates != col.name {
                        status = "aggregate".to_string();
                    }
                }
                ColumnEstimate {
                    name: col.name.clone(),
                    kind,
                    value,
                    std_error: if estimated.contains(&c) {
                        std_error(cov, c)
                    } else {
                        None
                    },
                    status,
                    estimates,
                }
            })
            .collect()
    }

    /// The sum a parameter estimates when a measured-medium parameter was
    /// held beside it (`N_r estimates N_r - 47*(W_uv + 0.001)`).
    fn numeric_aggregate(&self, name: &str) -> Option<String> {
        let prefix = format!("{name} estimates ");
        self.aggregates.iter().find_map(|a| {
            let rest = a.strip_prefix(&prefix)?;
            Some(rest.split(" (").next().unwrap_or(rest).to_string())
        })
    }

    /// Each parameter's standard error and their covariance, where estimated.
    #[allow(clippy::type_complexity)]
    fn theta_covariance(
        &self,
        estimated: &[usize],
        cov: Option<&Covariance>,
    ) -> (Vec<Option<f64>>, Vec<Vec<Option<f64>>>) {
        let cols = self.ir.predictors.get(self.kind);
        let theta_cols: Vec<Option<usize>> = (0..self.ir.parameters.len())
            .map(|p| {
                cols.iter()
                    .position(|c| c.kind == ColumnKind::Theta { parameter: p })
            })
            .collect();
        let std_errors = theta_cols
            .iter()
            .map(|c| {
                c.filter(|c| estimated.contains(c))
                    .and_then(|c| std_error(cov, c))
            })
            .collect();
        let covariance = theta_cols
            .iter()
            .map(|a| {
                theta_cols
                    .iter()
                    .map(|b| {
                        let (a, b) = ((*a)?, (*b)?);
                        if !(estimated.contains(&a) && estimated.contains(&b)) {
                            return None;
                        }
                        let m = cov?;
                        let (ab, ba) = (*m.get(&(a, b))?, *m.get(&(b, a))?);
                        // `B G Bᵀ` is symmetric up to round-off; the mean
                        // makes it exactly so and keeps the diagonal.
                        Some(if a == b { ab } else { 0.5 * (ab + ba) })
                    })
                    .collect()
            })
            .collect();
        (std_errors, covariance)
    }

    /// Warns of each ill-conditioned block, naming the columns of its
    /// weakest direction.
    /// Per experiment, the equations it loses at its start when the model
    /// declares dead times; nothing otherwise.
    fn dropped_at_start(&self) -> Vec<DroppedAtStart> {
        if self.ir.delays.is_empty() {
            return Vec::new();
        }
        self.facts
            .iter()
            .map(|f| DroppedAtStart {
                experiment: f.name.clone(),
                dead_time: f.dead_time,
                method: METHOD_DROPS,
                equations: f.dead_time + METHOD_DROPS,
            })
            .collect()
    }

    fn warn_ill_conditioned(&mut self, sol: &[BlockSolution]) {
        let cols = self.ir.predictors.get(self.kind);
        for s in sol.iter().filter(|s| s.condition > CONDITION_WARNING) {
            let weak: Vec<String> = s.weak.iter().map(|c| cols[*c].name.clone()).collect();
            self.warnings.push(Warning::new(
                "ill-conditioned",
                format!(
                    "ill-conditioned (condition number {:.2e}): {} are nearly collinear or barely excited",
                    s.condition,
                    names_capped(&weak, 3)
                ),
                "vary the inputs more (larger, more varied manoeuvres) or add experiments; their standard errors say how unreliable",
                format!(
                    "the moment matrix is ill-conditioned (condition number {:.2e}): the weakest direction involves {}, whose estimates are unreliable (nearly collinear, or barely excited by these data)",
                    s.condition,
                    if weak.is_empty() { "several columns".to_string() } else { weak.join(", ") }
                ),
            ));
        }
    }

    /// How the moments were centred, and why.
    fn centring_text(&self) -> String {
        let how = if self.options.centring.is_some() {
            "as asked"
        } else {
            "the default for this model"
        };
        match (self.options.method, self.centring) {
            (Method::Ls, Centring::Experiment) => format!(
                "experiment ({how}): an intercept per output and experiment — least squares keeps the constants that cos² = 1 − sin² and the disturbance means create; {}",
                self.centring.reason(self.ir, self.kind)
            ),
            (Method::Ls, Centring::Pooled) => format!(
                "pooled ({how}): one intercept per output over all experiments (the model's constant term where it has one); {}",
                self.centring.reason(self.ir, self.kind)
            ),
            (Method::Ls, Centring::None) => format!(
                "none ({how}): no intercept beyond the model's constant terms; {}",
                self.centring.reason(self.ir, self.kind)
            ),
            (_, c) => format!("{} ({how}): {}", c.name(), c.reason(self.ir, self.kind)),
        }
    }

    /// What the instruments were.
    fn instruments_text(&self) -> String {
        match (self.options.method, self.options.instruments) {
            (Method::Ls, _) => "none (least squares: the regressors themselves)".to_string(),
            (_, Instruments::Simulated) => {
                let first = match (&self.options.start, self.options.refine_subsample) {
                    (Some(_), Some(_)) => "first simulation: the estimate refined on the subsample",
                    (Some(_), None) => "first simulation: the warm start's estimate",
                    (None, _) => match self.options.initial {
                        Initial::Nominal => "first simulation: the nominal model",
                        Initial::Delayed => {
                            "first simulation: an estimate with delayed-measurement instruments"
                        }
                    },
                };
                let mut text = format!("simulated model ({first}), refined with the estimate");
                // Only what this model has: a heading, measured media.
                if matches!(self.ir.rotation, Rotation::Planar { .. }) {
                    text.push_str(
                        "; rotation from the heading anchored to the previous measurement",
                    );
                }
                if self.ir.disturbances.iter().any(|d| d.measured) {
                    text.push_str("; measured disturbances as their experiment mean");
                }
                text
            }
            (_, Instruments::Delayed) => {
                "regressors of the measurements one sample earlier".to_string()
            }
        }
    }
}

/// Covariances of the estimated columns, by column pair.
type Covariance = BTreeMap<(usize, usize), f64>;

/// The standard error of column `c`, from its variance in `cov`.
fn std_error(cov: Option<&Covariance>, c: usize) -> Option<f64> {
    cov.and_then(|m| m.get(&(c, c))).map(|v| v.max(0.0).sqrt())
}
