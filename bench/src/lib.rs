//! leeway-bench: benchmarks that need the whole stack (the facade, its macros
//! and the estimator crates), kept out of the facade so that trybuild, which compiles
//! every dev-dependency of the facade, never builds criterion. See
//! `benches/` and docs/performance.md. It holds the model generators shared
//! by the binaries `gen-model` and `fuzz-check` ([`models`]).
//!
//! This library holds what the benches print beside their times: the
//! floating-point work of the moment sums ([`moment_flops`]) for the columns
//! an estimate keeps ([`kept_columns`]), and one line relating it to a time
//! and to the core's peak ([`flop_line`]), so the distance to the
//! arithmetic floor is visible.

pub mod models;

use leeway::ir::{Ir, PredictorKind};
use leeway::model::Source;
use leeway::model::signs;
use leeway::structure::identify::Analysis;
use leeway::structure::identify::ExperimentStructure;
use leeway::structure::identify::Patterns;

/// Peak double-precision rate of one core of the machine the benches were
/// written on, GFLOP/s (the profile's figure: two 8-wide FMA ports at the
/// sustained clock). Only a yardstick: [`flop_line`] prints the fraction of
/// it achieved.
pub const PEAK_GFLOPS: f64 = 57.0;

/// The columns the estimator's moment sums run over for one record: the
/// predictor's columns that the exact structural analysis keeps for the
/// record's sign pattern (arguments whose sign changes within the record
/// stay symbolic), in column order — the estimator's `pivot` columns, with
/// the model's default centring and the rotation not frozen (a record whose
/// heading varies). Numeric column selection later drops no column from the
/// sums, only from the solve.
pub fn kept_columns(ir: &Ir, kind: PredictorKind, record: &dyn Source) -> Vec<usize> {
    let found = signs::detect(ir, kind, record);
    let varying = found
        .pointwise
        .iter()
        .filter(|a| a.minority_fraction > 0.0)
        .filter_map(|a| ir.sign_args.iter().position(|x| x.name == a.argument))
        .collect();
    let experiment = ExperimentStructure {
        pattern: found.pattern,
        frozen_rotation: None,
        varying,
    };
    Analysis::new(ir, kind)
        .reduce(Patterns::Experiments(&[experiment]))
        .kept()
}

/// Floating-point operations of the moment sums per sample and pass.
///
/// For every output `o` the estimator adds the rank-1 update `z·[φᵀ t]` of
/// its instruments `z` (`m_o` values) against its regressors `φ` (`p_o`
/// values) and its target `t`: `2·m_o·(p_o + 1)` operations (a multiply and
/// an add each), where `m_o = p_o` is the number of `kept` columns in `o`'s
/// block — outputs joined into one block when a column of the predictor
/// appears in several of them (`Column::outputs`), as `Estimator::new`
/// builds them. The lower-order sums (means, energies: `O(m_o)`) are left
/// out. For IV3 on the ship at the paper's wind this is 1,204.
pub fn moment_flops(ir: &Ir, kind: PredictorKind, kept: &[usize]) -> u64 {
    let columns = ir.predictors.get(kind);
    let n_out = ir.states.len();
    // Outputs connected through shared columns, by union–find.
    let mut block: Vec<usize> = (0..n_out).collect();
    fn root(block: &mut [usize], mut o: usize) -> usize {
        while block[o] != o {
            block[o] = block[block[o]];
            o = block[o];
        }
        o
    }
    for col in columns {
        let outputs = col.outputs();
        for pair in outputs.windows(2) {
            if pair[1] < n_out {
                let (a, b) = (root(&mut block, pair[0]), root(&mut block, pair[1]));
                block[b] = a;
            }
        }
    }
    // Kept columns per block, counted at the column's first output.
    let mut size = vec![0u64; n_out];
    for &c in kept {
        if let Some(o) = columns
            .get(c)
            .and_then(|col| col.outputs().first().copied())
            && o < n_out
        {
            size[root(&mut block, o)] += 1;
        }
    }
    (0..n_out)
        .map(|o| {
            let m = size[root(&mut block, o)];
            2 * m * (m + 1)
        })
        .sum()
}

/// One line of a bench's report for one estimate: what was timed, `N`,
/// the moment passes, the moment sums' FLOP per sample and pass, then
/// [`rate`] of the total (`N · passes · flops_per_sample`).
pub fn flop_line(
    what: &str,
    n: usize,
    passes: usize,
    flops_per_sample: u64,
    seconds: f64,
) -> String {
    let flop = n as f64 * passes as f64 * flops_per_sample as f64;
    format!(
        "{what:<24} N {n:>5}  passes {passes:>2}  {flops_per_sample:>5} FLOP/sample/pass  {}",
        rate(flop, seconds)
    )
}

/// `flop` operations done in `seconds`: the total, the time, the rate
/// achieved and its share of [`PEAK_GFLOPS`], and the floor — the time the
/// operations alone would take at peak.
pub fn rate(flop: f64, seconds: f64) -> String {
    let gflops = flop / seconds / 1e9;
    format!(
        "{:>7.2} MFLOP  {:>8.3} ms  {gflops:>6.3} GFLOP/s = {:>5.2}% of {PEAK_GFLOPS} (floor {:.3} ms)",
        flop / 1e6,
        seconds * 1e3,
        100.0 * gflops / PEAK_GFLOPS,
        flop / (PEAK_GFLOPS * 1e9) * 1e3,
    )
}

/// One sample's signals, owned.
pub struct Sample {
    /// The states.
    pub states: Vec<f64>,
    /// The inputs.
    pub inputs: Vec<f64>,
    /// The planar rotation's entries.
    pub rotation: Vec<f64>,
    /// Every disturbance component.
    pub disturbances: Vec<f64>,
}

impl Sample {
    /// The sample as a model reads it.
    pub fn signals(&self) -> leeway::Signals<'_> {
        leeway::Signals {
            states: &self.states,
            inputs: &self.inputs,
            rotation: &self.rotation,
            disturbances: &self.disturbances,
        }
    }
}

/// `batch` deterministic pseudo-random samples (a 64-bit LCG; no
/// dependency) of a planar `model`'s signals.
pub fn samples(model: &dyn leeway::Model, batch: usize) -> Vec<Sample> {
    let ir = model.ir();
    let (states, inputs, components) = (ir.states.len(), ir.inputs.len(), ir.components.len());
    let mut state = 0x9E37_79B9_7F4A_7C15_u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..batch)
        .map(|_| Sample {
            states: (0..states).map(|_| 4.0 * next() - 2.0).collect(),
            inputs: (0..inputs).map(|_| 40.0 * next() - 20.0).collect(),
            rotation: leeway::planar_rotation(7.0 * next()).to_vec(),
            disturbances: (0..components).map(|_| 3.0 * next() - 1.5).collect(),
        })
        .collect()
}

/// This process's CPU time (user + system, all threads) in seconds, where
/// `/proc/self/stat` reports it (Linux; its clock ticks are 1/100 s).
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (in parentheses, which may hold spaces).
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime: fields 14 and 15 of the line, 12 and 13 after the name.
    let ticks: u64 = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    Some(ticks as f64 / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use leeway::Model;

    fn ship() -> Ir {
        let source = include_str!("../../examples/models/ship.som");
        match leeway::compile(source, &leeway::CompileOptions::default()).ir {
            Some(ir) => ir,
            None => panic!("the ship compiles"),
        }
    }

    /// Every column kept: `Σ_o 2·m_o·(m_o + 1)` with one block per output.
    #[test]
    fn moment_flops_count_every_output_block() {
        let ir = ship();
        let kind = PredictorKind::Basic;
        let all: Vec<usize> = (0..ir.predictors.basic.len()).collect();
        let mut per_output = [0u64; 3];
        for c in &ir.predictors.basic {
            per_output[c.outputs()[0]] += 1;
        }
        let want: u64 = per_output.iter().map(|m| 2 * m * (m + 1)).sum();
        assert_eq!(moment_flops(&ir, kind, &all), want);
        assert_eq!(moment_flops(&ir, kind, &[]), 0);
    }

    /// A column in two outputs joins them into one block: both outputs sum
    /// over the block's columns.
    #[test]
    fn a_shared_column_joins_outputs() {
        let mut ir = ship();
        let kind = PredictorKind::Basic;
        let all: Vec<usize> = (0..ir.predictors.basic.len()).collect();
        let mut extra = ir.predictors.basic[0].clone();
        let Some(leeway::ir::Entry::Term { output, .. }) = extra.entries.first_mut() else {
            panic!("a basic column is a term")
        };
        *output = 1;
        ir.predictors.basic[0].entries.extend(extra.entries);
        let m = (ir.predictors.basic.iter())
            .filter(|c| c.outputs().iter().any(|o| *o < 2))
            .count() as u64;
        let m2 = (ir.predictors.basic.iter())
            .filter(|c| c.outputs() == [2])
            .count() as u64;
        assert_eq!(
            moment_flops(&ir, kind, &all),
            2 * (2 * m * (m + 1)) + 2 * m2 * (m2 + 1)
        );
    }

    /// The count for IV3 on the paper's ship: the kept columns
    /// (13, 14 and 14 per output) give 1,204 FLOP a sample a pass.
    #[test]
    fn iv3_on_the_paper_ship() {
        let model = leeway::Interpreter::new(ship());
        let (data, _) = leeway_scenarios::study::estimation_experiment(
            &model,
            &Default::default(),
            10.0,
            1000,
            1,
        );
        let kind = PredictorKind::Measured;
        let kept = kept_columns(model.ir(), kind, &data);
        assert_eq!(moment_flops(model.ir(), kind, &kept), 1204, "kept {kept:?}");
    }

    #[test]
    fn the_line_relates_work_to_time() {
        // 1e9 FLOP in one second: 1 GFLOP/s.
        let line = flop_line("x", 1000, 1, 1_000_000, 1.0);
        assert!(line.contains(" 1.000 GFLOP/s"), "{line}");
        assert!(line.contains("passes  1"), "{line}");
    }
}
