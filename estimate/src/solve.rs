//! Solving the moment equations per block: residue test, equilibration, column selection, the pseudo-inverse map used by the covariance.
//!
//! The experiments' equations are summed (the default, and least squares'
//! normal equations) or stacked. An IV's summed system is divided by the
//! total number of equations, so one experiment gives the stacked system's
//! estimate bit for bit. Rank decisions and the reported condition number
//! are made on the row- and column-equilibrated system, so units never
//! change a verdict; the numeric rank only adds what the data failed to
//! excite to the structural analysis, the single source of identifiability
//! verdicts. A moment sum that is not finite is the error
//! `non-finite-moments` before any decomposition sees it (nalgebra's SVD
//! panics on a NaN).

use crate::estimator::Estimator;
use crate::method::{Combine, Method};
use crate::moments::CrossMoments;
use crate::outcome::{EstimateError, err};
use leeway_model::number::short_number;
use leeway_model::warning::{Warning, names_capped};
use leeway_structure::exact::Q;
use leeway_structure::ir::{Column, ColumnKind, PredictorKind};
use nalgebra::{DMatrix, DVector};

/// A moment column below this many machine epsilons per equation of its
/// Cauchy–Schwarz scale is rounding residue, not information.
pub(super) const RESIDUE_EPSILONS: f64 = 64.0;

/// Condition number of the equilibrated moment matrix above which an
/// estimate is reported as ill-conditioned, naming the columns involved.
pub(super) const CONDITION_WARNING: f64 = 1e8;

/// The per-block outcome of a solve.
#[derive(Clone, Debug)]
pub(super) struct BlockSolution {
    /// Columns (predictor indices) estimated.
    pub(super) kept: Vec<usize>,
    /// Numerically dropped columns with their held value.
    pub(super) held: Vec<(usize, f64)>,
    /// Estimates of `kept`.
    pub(super) values: Vec<f64>,
    /// `ϑ_K = Σ_i B_i · (Σ_k ζ_k of experiment i)` over the block's instrument rows.
    pub(super) b: Vec<DMatrix<f64>>,
    /// Instrument rows (predictor columns) of ζ.
    pub(super) rows: Vec<usize>,
    pub(super) condition: f64,
    /// Columns that dominate the weakest direction when ill-conditioned.
    pub(super) weak: Vec<usize>,
}

impl Estimator<'_> {
    /// The error for a block whose moment sums are not finite.
    fn non_finite_moments(&self, b: usize) -> EstimateError {
        let outputs: Vec<&str> = self.blocks[b]
            .outputs
            .iter()
            .filter_map(|o| self.ir.states.get(*o).map(String::as_str))
            .collect();
        err(
            "non-finite-moments",
            format!(
                "the moment sums of output{} {} are not finite: the instruments' simulation or a sum overflowed",
                if outputs.len() == 1 { "" } else { "s" },
                outputs.join(", ")
            ),
            "check the nominal values (--nominal, the model's nominal { }) and the data's units; --initial delayed or --instruments delayed start from the data instead of the nominal model",
        )
    }

    /// Solves every block; collects numeric rank findings.
    pub(super) fn solve(
        &mut self,
        moments: &[Vec<CrossMoments>],
        record: bool,
    ) -> Result<Vec<BlockSolution>, EstimateError> {
        let mut out = Vec::with_capacity(self.blocks.len());
        let mut errors = Vec::new();
        for b in 0..self.blocks.len() {
            out.push(self.solve_block(moments, b, record, &mut errors)?);
        }
        if !errors.is_empty() {
            return Err(self.rank_deficient(&errors));
        }
        Ok(out)
    }

    /// Solves block `b`: its system assembled, residue columns zeroed,
    /// rows equilibrated, columns selected (those not excited held, or
    /// reported in `errors`), then solved.
    fn solve_block(
        &mut self,
        moments: &[Vec<CrossMoments>],
        b: usize,
        record: bool,
        errors: &mut Vec<String>,
    ) -> Result<BlockSolution, EstimateError> {
        let cols = self.blocks[b].cols.clone();
        let m = cols.len();
        // The summed system (Σ H_i) ϑ = Σ g_i (IV by default, and LS's
        // normal equations), or the stacked one [H_i/n_i] ϑ = [g_i/n_i].
        let summed = self.options.method == Method::Ls || self.combine() == Combine::Summed;
        let System {
            mut mat,
            rhs,
            scale_rows,
            bound,
        } = self.block_system(moments, b, summed);
        // A simulation that overflowed (or a sum that did) leaves a
        // non-finite moment: no decomposition may see it.
        if !(mat.iter().chain(rhs.iter()).chain(&bound)).all(|v| v.is_finite()) {
            return Err(self.non_finite_moments(b));
        }
        let equations: usize = moments.iter().map(|e| e[self.blocks[b].outputs[0]].n).sum();
        zero_residue_columns(&mut mat, &bound, equations);
        let (scaled, row_scale) = equilibrate_rows(&mat, m);
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by_key(|j| self.preference[cols[*j]]);
        // A dropped column's combination of the kept ones is only read in
        // messages: the recorded solve's, or the error without --aggregate.
        let explain = record || !self.options.aggregate;
        let sel = select_columns(&scaled, &order, self.options.rank_tolerance, explain);
        // The square summed system is solved equilibrated (its solution
        // does not depend on row scaling); the stacked one as the paper
        // writes it, by unweighted least squares over the rows.
        let (mat, rhs, row_scale) = if summed {
            (scaled.clone(), scaled_rhs(rhs, &row_scale), row_scale)
        } else {
            (mat, rhs, vec![1.0; row_scale.len()])
        };
        let held = self.hold_dropped(&cols, &sel.dropped, record, errors);
        let kept: Vec<usize> = sel.kept.iter().map(|j| cols[*j]).collect();
        let g = without_held(&rhs, &mat, &cols, &held);
        let kj: Vec<usize> = sel.kept.clone();
        let mk = DMatrix::from_fn(mat.nrows(), kj.len(), |r, k| mat[(r, kj[k])]);
        // A refinement's iterate needs only ϑ: the columns kept are
        // independent, so a QR factorisation solves it; the recorded
        // solve (the estimate reported, its covariance map and
        // conditioning) takes the SVD.
        // Without a covariance, the recorded solve needs only the
        // singular values besides ϑ (the conditioning of the summed,
        // equilibrated system), not the pseudo-inverse.
        let values_only = !record || (summed && !self.options.covariance);
        if values_only && let Some(values) = solve_independent(&mk, &g) {
            return Ok(independent_solution(&mk, kept, held, &values, record));
        }
        let (values, mut pinv, condition) = solve_equilibrated(&mk, &g);
        // The map from the unscaled moment sums to ϑ includes the row scaling.
        for (c, d) in row_scale.iter().enumerate() {
            pinv.column_mut(c).scale_mut(*d);
        }
        // Conditioning judged on the equilibrated system, whatever the units.
        let ks = || DMatrix::from_fn(scaled.nrows(), kj.len(), |r, k| scaled[(r, kj[k])]);
        let condition = if summed {
            condition
        } else {
            solve_equilibrated(&ks(), &DVector::zeros(scaled.nrows())).2
        };
        let weak = if condition > CONDITION_WARNING {
            weak_columns(condition, &ks(), &kept)
        } else {
            Vec::new()
        };
        let b_list = self.moment_maps(&pinv, &kj, &scale_rows, summed, m);
        let rows = if self.options.method == Method::Ls {
            kept.clone()
        } else {
            cols.clone()
        };
        Ok(BlockSolution {
            kept,
            held,
            values: values.iter().copied().collect(),
            b: b_list,
            rows,
            condition,
            weak,
        })
    }

    /// Block `b`'s moment equations over every experiment: summed, or
    /// stacked with each experiment's rows divided by its count.
    fn block_system(&self, moments: &[Vec<CrossMoments>], b: usize, summed: bool) -> System {
        let m = self.blocks[b].cols.len();
        let e_count = moments.len();
        if summed {
            let mut a = DMatrix::zeros(m, m);
            let mut g = DVector::zeros(m);
            let mut bound = vec![0.0; m];
            for i in 0..e_count {
                let (h, gi, bi) = self.equations(moments, i, b);
                a += h;
                g += gi;
                for (s, v) in bound.iter_mut().zip(bi) {
                    *s += v;
                }
            }
            if self.options.method == Method::Ls {
                System {
                    mat: a,
                    rhs: g,
                    scale_rows: vec![1.0; e_count],
                    bound,
                }
            } else {
                // Divided by the total count, the summed system of one
                // experiment is the stacked one bit for bit.
                let total: usize = moments.iter().map(|e| e[self.blocks[b].outputs[0]].n).sum();
                let n = total.max(1) as f64;
                for v in &mut bound {
                    *v /= n;
                }
                System {
                    mat: a / n,
                    rhs: g / n,
                    scale_rows: vec![1.0 / n; e_count],
                    bound,
                }
            }
        } else {
            let mut a = DMatrix::zeros(m * e_count, m);
            let mut g = DVector::zeros(m * e_count);
            let mut scales = Vec::new();
            let mut bound = vec![0.0; m];
            for i in 0..e_count {
                let (h, gi, bi) = self.equations(moments, i, b);
                let n = moments[i][self.blocks[b].outputs[0]].n.max(1) as f64;
                a.view_mut((i * m, 0), (m, m)).copy_from(&(h / n));
                g.rows_mut(i * m, m).copy_from(&(gi / n));
                scales.push(1.0 / n);
                for (s, v) in bound.iter_mut().zip(bi) {
                    *s += v / n;
                }
            }
            System {
                mat: a,
                rhs: g,
                scale_rows: scales,
                bound,
            }
        }
    }

    /// What the numerically dropped columns (`dropped`, indices into
    /// `cols`, with their combinations of the kept ones) are held at: θ
    /// columns at nominal where that is allowed (else an entry of
    /// `errors`), nuisance columns at 0; a `record`ed solve reports them.
    fn hold_dropped(
        &mut self,
        cols: &[usize],
        dropped: &[(usize, Vec<(usize, f64)>)],
        record: bool,
        errors: &mut Vec<String>,
    ) -> Vec<(usize, f64)> {
        let mut held = Vec::new();
        for (j, combo) in dropped {
            let c = cols[*j];
            let col = &self.ir.predictors.get(self.kind)[c];
            // Formatted only where it is reported (a recorded solve,
            // or an error): exact rationals are not cheap.
            let text = || self.dropped_text(cols, c, combo);
            match col.kind {
                ColumnKind::Theta { parameter } => {
                    let p = &self.ir.parameters[parameter];
                    let value = self.nominal[parameter];
                    if p.measured && self.kind == PredictorKind::Measured {
                        if record {
                            let text = text();
                            self.report_measured_held(text, parameter, cols, combo);
                        }
                        held.push((c, value));
                    } else if self.options.aggregate {
                        if record {
                            let text = text();
                            self.warnings.push(Warning::new(
                                "not-excited",
                                format!(
                                    "`{}` held at {} (--aggregate): these data do not excite it apart from {}",
                                    p.name,
                                    short_number(value),
                                    self.combo_names(cols, combo)
                                ),
                                "add experiments that excite it; --verbose shows the exact combination",
                                format!("{text}; held at its nominal value {value} (--aggregate)"),
                            ));
                            self.unexcited.push(text);
                        }
                        held.push((c, value));
                    } else {
                        errors.push(text());
                    }
                }
                _ => {
                    if record {
                        self.unexcited
                            .push(format!("{} (nuisance; held at 0)", text()));
                    }
                    held.push((c, 0.0));
                }
            }
        }
        held
    }

    /// Why column `c` was dropped: not excited, or (`combo`, indices into
    /// `cols`) a combination of the kept ones.
    fn dropped_text(&self, cols: &[usize], c: usize, combo: &[(usize, f64)]) -> String {
        let predictors = self.ir.predictors.get(self.kind);
        let col = &predictors[c];
        if combo.is_empty() {
            format!(
                "{} is not excited by these data (its moments vanish)",
                col.name
            )
        } else {
            let mut items: Vec<(String, Q)> = vec![];
            for (k, a) in combo {
                items.push((
                    predictors[cols[*k]].name.clone(),
                    Q::from_float(round_sig(*a)).unwrap_or_default(),
                ));
            }
            format!(
                "{} is not separately excited: its column equals {}",
                col.name,
                linear_text_f(&items)
            )
        }
    }

    /// The columns of a combination (`combo`, indices into `cols`) for a
    /// one-line summary: up to two θ names, the rest counted.
    fn combo_names(&self, cols: &[usize], combo: &[(usize, f64)]) -> String {
        let predictors = self.ir.predictors.get(self.kind);
        let (theta, nuisance): (Vec<&Column>, Vec<&Column>) = combo
            .iter()
            .map(|(k, _)| &predictors[cols[*k]])
            .partition(|c| !c.kind.is_nuisance());
        let names: Vec<String> = theta
            .iter()
            .chain(&nuisance)
            .map(|c| c.name.clone())
            .collect();
        names_capped(&names, theta.len().clamp(1, 2))
    }

    /// Reports a measured-medium parameter held at its nominal value
    /// (`text` says why), and the aggregates the columns it is combined
    /// with (`combo`) estimate.
    fn report_measured_held(
        &mut self,
        text: String,
        parameter: usize,
        cols: &[usize],
        combo: &[(usize, f64)],
    ) {
        let p = &self.ir.parameters[parameter];
        let value = self.nominal[parameter];
        let medium = &self.ir.disturbances[p.medium.unwrap_or(0)].name;
        let detail = format!(
            "{}: the measured {} enters the instruments as its experiment mean, and with these data the instrument of `{}` is a combination of the others (its regressor differs from theirs only through the {}'s fluctuations, or it has no modulus whose sign changes); `{}` is not separately excited by these data, so it is held at its nominal value {} and the parameters it is combined with estimate the aggregates",
            text, medium, p.name, medium, p.name, value
        );
        self.warnings.push(
            Warning::new(
                "not-excited",
                format!(
                    "`{}` held at {}: the {medium} barely varies; its regressor is nearly a combination of {}",
                    p.name,
                    short_number(value),
                    self.combo_names(cols, combo)
                ),
                format!(
                    "a data condition, not a structural one: add runs where the {medium} varies or its relative velocity changes sign"
                ),
                detail,
            )
            .biasing(),
        );
        self.unexcited.push(text);
        for (k, a) in combo {
            let kept = &self.ir.predictors.get(self.kind)[cols[*k]].name;
            let held = if value == 0.0 {
                p.name.clone()
            } else if value < 0.0 {
                format!("({} + {})", p.name, short_number(-value))
            } else {
                format!("({} - {})", p.name, short_number(value))
            };
            let coef = round_sig(*a);
            self.aggregates.push(format!(
                "{kept} estimates {kept} {} {}*{held}",
                if coef < 0.0 { "-" } else { "+" },
                coef.abs()
            ));
        }
    }

    /// `B_i` of each experiment: `ϑ_K = pinv · g`, with g's experiment-i
    /// rows = `(Σ_k ζ_k)·scale_i` (`kj`: the kept columns, `m` per block).
    fn moment_maps(
        &self,
        pinv: &DMatrix<f64>,
        kj: &[usize],
        scale_rows: &[f64],
        summed: bool,
        m: usize,
    ) -> Vec<DMatrix<f64>> {
        let e_count = scale_rows.len();
        if self.options.method == Method::Ls {
            // ϑ = A⁻¹ Σ ζ restricted to the kept rows.
            let rows_idx = kj.to_vec();
            let sub = DMatrix::from_fn(kj.len(), rows_idx.len(), |r, k| pinv[(r, rows_idx[k])]);
            vec![sub; e_count]
        } else if summed {
            (0..e_count).map(|i| pinv * scale_rows[i]).collect()
        } else {
            (0..e_count)
                .map(|i| pinv.columns(i * m, m) * scale_rows[i])
                .collect()
        }
    }

    /// The error for columns the data did not excite (`errors`).
    fn rank_deficient(&self, errors: &[String]) -> EstimateError {
        let remark2 = self
            .infos
            .iter()
            .any(|i| i.spread < 4.0 * self.options.heading_spread);
        err(
            "rank-deficient",
            format!(
                "the data did not excite every parameter: {}",
                errors.join("; ")
            ),
            if remark2 {
                "the heading barely varied, which leaves the disturbance terms collinear with the others (paper Remark 2): turn the craft during the experiment; or estimate the identifiable combinations with --aggregate".to_string()
            } else {
                "excite the named terms (richer input, experiments with other sign patterns), or estimate the identifiable combinations with --aggregate".to_string()
            },
        )
    }

    /// θ from block solutions (held parameters at nominal).
    pub(super) fn theta_of(&self, sol: &[BlockSolution]) -> Vec<f64> {
        let mut theta = self.nominal.clone();
        let cols = self.ir.predictors.get(self.kind);
        for (c, v) in self.all_values(sol) {
            if let ColumnKind::Theta { parameter } = cols[c].kind {
                theta[parameter] = v;
            }
        }
        theta
    }

    pub(super) fn all_values(&self, sol: &[BlockSolution]) -> Vec<(usize, f64)> {
        let mut v: Vec<(usize, f64)> = self.held.clone();
        for s in sol {
            v.extend(s.kept.iter().copied().zip(s.values.iter().copied()));
            v.extend(s.held.iter().copied());
        }
        v.sort_by_key(|(c, _)| *c);
        v
    }
}

/// One block's moment equations, as solved.
struct System {
    mat: DMatrix<f64>,
    rhs: DVector<f64>,
    /// The scale of each experiment's rows.
    scale_rows: Vec<f64>,
    /// Each column's Cauchy–Schwarz scale, for the residue test.
    bound: Vec<f64>,
}

/// Scale-aware residue test over the whole system: a column whose moments
/// are at the rounding level of its own scale (`bound`, over `equations`
/// equations) carries no information, whatever the units (equilibration
/// would otherwise blow the residue up into a column): it is zeroed.
fn zero_residue_columns(mat: &mut DMatrix<f64>, bound: &[f64], equations: usize) {
    let residue = RESIDUE_EPSILONS * f64::EPSILON * (equations.max(1) as f64);
    for (j, bj) in bound.iter().enumerate() {
        if mat.column(j).norm() <= residue * bj {
            mat.column_mut(j).fill(0.0);
        }
    }
}

/// `mat` with its rows equilibrated (each instrument's equation to unit
/// norm, `m` instruments), and the scale of each row: an instrument in
/// large units must not drown the others, so the rank decision and the
/// conditioning do not depend on the units. One scale per instrument, the
/// same in every experiment's rows (stacked), so the experiments keep their
/// relative weights.
fn equilibrate_rows(mat: &DMatrix<f64>, m: usize) -> (DMatrix<f64>, Vec<f64>) {
    let instrument_norm: Vec<f64> = (0..m)
        .map(|r| {
            (0..mat.nrows() / m)
                .map(|i| mat.row(i * m + r).norm_squared())
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let row_scale: Vec<f64> = (0..mat.nrows())
        .map(|r| {
            let norm = instrument_norm[r % m];
            if norm > 0.0 && norm.is_finite() {
                1.0 / norm
            } else {
                1.0
            }
        })
        .collect();
    let mut scaled = mat.clone();
    for (r, d) in row_scale.iter().enumerate() {
        scaled.row_mut(r).scale_mut(*d);
    }
    (scaled, row_scale)
}

/// The solution `values` of the `kept` columns' independent system `mk`,
/// with `held` ones, and without a map for the covariance: a `record`ed
/// one with its conditioning.
fn independent_solution(
    mk: &DMatrix<f64>,
    kept: Vec<usize>,
    held: Vec<(usize, f64)>,
    values: &DVector<f64>,
    record: bool,
) -> BlockSolution {
    let (condition, weak) = if record {
        let condition = condition_number(mk);
        (condition, weak_columns(condition, mk, &kept))
    } else {
        (f64::NAN, Vec::new())
    };
    BlockSolution {
        kept,
        held,
        values: values.iter().copied().collect(),
        b: Vec::new(),
        rows: Vec::new(),
        condition,
        weak,
    }
}

/// `rhs` with its rows scaled by `row_scale`.
fn scaled_rhs(mut rhs: DVector<f64>, row_scale: &[f64]) -> DVector<f64> {
    for (r, d) in row_scale.iter().enumerate() {
        rhs[r] *= d;
    }
    rhs
}

/// The right-hand side `rhs` without the contribution of the `held`
/// columns (of `cols`, the columns of `mat`).
fn without_held(
    rhs: &DVector<f64>,
    mat: &DMatrix<f64>,
    cols: &[usize],
    held: &[(usize, f64)],
) -> DVector<f64> {
    let mut g = rhs.clone();
    for (c, v) in held {
        if let Some(j) = cols.iter().position(|x| x == c) {
            g -= mat.column(j) * *v;
        }
    }
    g
}

/// The kept columns (`kept`, by column of `mk`) that dominate the weakest
/// direction of `mk` when its `condition` is above [`CONDITION_WARNING`].
fn weak_columns(condition: f64, mk: &DMatrix<f64>, kept: &[usize]) -> Vec<usize> {
    if condition > CONDITION_WARNING {
        weakest_direction(mk).into_iter().map(|k| kept[k]).collect()
    } else {
        Vec::new()
    }
}

/// Significant digits for messages.
pub(super) fn round_sig(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    format!("{v:.2e}").parse().unwrap_or(v)
}

pub(super) fn linear_text_f(items: &[(String, Q)]) -> String {
    let mut out = String::new();
    for (i, (name, q)) in items.iter().enumerate() {
        let v = leeway_structure::exact::to_f64(q);
        if i == 0 {
            out.push_str(&format!("{v}*{name}"));
        } else {
            out.push_str(&format!(
                " {} {}*{name}",
                if v < 0.0 { "-" } else { "+" },
                v.abs()
            ));
        }
    }
    out
}

/// Greedy column selection in preference order on the column-equilibrated
/// matrix (modified Gram–Schmidt, reorthogonalised): a column is kept when
/// its residual against the kept ones exceeds `tol` relative to its norm.
pub(crate) struct Selection {
    pub(crate) kept: Vec<usize>,
    /// Dropped column with its combination of kept columns (original units;
    /// empty unless asked to explain).
    pub(crate) dropped: Vec<(usize, Vec<(usize, f64)>)>,
}

/// `Σ aᵢ bᵢ` in nalgebra's order for dynamic vectors (eight partial sums
/// over blocks of eight, joined as `(0+4) (1+5) (2+6) (3+7)`, then the
/// rest): the column selection computes on slices what it computed with
/// nalgebra, and must keep its bits.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let mut acc = [0.0f64; 8];
    let mut i = 0;
    while n - i >= 8 {
        for (k, s) in acc.iter_mut().enumerate() {
            *s += a[i + k] * b[i + k];
        }
        i += 8;
    }
    let mut res = 0.0;
    res += acc[0] + acc[4];
    res += acc[1] + acc[5];
    res += acc[2] + acc[6];
    res += acc[3] + acc[7];
    for k in i..n {
        res += a[k] * b[k];
    }
    res
}

/// nalgebra's `norm` of a vector: `√(0 + dot(a, a))`.
fn norm(a: &[f64]) -> f64 {
    let mut squares = 0.0;
    squares += dot(a, a);
    squares.sqrt()
}

pub(crate) fn select_columns(
    m: &DMatrix<f64>,
    order: &[usize],
    tol: f64,
    explain: bool,
) -> Selection {
    let rows = m.nrows();
    // Modified Gram–Schmidt, twice, on plain slices into one preallocated
    // basis (a solve makes this selection on every refinement), with
    // nalgebra's order of operations (see `dot`): the same selection.
    let mut basis: Vec<f64> = Vec::with_capacity(rows * rows.min(order.len()));
    let mut v = vec![0.0; rows];
    let mut kept = Vec::new();
    let mut dropped_idx = Vec::new();
    for &j in order {
        let col = &m.as_slice()[j * rows..(j + 1) * rows];
        let length = norm(col);
        if length == 0.0 || !length.is_finite() {
            dropped_idx.push(j);
            continue;
        }
        for (x, c) in v.iter_mut().zip(col) {
            *x = c / length;
        }
        for _ in 0..2 {
            for q in basis.chunks_exact(rows) {
                let d = dot(q, &v);
                // nalgebra's `axpy(−d, q, 1)`: `(−d·q)·1 + 1·v`, that is `−d·q + v`.
                for (x, b) in v.iter_mut().zip(q) {
                    *x += -d * b;
                }
            }
        }
        let r = norm(&v);
        if r > tol.max(1e-300) && basis.len() < rows * rows {
            basis.extend(v.iter().map(|x| x / r));
            kept.push(j);
        } else {
            dropped_idx.push(j);
        }
    }
    kept.sort_unstable();
    let mk = DMatrix::from_fn(rows, kept.len(), |r, k| m[(r, kept[k])]);
    let dropped = dropped_idx
        .into_iter()
        .map(|j| {
            if !explain || kept.is_empty() || m.column(j).norm() == 0.0 {
                return (j, Vec::new());
            }
            let (alpha, _, _) = solve_equilibrated(&mk, &m.column(j).into_owned());
            let scale = m.column(j).norm();
            let combo = kept
                .iter()
                .zip(alpha.iter())
                .filter(|(k, a)| (**a * m.column(**k).norm()).abs() > 1e-3 * scale)
                .map(|(k, a)| (*k, *a))
                .collect();
            (j, combo)
        })
        .collect();
    Selection { kept, dropped }
}

/// The columns (indices into `m`) that dominate the right singular vector
/// of the smallest singular value of the column-equilibrated `m`.
pub(super) fn weakest_direction(m: &DMatrix<f64>) -> Vec<usize> {
    let cols = m.ncols();
    if cols == 0 || m.nrows() == 0 {
        return Vec::new();
    }
    let d: Vec<f64> = (0..cols)
        .map(|j| m.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    let scaled = DMatrix::from_fn(m.nrows(), cols, |r, c| m[(r, c)] / d[c]);
    let svd = scaled.svd(false, true);
    let Some(vt) = svd.v_t else {
        return Vec::new();
    };
    let (weakest, _) = svd.singular_values.argmin();
    let v = vt.row(weakest);
    let top = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    (0..cols).filter(|j| v[*j].abs() >= 0.3 * top).collect()
}

/// Least-squares solution of `M x = g` for independent columns, with
/// column equilibration, by Householder QR; `None` when the triangular
/// factor is singular or the solution not finite (then only the SVD of
/// [`solve_equilibrated`] answers).
pub(crate) fn solve_independent(m: &DMatrix<f64>, g: &DVector<f64>) -> Option<DVector<f64>> {
    let cols = m.ncols();
    if cols == 0 || m.nrows() < cols {
        return None;
    }
    let d: Vec<f64> = (0..cols)
        .map(|j| m.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    let scaled = DMatrix::from_fn(m.nrows(), cols, |r, c| m[(r, c)] / d[c]);
    let qr = scaled.qr();
    let mut rhs = g.clone();
    qr.q_tr_mul(&mut rhs);
    let r = qr.r();
    let x = r.solve_upper_triangular(&rhs.rows(0, cols).into_owned())?;
    let x = DVector::from_iterator(cols, x.iter().zip(&d).map(|(v, s)| v / s));
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The condition number of the column-equilibrated `m`, as
/// [`solve_equilibrated`] reports it, from its singular values alone.
pub(crate) fn condition_number(m: &DMatrix<f64>) -> f64 {
    let cols = m.ncols();
    if cols == 0 || m.nrows() == 0 {
        return 1.0;
    }
    let d: Vec<f64> = (0..cols)
        .map(|j| m.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    let scaled = DMatrix::from_fn(m.nrows(), cols, |r, c| m[(r, c)] / d[c]);
    let s = scaled.singular_values();
    let (smax, smin) = (s.max(), s.min());
    if smin > 0.0 {
        smax / smin
    } else {
        f64::INFINITY
    }
}

/// Least-squares solution of `M x = g` with column equilibration; returns
/// `x`, the pseudo-inverse mapping `g ↦ x`, and the condition number.
pub(crate) fn solve_equilibrated(
    m: &DMatrix<f64>,
    g: &DVector<f64>,
) -> (DVector<f64>, DMatrix<f64>, f64) {
    let cols = m.ncols();
    if cols == 0 || m.nrows() == 0 {
        return (DVector::zeros(0), DMatrix::zeros(0, m.nrows()), 1.0);
    }
    let d: Vec<f64> = (0..cols)
        .map(|j| m.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    let scaled = DMatrix::from_fn(m.nrows(), cols, |r, c| m[(r, c)] / d[c]);
    let svd = scaled.svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    let condition = if smin > 0.0 {
        smax / smin
    } else {
        f64::INFINITY
    };
    let pinv = svd
        .pseudo_inverse(0.0)
        .unwrap_or_else(|_| DMatrix::zeros(cols, m.nrows()));
    let pinv = DMatrix::from_fn(cols, m.nrows(), |r, c| pinv[(r, c)] / d[r]);
    let x = &pinv * g;
    (x, pinv, condition)
}
