//! Turning the solution into the returned `Estimate`: column statuses, standard errors, warnings, diagnostics.

use crate::estimator::Estimator;
use crate::method::{Initial, Instruments, Method};
use crate::outcome::{ColumnEstimate, Diagnostics, Estimate, EstimateError};
use crate::solve::{BlockSolution, CONDITION_WARNING};
use leeway_model::signs::ExperimentSigns;
use leeway_structure::identify::Centring;
use leeway_structure::ir::{ColumnKind, PredictorKind};
use std::collections::BTreeMap;

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
        let se = |c: usize| {
            cov.as_ref()
                .and_then(|m| m.get(&(c, c)))
                .map(|v| v.max(0.0).sqrt())
        };
        let estimated: Vec<usize> = sol.iter().flat_map(|s| s.kept.iter().copied()).collect();
        let numeric_held: BTreeMap<usize, f64> =
            sol.iter().flat_map(|s| s.held.iter().copied()).collect();
        let structural_held: BTreeMap<usize, f64> = self.held.iter().copied().collect();
        let columns: Vec<ColumnEstimate> = cols
            .iter()
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
                ColumnEstimate {
                    name: col.name.clone(),
                    kind,
                    value,
                    std_error: if estimated.contains(&c) { se(c) } else { None },
                    status,
                    estimates: self.column_texts[c].clone(),
                }
            })
            .collect();
        let theta_cols: Vec<Option<usize>> = (0..self.ir.parameters.len())
            .map(|p| {
                cols.iter()
                    .position(|c| c.kind == ColumnKind::Theta { parameter: p })
            })
            .collect();
        let std_errors = theta_cols
            .iter()
            .map(|c| c.filter(|c| estimated.contains(c)).and_then(se))
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
                        let m = cov.as_ref()?;
                        let (ab, ba) = (*m.get(&(a, b))?, *m.get(&(b, a))?);
                        // `B G Bᵀ` is symmetric up to round-off; the mean
                        // makes it exactly so and keeps the diagonal.
                        Some(if a == b { ab } else { 0.5 * (ab + ba) })
                    })
                    .collect()
            })
            .collect();
        let disturbances = if self.kind == PredictorKind::Basic {
            Vec::new()
        } else {
            self.disturbance_means(&values, &theta, cov.as_ref())
        };
        let condition = sol.iter().map(|s| s.condition).fold(0.0, f64::max);
        for s in sol.iter().filter(|s| s.condition > CONDITION_WARNING) {
            let weak: Vec<&str> = s.weak.iter().map(|c| cols[*c].name.as_str()).collect();
            self.warnings.push(format!(
                "the moment matrix is ill-conditioned (condition number {:.2e}): the weakest direction involves {}, whose estimates are unreliable (nearly collinear, or barely excited by these data)",
                s.condition,
                if weak.is_empty() { "several columns".to_string() } else { weak.join(", ") }
            ));
        }
        let structural_kept: usize = self.blocks.iter().map(|b| b.cols.len()).sum();
        let how = if self.options.centring.is_some() {
            "as asked"
        } else {
            "the default for this model"
        };
        let centring = match (self.options.method, self.centring) {
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
        };
        let instruments = match (self.options.method, self.options.instruments) {
            (Method::Ls, _) => "none (least squares: the regressors themselves)".to_string(),
            (_, Instruments::Simulated) => format!(
                "simulated model ({}), refined with the estimate; rotation from the heading anchored to the previous measurement; measured disturbances as their experiment mean",
                match self.options.initial {
                    Initial::Nominal => "first simulation: the nominal model",
                    Initial::Delayed =>
                        "first simulation: an estimate with delayed-measurement instruments",
                }
            ),
            (_, Instruments::Delayed) => {
                "regressors of the measurements one sample earlier".to_string()
            }
        };
        let equations = self.facts.iter().map(|f| f.len.saturating_sub(2)).sum();
        Ok(Estimate {
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
            },
            warnings: self.warnings.clone(),
            notes: Vec::new(),
            instrument_simulation: None,
        })
    }
}
