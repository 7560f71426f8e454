//! Estimation split into map and reduce: a pass runner that behaves like a
//! distributed engine — every message crosses as bytes, each experiment's
//! summary is computed on its own thread in an arbitrary order — must give
//! the local estimate's bits exactly, because the driver combines the
//! summaries in experiment order whoever computed them.

use crate::Streamed;
use leeway_estimate::Estimate;
use leeway_estimate::EstimateError;
use leeway_estimate::EstimateOptions;
use leeway_estimate::ExperimentFacts;
use leeway_estimate::FactsRequest;
use leeway_estimate::LocalPasses;
use leeway_estimate::Method;
use leeway_estimate::PassRequest;
use leeway_estimate::PassRunner;
use leeway_estimate::PassSummary;
use leeway_estimate::Passes;
use leeway_estimate::decode;
use leeway_estimate::encode;
use leeway_estimate::estimate;
use leeway_estimate::estimate_with;
use leeway_model::Experiment;
use leeway_model::Interpreter;
use leeway_model::Model;
use leeway_model::Source;
use leeway_scenarios::study;
use leeway_scenarios::study::InputDesign;
use rayon::prelude::*;

fn ship() -> Interpreter {
    let path = format!("{}/../examples/models/ship.som", env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(path).unwrap_or_default();
    let c = leeway_structure::compile(&src, &Default::default());
    Interpreter::new(c.ir.unwrap_or_else(|| panic!("ship.som compiles: {:?}", c.diagnostics)))
}

/// Workers that each hold their experiments and see only bytes.
struct Workers<'a> {
    model: &'a Interpreter,
    experiments: &'a [Experiment],
}

impl Passes for Workers<'_> {
    fn facts(&self, request: &FactsRequest) -> Result<Vec<ExperimentFacts>, EstimateError> {
        let bytes = encode(request);
        let answers: Vec<Vec<u8>> = self
            .experiments
            .par_iter()
            .map(|e| {
                let request: FactsRequest = decode(&bytes).expect("request");
                encode(&PassRunner::new(self.model).facts(e, &request))
            })
            .collect();
        answers.iter().map(|b| decode(b)).collect()
    }

    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        let bytes = encode(request);
        // Last experiment first, on whatever thread: order must not matter.
        let mut answers: Vec<(usize, Vec<u8>)> = (0..self.experiments.len())
            .rev()
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|i| {
                let request: PassRequest = decode(&bytes).expect("request");
                let runner = PassRunner::new(self.model);
                (i, encode(&runner.pass(&self.experiments[i], i, &request)))
            })
            .collect();
        answers.sort_by_key(|(i, _)| *i);
        answers.iter().map(|(_, b)| decode(b)).collect()
    }
}

/// Every number of the estimate by its bits, and its diagnostics and warnings.
fn bits(e: &Estimate) -> String {
    let theta: Vec<u64> = e.theta.iter().map(|v| v.to_bits()).collect();
    let se: Vec<Option<u64>> = e.std_errors.iter().map(|v| v.map(f64::to_bits)).collect();
    let means: Vec<(u64, Option<u64>)> = e
        .disturbances
        .iter()
        .map(|d| (d.mean.to_bits(), d.std_error.map(f64::to_bits)))
        .collect();
    format!(
        "{theta:?} {se:?} {means:?} {:?} {:?}",
        e.diagnostics, e.warnings
    )
}

fn experiments(model: &Interpreter) -> Vec<Experiment> {
    // Runs of different lengths and winds, as a campaign has.
    runs(model, &[(10.0, 700, 11), (6.0, 1300, 12), (14.0, 450, 13)])
}

/// The study's estimation runs of these `(wind, samples, seed)`.
fn runs(model: &Interpreter, runs: &[(f64, usize, u64)]) -> Vec<Experiment> {
    let design = InputDesign::default();
    runs.iter()
        .map(|&(wind, n, seed)| study::estimation_experiment(model, &design, wind, n, seed).0)
        .collect()
}

#[test]
fn mapped_passes_give_the_local_estimate_bit_for_bit() {
    let model = ship();
    let data = experiments(&model);
    let sources: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let workers = Workers {
        model: &model,
        experiments: &data,
    };
    for method in [Method::Iv3, Method::Ls, Method::Iv2] {
        // The study's ship is identifiable only up to its aggregates.
        let options = EstimateOptions {
            method,
            aggregate: true,
            ..EstimateOptions::default()
        };
        let local = estimate(&model, &sources, &options).expect("local estimate");
        let mapped = estimate_with(&model, &workers, &options).expect("mapped estimate");
        assert_eq!(bits(&local), bits(&mapped), "{method:?}");
        assert!(local.std_errors.iter().any(Option::is_some), "{method:?}");
        if method == Method::Iv3 {
            assert!(local.diagnostics.refinements >= 1, "a refined estimate");
        }
    }
}

/// A runner that loses an experiment.
struct Lossy<'a>(Workers<'a>);

impl Passes for Lossy<'_> {
    fn facts(&self, request: &FactsRequest) -> Result<Vec<ExperimentFacts>, EstimateError> {
        self.0.facts(request)
    }
    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        let mut out = self.0.pass(request)?;
        out.pop();
        Ok(out)
    }
}

#[test]
fn a_runner_that_loses_a_summary_is_an_error_not_an_estimate() {
    let model = ship();
    let data = experiments(&model);
    let lossy = Lossy(Workers {
        model: &model,
        experiments: &data,
    });
    let options = EstimateOptions {
        aggregate: true,
        ..EstimateOptions::default()
    };
    let e = estimate_with(&model, &lossy, &options).expect_err("refused");
    assert_eq!(e.code, "invalid-pass");
    let garbage: Result<PassRequest, _> = decode(b"not a pass");
    assert_eq!(garbage.expect_err("garbage").code, "invalid-pass");
}

/// The study's options for `method`: aggregated where the data leave a
/// parameter unexcited.
fn aggregated(method: Method) -> EstimateOptions {
    EstimateOptions {
        method,
        aggregate: true,
        ..EstimateOptions::default()
    }
}

/// Every method's estimate by workers that keep nothing, by its bits.
fn from_scratch(workers: &Workers) -> Vec<String> {
    Method::ALL
        .iter()
        .map(|m| bits(&estimate_with(workers.model, workers, &aggregated(*m)).expect("fresh")))
        .collect()
}

/// One `LocalPasses` kept across the four methods (as the study runs them)
/// reuses facts, regressor rows, heading rotations and simulations between
/// passes and between estimates: each estimate must still be, bit for bit,
/// the one computed from scratch by workers that keep nothing — in either
/// order of the methods, with a warm start, and with nothing kept at all.
#[test]
fn passes_that_keep_what_they_computed_change_no_bit() {
    use leeway_estimate::LocalPasses;
    use leeway_estimate::Start;
    let model = ship();
    let data = experiments(&model);
    let sources: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let workers = Workers {
        model: &model,
        experiments: &data,
    };
    let fresh = from_scratch(&workers);
    for budget in [None, Some(0), Some(300_000)] {
        let shared = LocalPasses::new(&model, &sources).for_several_estimates();
        let shared = match budget {
            Some(b) => shared.with_budget(b),
            None => shared,
        };
        for order in [
            Method::ALL.to_vec(),
            Method::ALL.iter().rev().copied().collect(),
        ] {
            for m in order {
                let kept = estimate_with(&model, &shared, &aggregated(m)).expect("kept");
                let i = Method::ALL.iter().position(|x| *x == m).expect("a method");
                assert_eq!(bits(&kept), fresh[i], "{m:?}, budget {budget:?}");
            }
        }
        // A warm start: the refinement's reference simulation is the kept one.
        let first = estimate_with(&model, &shared, &aggregated(Method::Iv3)).expect("iv3");
        let warm = EstimateOptions {
            start: Some(Start::from_estimate(model.ir(), &first)),
            ..aggregated(Method::Iv3)
        };
        let kept = estimate_with(&model, &shared, &warm).expect("warm");
        let fresh = estimate_with(&model, &workers, &warm).expect("warm, fresh");
        assert_eq!(bits(&kept), bits(&fresh), "warm start, budget {budget:?}");
        assert!(kept.diagnostics.refinements >= 1, "a refined estimate");
    }
}

/// Passes over records that begin with shorter records already estimated
/// on (the study's longer and longer prefixes) take the regressor rows kept
/// over the prefix as their first rows, and the passes whose instruments
/// do not depend on θ (least squares, the delayed bootstraps) go on from
/// where they stood after the prefix, in the middle of a block:
/// every method's estimate must still be, bit for bit, the one computed
/// from scratch — for prefixes short
/// enough that a sign pattern differs, when the rows were kept over
/// other records (which must then go unused), and under budgets that keep
/// only some of what the passes offer (rows of some plans, rotations or not).
#[test]
fn rows_kept_over_a_prefix_change_no_bit() {
    use leeway_estimate::LocalPasses;
    let model = ship();
    let data = experiments(&model);
    let sources: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let workers = Workers {
        model: &model,
        experiments: &data,
    };
    let fresh = from_scratch(&workers);
    // The rows of the prefixes, as the study keeps them: all four methods.
    fn budgeted(passes: LocalPasses<'_>, budget: Option<usize>) -> LocalPasses<'_> {
        match budget {
            Some(b) => passes.with_budget(b),
            None => passes,
        }
    }
    let rows_over = |records: &[Experiment], budget: Option<usize>| {
        let sources: Vec<&dyn Source> = records.iter().map(|e| e as &dyn Source).collect();
        let passes = budgeted(
            LocalPasses::new(&model, &sources).for_several_estimates(),
            budget,
        );
        for m in Method::ALL {
            let _ = estimate_with(&model, &passes, &aggregated(m));
        }
        passes.into_prefix_rows()
    };
    for n in [40, 300] {
        let prefixes: Vec<Experiment> = data.iter().map(|e| e.truncated(n)).collect();
        // Kept over each record's prefix, and over the others' (shifted by one).
        let mut others = prefixes.clone();
        others.rotate_left(1);
        for (label, prefixes) in [("own", &prefixes), ("others", &others)] {
            // Under 1.28 MB (found by a sweep), a bootstrap that read kept
            // heading rotations over the prefix finds none kept over the
            // record: it must not go on from the prefix.
            for budget in [
                None,
                Some(60_000),
                Some(250_000),
                Some(1_000_000),
                Some(1_280_000),
            ] {
                let passes = budgeted(
                    LocalPasses::new(&model, &sources).for_several_estimates(),
                    budget,
                )
                .continuing(rows_over(prefixes, budget));
                for (m, fresh) in Method::ALL.iter().zip(&fresh) {
                    let kept = estimate_with(&model, &passes, &aggregated(*m)).expect("continued");
                    assert_eq!(
                        &bits(&kept),
                        fresh,
                        "{m:?}, prefix {n} ({label}), budget {budget:?}"
                    );
                }
            }
        }
    }
}

/// The estimates of every method on the first `n` samples of each record,
/// through one `LocalPasses` as the study runs them: the warm starts of the
/// methods that settled (with the instruments they settled on) and what
/// the passes kept, for the passes over the whole records.
fn settled_on_prefixes(
    model: &Interpreter,
    data: &[Experiment],
    n: usize,
    budget: Option<usize>,
) -> (
    Vec<Option<leeway_estimate::Start>>,
    leeway_estimate::PrefixRows,
) {
    use leeway_estimate::LocalPasses;
    use leeway_estimate::Start;
    let prefixes: Vec<Experiment> = data.iter().map(|e| e.truncated(n)).collect();
    let sources: Vec<&dyn Source> = prefixes.iter().map(|e| e as &dyn Source).collect();
    let mut passes = LocalPasses::new(model, &sources).for_several_estimates();
    if let Some(b) = budget {
        passes = passes.with_budget(b);
    }
    let starts = Method::ALL
        .iter()
        .map(|m| {
            let e = estimate_with(model, &passes, &aggregated(*m)).ok()?;
            e.diagnostics
                .converged
                .then(|| Start::from_estimate(model.ir(), &e))
        })
        .collect();
    (starts, passes.into_prefix_rows())
}

/// A warm start that carries the instruments it settled on over shorter
/// records begins on the longer ones with those instruments; the passes
/// that kept them over the prefix go on from their sums, simulation and
/// trajectory mid-record (mid-block too): every estimate must be, bit for
/// bit, the one workers that keep nothing compute with the same start —
/// where the prefix's sign pattern differs (nothing to go on from), and
/// under budgets that keep only part of what the passes offer.
#[test]
fn warm_starts_that_continue_the_prefix_instruments_change_no_bit() {
    use leeway_estimate::LocalPasses;
    let model = ship();
    let design = InputDesign::default();
    // Records long enough for IV2 and IV3 to settle on their prefixes, and
    // prefixes that end inside a block of the moment sums.
    for (records, n) in [
        (vec![(10.0, 3000, 2), (10.0, 2800, 3)], 2500),
        (vec![(10.0, 4000, 1)], 3000),
    ] {
        let data: Vec<Experiment> = records
            .iter()
            .map(|&(wind, len, seed)| {
                study::estimation_experiment(&model, &design, wind, len, seed).0
            })
            .collect();
        let sources: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
        let workers = Workers {
            model: &model,
            experiments: &data,
        };
        for budget in [None, Some(250_000), Some(0)] {
            let (starts, rows) = settled_on_prefixes(&model, &data, n, budget);
            // Least squares (index 0) settles trivially and simulates nothing.
            let refined = &starts[1..];
            assert!(
                refined[1..].iter().all(Option::is_some),
                "IV2 and IV3 settle on {n} samples"
            );
            assert!(
                refined.iter().flatten().all(|s| s
                    .instruments
                    .as_ref()
                    .is_some_and(|i| i.experiments.iter().all(|(samples, _)| *samples == n))),
                "a settled refinement carries its instruments"
            );
            assert!(starts[0].as_ref().is_none_or(|s| s.instruments.is_none()));
            let mut passes = LocalPasses::new(&model, &sources).for_several_estimates();
            if let Some(b) = budget {
                passes = passes.with_budget(b);
            }
            let passes = passes.continuing(rows);
            for (m, start) in Method::ALL.iter().zip(&starts) {
                let options = EstimateOptions {
                    start: start.clone(),
                    ..aggregated(*m)
                };
                let kept = estimate_with(&model, &passes, &options).expect("continued");
                let fresh = estimate_with(&model, &workers, &options).expect("fresh");
                assert_eq!(
                    bits(&kept),
                    bits(&fresh),
                    "{m:?}, prefix {n}, budget {budget:?}"
                );
            }
        }
    }
}

/// Beginning with the instruments a warm start settled on, rather than a
/// simulation of its θ, is a statistical no-op: the refinement reaches the
/// same fixed point within its tolerance. On one long record, IV2's and
/// IV3's estimates either way differ by a small fraction of their standard
/// errors.
#[test]
fn continued_instruments_reach_the_same_fixed_point() {
    use leeway_estimate::Start;
    let model = ship();
    let design = InputDesign::default();
    let (record, _) = study::estimation_experiment(&model, &design, 10.0, 4000, 1);
    let prefix = record.truncated(3000);
    for method in [Method::Iv2, Method::Iv3] {
        let settled = estimate(&model, &[&prefix as &dyn Source], &aggregated(method))
            .expect("prefix estimate");
        assert!(settled.diagnostics.converged, "{method:?} settles");
        let start = Start::from_estimate(model.ir(), &settled);
        assert!(
            start.instruments.is_some(),
            "{method:?} carries its instruments"
        );
        let with = |start: Start| {
            estimate(
                &model,
                &[&record as &dyn Source],
                &EstimateOptions {
                    start: Some(start),
                    ..aggregated(method)
                },
            )
            .expect("warm estimate")
        };
        let continued = with(start.clone());
        let simulated = with(Start {
            instruments: None,
            ..start
        });
        assert!(continued.diagnostics.converged && simulated.diagnostics.converged);
        for ((a, b), se) in continued
            .theta
            .iter()
            .zip(&simulated.theta)
            .zip(&continued.std_errors)
        {
            if let Some(se) = se {
                assert!(
                    (a - b).abs() <= 0.05 * se,
                    "{method:?}: {a} vs {b}, standard error {se}"
                );
            }
        }
    }
}

/// A streamed record that counts its visits of the whole record and of its
/// head apart.
struct Counted<'a>(
    Streamed<'a>,
    std::sync::atomic::AtomicUsize,
    std::sync::atomic::AtomicUsize,
);

impl Source for Counted<'_> {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn len(&self) -> usize {
        self.0.len()
    }
    fn step(&self) -> f64 {
        self.0.step()
    }
    fn visit(&self, f: &mut dyn FnMut(&leeway_model::Row)) {
        self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.0.visit(f);
    }
    fn visit_head(&self, n: usize, f: &mut dyn FnMut(&leeway_model::Row)) {
        self.2.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        // The record's own head: read no further than `n`.
        self.0.0.visit_head(n, f);
    }
}

/// The estimate from `data` streamed, and how often it visited each record
/// whole and its head.
fn counted(
    model: &Interpreter,
    data: &[Experiment],
    options: &EstimateOptions,
) -> (Estimate, Vec<usize>, Vec<usize>) {
    let counted: Vec<Counted> = data
        .iter()
        .map(|e| Counted(Streamed(e), Default::default(), Default::default()))
        .collect();
    let sources: Vec<&dyn Source> = counted.iter().map(|e| e as &dyn Source).collect();
    let estimate = estimate(model, &sources, options).expect("an estimate");
    let load = |a: &std::sync::atomic::AtomicUsize| a.load(std::sync::atomic::Ordering::Relaxed);
    let (whole, heads) = counted.iter().map(|c| (load(&c.1), load(&c.2))).unzip();
    (estimate, whole, heads)
}

#[test]
fn the_own_simulation_reads_a_streamed_record_in_the_covariance_pass() {
    let model = ship();
    let data = experiments(&model);
    let run = |options: &EstimateOptions| {
        let (estimate, visits, _) = counted(&model, &data, options);
        (estimate, visits)
    };
    for method in [Method::Iv3, Method::Ls] {
        let options = aggregated(method);
        let (with, visits) = run(&options);
        let (without, visits_without) = run(&EstimateOptions {
            own_simulation: false,
            ..options.clone()
        });
        // No visit of its own: it steps along the covariance pass's walk.
        assert_eq!(visits, visits_without, "{method:?}");
        assert!(without.diagnostics.own_simulation.is_none());
        let own = with.diagnostics.own_simulation.clone();
        assert!(
            own.as_ref().is_some_and(|o| o.mean_fit.is_some()),
            "{own:?}"
        );
        // In-memory records' free runs visit them after the covariance
        // walk: the same fits, bit for bit.
        let held: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
        let separate = estimate(&model, &held, &options).expect("in memory");
        assert_eq!(
            format!("{own:?}"),
            format!("{:?}", separate.diagnostics.own_simulation),
            "{method:?}"
        );
        let estimated = |e: &Estimate| bits(e).split(" Diagnostics").next().map(str::to_string);
        assert_eq!(estimated(&with), estimated(&without), "{method:?}");
    }
}

#[test]
fn streamed_experiments_on_several_threads_give_the_estimate_of_one() {
    let model = ship();
    let data = experiments(&model);
    let streamed: Vec<Streamed> = data.iter().map(Streamed).collect();
    let sources: Vec<&dyn Source> = streamed.iter().map(|e| e as &dyn Source).collect();
    let held: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    for method in [Method::Iv3, Method::Ls, Method::Iv1] {
        let options = aggregated(method);
        let one = estimate_with(
            &model,
            &LocalPasses::new(&model, &sources).with_threads(1),
            &options,
        )
        .expect("one thread");
        for threads in [2, 3, 8] {
            let passes = LocalPasses::new(&model, &sources).with_threads(threads);
            let many = estimate_with(&model, &passes, &options).expect("several threads");
            assert_eq!(bits(&one), bits(&many), "{method:?} on {threads} threads");
        }
        // And the in-memory records' estimate, which keeps what it computed.
        let local = estimate(&model, &held, &options).expect("in memory");
        assert_eq!(bits(&one), bits(&local), "{method:?}");
    }
}

/// Long runs of different lengths and winds, for the refinement on a subsample.
fn long_experiments(model: &Interpreter) -> Vec<Experiment> {
    runs(
        model,
        &[(10.0, 4000, 21), (6.0, 6000, 22), (14.0, 3000, 23)],
    )
}

/// Refining on a fifth of every record first reaches the fixed point of the
/// refinement over all samples — that of a refinement run to a far tighter
/// tolerance, within a hundredth of a standard error — and passes over all
/// samples only for the refinement from the subsample's estimate, never
/// for a bootstrap; in memory or streamed, and mapped over workers, the
/// same bits.
#[test]
fn refining_on_a_subsample_first_reaches_the_fixed_point_over_all_samples() {
    let model = ship();
    let data = long_experiments(&model);
    // IV1 and IV2 run away on these windy records from their bootstrap on.
    let method = Method::Iv3;
    let plain = aggregated(method);
    let sub = EstimateOptions {
        refine_subsample: Some(0.2),
        ..plain.clone()
    };
    let (full, whole_full, heads_full) = counted(&model, &data, &plain);
    let (first, whole_sub, heads_sub) = counted(&model, &data, &sub);
    let s = first.diagnostics.subsample.clone().expect("reported");
    assert!(s.used && s.why_not.is_none(), "{s:?}");
    assert_eq!(s.samples, (4000 + 6000 + 3000) / 5, "{s:?}");
    assert!(first.diagnostics.converged && full.diagnostics.converged);
    assert!(full.diagnostics.subsample.is_none());
    assert_eq!(heads_full, vec![0, 0, 0]);
    // The subsample's facts, bootstrap and refinements read the heads only.
    assert_eq!(heads_sub, vec![2 + s.refinements; 3]);
    // Over all samples: the facts, the bootstrap (or the first pass from
    // the subsample's estimate), each refinement and the covariance.
    assert_eq!(whole_full, vec![3 + full.diagnostics.refinements; 3]);
    assert_eq!(whole_sub, vec![3 + first.diagnostics.refinements; 3]);
    let tight = estimate(
        &model,
        &data.iter().map(|e| e as &dyn Source).collect::<Vec<_>>(),
        &EstimateOptions {
            tolerance: 1e-9,
            max_refinements: 30,
            ..plain.clone()
        },
    )
    .expect("a tight estimate");
    assert!(tight.diagnostics.converged);
    for (((a, b), se), name) in first
        .theta
        .iter()
        .zip(&tight.theta)
        .zip(&tight.std_errors)
        .zip(&tight.parameters)
    {
        if let Some(se) = se {
            assert!(
                (a - b).abs() <= 0.01 * se,
                "{name}: {a} vs {b}, standard error {se}"
            );
        }
    }
    // In memory (heads copied) and mapped over workers (the head in the
    // request): the streamed estimate's bits.
    let held: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let local = estimate(&model, &held, &sub).expect("in memory");
    assert_eq!(bits(&first), bits(&local), "in memory");
    let workers = Workers {
        model: &model,
        experiments: &data,
    };
    let mapped = estimate_with(&model, &workers, &sub).expect("mapped");
    assert_eq!(bits(&first), bits(&mapped), "mapped");
}

/// A subsample too short to estimate from changes nothing: the refinement
/// over all samples begins from the bootstrap, bit for bit as without one,
/// and the report says why the subsample was not used.
#[test]
fn a_subsample_that_cannot_settle_leaves_the_estimate_as_without_one() {
    let model = ship();
    let data = experiments(&model);
    let held: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let plain = aggregated(Method::Iv3);
    let without = estimate(&model, &held, &plain).expect("an estimate");
    let mut with = estimate(
        &model,
        &held,
        &EstimateOptions {
            refine_subsample: Some(0.001),
            ..plain
        },
    )
    .expect("an estimate");
    let s = with.diagnostics.subsample.take().expect("reported");
    assert!(!s.used, "{s:?}");
    let why = s.why_not.unwrap_or_default();
    assert!(why.contains("on the subsample: 24 equations"), "{why}");
    assert_eq!(bits(&with), bits(&without));
}

/// A bad value after the subsample is found by the first pass over all
/// samples, as the bootstrap finds it without a subsample: the same error.
#[test]
fn a_bad_value_past_the_subsample_is_the_error_it_is_without_one() {
    let model = ship();
    let mut data = long_experiments(&model);
    let last = data[1].len() - 5;
    data[1].states[0][last] = f64::NAN;
    let held: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let plain = aggregated(Method::Iv3);
    let without = estimate(&model, &held, &plain).expect_err("a bad value");
    let with = estimate(
        &model,
        &held,
        &EstimateOptions {
            refine_subsample: Some(0.2),
            ..plain
        },
    )
    .expect_err("a bad value");
    assert_eq!(with.code, "non-finite-data", "{with:?}");
    assert_eq!(format!("{with:?}"), format!("{without:?}"));
}

/// Workers that hold their experiments across passes and keep each one's
/// instrument simulations between them, as `leeway.dask`'s do.
struct KeepingWorkers<'a> {
    model: &'a dyn Model,
    experiments: &'a [Experiment],
    kept: Vec<std::sync::Mutex<Option<leeway_estimate::KeptSimulations>>>,
}

impl Passes for KeepingWorkers<'_> {
    fn facts(&self, request: &FactsRequest) -> Result<Vec<ExperimentFacts>, EstimateError> {
        let runner = PassRunner::new(self.model);
        Ok(self
            .experiments
            .iter()
            .map(|e| runner.facts(e, request))
            .collect())
    }

    fn pass(&self, request: &PassRequest) -> Result<Vec<PassSummary>, EstimateError> {
        let request: PassRequest = decode(&encode(request)).expect("request");
        let answers: Vec<Vec<u8>> = (0..self.experiments.len())
            .into_par_iter()
            .map(|i| {
                let runner = PassRunner::new(self.model);
                let mut kept = self.kept[i].lock().expect("no pass panicked");
                let e = Streamed(&self.experiments[i]);
                encode(&runner.pass_with_kept(&e, i, &request, kept.as_mut()))
            })
            .collect();
        answers.iter().map(|b| decode(b)).collect()
    }
}

/// A refinement's next pass reads its reference simulation — the previous
/// pass's instruments — from what that pass kept, and the covariance pass
/// its instruments, instead of stepping them again: for streamed records
/// (which keep their instrument simulations only) and in-memory ones, on
/// one thread or several. The same bits as passes that keep nothing, with
/// one simulation over every record saved per refinement — and where a
/// refinement diverges (IV1 here, whose best iterate is then an earlier
/// one), the same bits still.
#[test]
fn kept_instrument_simulations_are_read_not_stepped_again() {
    let ship = ship();
    let data = experiments(&ship);
    let streamed: Vec<Streamed> = data.iter().map(Streamed).collect();
    let streamed: Vec<&dyn Source> = streamed.iter().map(|e| e as &dyn Source).collect();
    let held: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    // Steps of one simulation over every record (from its first sample).
    let one_simulation: usize = data.iter().map(|e| e.len() - 1).sum();
    for method in [Method::Iv3, Method::Iv1] {
        let options = aggregated(method);
        let run = |sources: &[&dyn Source], threads: usize, budget: Option<usize>| {
            let model = Counting::new(&ship, true);
            let passes = LocalPasses::new(&model, sources).with_threads(threads);
            let passes = match budget {
                Some(bytes) => passes.with_budget(bytes),
                None => passes,
            };
            let estimate = estimate_with(&model, &passes, &options).expect("an estimate");
            (estimate, model.steps())
        };
        let (nothing_kept, _) = run(&streamed, 1, Some(0));
        let refinements = nothing_kept.diagnostics.refinements;
        let diverged = nothing_kept.warnings.iter().any(|w| w.contains("diverges"));
        assert_eq!(
            diverged,
            method == Method::Iv1,
            "{:?}",
            nothing_kept.warnings
        );
        assert!(refinements >= 2 || diverged, "{method:?}: {refinements}");
        // Workers that keep them, beside them.
        let mapped = |keeps: bool| {
            let model = Counting::new(&ship, true);
            let n_out = ship.ir().states.len();
            let kept = data
                .iter()
                .map(|e| {
                    let bytes = leeway_estimate::KeptSimulations::bytes(e.len(), n_out);
                    std::sync::Mutex::new(
                        keeps.then(|| leeway_estimate::KeptSimulations::new(bytes)),
                    )
                })
                .collect();
            let workers = KeepingWorkers {
                model: &model,
                experiments: &data,
                kept,
            };
            let estimate = estimate_with(&model, &workers, &options).expect("mapped");
            (estimate, model.steps())
        };
        let ((plain, all_mapped), (kept_mapped, mapped_steps)) = (mapped(false), mapped(true));
        assert_eq!(bits(&plain), bits(&nothing_kept), "{method:?} mapped");
        assert_eq!(bits(&kept_mapped), bits(&nothing_kept), "{method:?} mapped");
        assert!(mapped_steps < all_mapped, "{method:?} mapped");
        if !diverged {
            assert_eq!(all_mapped - mapped_steps, refinements * one_simulation);
        }
        for (sources, threads) in [(&streamed, 1), (&streamed, 3), (&held, 1)] {
            // Records walked side by side do not stop at another's divergence.
            let (_, all_steps) = run(sources, threads, Some(0));
            let (kept, steps) = run(sources, threads, None);
            assert_eq!(bits(&kept), bits(&nothing_kept), "{method:?} on {threads}");
            // Refinements after the first read their reference; the
            // covariance pass reads its instruments.
            if diverged {
                assert!(steps < all_steps, "{method:?} on {threads}");
            } else {
                assert_eq!(
                    all_steps - steps,
                    refinements * one_simulation,
                    "{method:?} on {threads}"
                );
            }
        }
    }
}

/// The interpreter's evaluators of some slots, taking blocks of samples
/// (as the interpreter does) or not, counting the blocks they evaluate.
struct SlotsByBlock {
    inner: Box<dyn leeway_model::model::SlotRegressors>,
    blocks: bool,
    evaluated: std::sync::Arc<std::sync::atomic::AtomicUsize>,
}

impl leeway_model::model::SlotRegressors for SlotsByBlock {
    fn update(&self, sig: &leeway_model::Signals, signs: &[f64], out: &mut [f64]) {
        self.inner.update(sig, signs, out);
    }
    fn evaluates_blocks(&self) -> bool {
        self.blocks
    }
    fn update_block(
        &self,
        samples: &[leeway_model::Signals],
        signs: &[f64],
        n_signs: usize,
        out: &mut [f64],
    ) {
        self.evaluated
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.inner.update_block(samples, signs, n_signs, out);
    }
}

/// The ship, counting its simulation steps and the blocks of equations its
/// walks evaluate — a block at a time (as the interpreter does) or, where
/// its slot evaluators say they take no blocks, one by one.
struct Counting<'a> {
    model: &'a Interpreter,
    blocks: bool,
    steps: std::sync::atomic::AtomicUsize,
    evaluated: std::sync::Arc<std::sync::atomic::AtomicUsize>,
}

impl<'a> Counting<'a> {
    fn new(model: &'a Interpreter, blocks: bool) -> Counting<'a> {
        Counting {
            model,
            blocks,
            steps: Default::default(),
            evaluated: Default::default(),
        }
    }
    fn steps(&self) -> usize {
        self.steps.load(std::sync::atomic::Ordering::Relaxed)
    }
    fn blocks_evaluated(&self) -> usize {
        self.evaluated.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl Model for Counting<'_> {
    fn ir(&self) -> &leeway_structure::ir::Ir {
        self.model.ir()
    }
    fn basic(&self, sig: &leeway_model::Signals, out: &mut [f64]) {
        self.model.basic(sig, out);
    }
    fn augmented(&self, sig: &leeway_model::Signals, signs: &[f64], out: &mut [f64]) {
        self.model.augmented(sig, signs, out);
    }
    fn measured(&self, sig: &leeway_model::Signals, signs: &[f64], out: &mut [f64]) {
        self.model.measured(sig, signs, out);
    }
    fn rhs(&self, theta: &[f64], sig: &leeway_model::Signals, out: &mut [f64]) {
        self.model.rhs(theta, sig, out);
    }
    fn regressors_update(
        &self,
        kind: leeway_structure::ir::PredictorKind,
        sig: &leeway_model::Signals,
        signs: &[f64],
        out: &mut [f64],
    ) {
        self.model.regressors_update(kind, sig, signs, out);
    }
    fn regressor_slots(
        &self,
        kind: leeway_structure::ir::PredictorKind,
        wanted: &[bool],
    ) -> Option<Box<dyn leeway_model::model::SlotRegressors>> {
        let inner = self.model.regressor_slots(kind, wanted)?;
        Some(Box::new(SlotsByBlock {
            inner,
            blocks: self.blocks,
            evaluated: std::sync::Arc::clone(&self.evaluated),
        }))
    }
    fn step(
        &self,
        theta: &[f64],
        h: f64,
        sig: &leeway_model::Signals,
        f: &mut [f64],
        next: &mut [f64],
    ) {
        self.steps
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.model.step(theta, h, sig, f, next);
    }
}

/// The ship holding its heading in a strong wind: the relative wind keeps
/// its sign, so IV3's measured-medium columns take fixed-sign instruments.
fn holding_course(model: &Interpreter, n: usize, seed: u64) -> Experiment {
    let inputs: Vec<Vec<f64>> = study::estimation_input(&InputDesign::default(), n, seed)
        .into_iter()
        .map(|u| vec![u[0], u[1], 0.0])
        .collect();
    let system = study::true_system(20.0);
    let x0 = [0.5, 0.0, 0.0];
    leeway_scenarios::synth::experiment(model, &system, "course", &x0, 0.3, &inputs, seed).0
}

/// Equations evaluated a block at a time (the interpreter's evaluators,
/// read by the sinks slot-major) give every method the bits of equations
/// evaluated one by one: streamed records of lengths that leave a shorter
/// last block, in memory keeping nothing, on one thread or several.
#[test]
fn equations_evaluated_by_blocks_give_the_bits_of_one_by_one() {
    let ship = ship();
    // Lengths that are no multiple of the block: a shorter block ends each.
    let mut data = runs(&ship, &[(10.0, 701, 31), (6.0, 1290, 32), (14.0, 37, 33)]);
    data.push(holding_course(&ship, 900, 34));
    let streamed: Vec<Streamed> = data.iter().map(Streamed).collect();
    let streamed: Vec<&dyn Source> = streamed.iter().map(|e| e as &dyn Source).collect();
    let held: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    for method in [Method::Ls, Method::Iv1, Method::Iv2, Method::Iv3] {
        let options = aggregated(method);
        let run = |blocks: bool, sources: &[&dyn Source], threads: usize| {
            let model = Counting::new(&ship, blocks);
            let passes = LocalPasses::new(&model, sources)
                .with_threads(threads)
                .with_budget(0);
            let estimate = estimate_with(&model, &passes, &options).expect("an estimate");
            (bits(&estimate), model.blocks_evaluated())
        };
        let (one_by_one, none) = run(false, &streamed, 1);
        assert_eq!(none, 0, "{method:?}");
        for (sources, threads) in [(&streamed, 1), (&streamed, 3), (&held, 2)] {
            let (by_blocks, evaluated) = run(true, sources, threads);
            assert!(evaluated > 0, "{method:?}: no block evaluated");
            assert_eq!(by_blocks, one_by_one, "{method:?} on {threads} threads");
        }
    }
    // A bad value inside a block (and one in the block after) is the
    // error it is one by one: the same sample, the same regressor.
    let mut bad = data;
    bad[1].states[2][300] = f64::NAN;
    bad[1].states[0][333] = 1e300;
    let streamed: Vec<Streamed> = bad.iter().map(Streamed).collect();
    let streamed: Vec<&dyn Source> = streamed.iter().map(|e| e as &dyn Source).collect();
    let error = |blocks: bool| {
        let model = Counting::new(&ship, blocks);
        let e = estimate(&model, &streamed, &aggregated(Method::Iv3)).expect_err("a bad value");
        (format!("{e:?}"), model.blocks_evaluated())
    };
    let ((one_by_one, _), (by_blocks, evaluated)) = (error(false), error(true));
    assert!(one_by_one.contains("non-finite-data"), "{one_by_one}");
    assert!(evaluated > 0);
    assert_eq!(by_blocks, one_by_one);
}
