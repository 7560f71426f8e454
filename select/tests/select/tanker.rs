//! The tanker zigzags (`leeway_scenarios::zigzag`, a true system richer
//! than any model written here): selection among 40 candidate terms on the
//! four noisy training runs, then the chosen model's free-run fit on the six
//! held-out runs beside the hand-written model of docs/real-data.md
//! (`examples/models/tanker.som`), both estimated the same way.

use leeway_estimate::estimate;
use leeway_model::simulate::{Disturbances, fits, simulate};
use leeway_model::{Experiment, Interpreter, Model, Source};
use leeway_scenarios::zigzag;
use leeway_select::{SelectOptions, Selection, select};

/// The candidate model: the hand-written model's 17 terms and 23
/// plausible extras, every one a candidate (the file says which).
pub const CANDIDATE_TANKER: &str = include_str!("../models/candidate-tanker.som");

/// The hand-written model of docs/real-data.md.
fn hand_written() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/models/tanker.som");
    std::fs::read_to_string(path).expect("tanker.som")
}

fn interpreter(source: &str) -> Interpreter {
    let c = leeway_structure::compile(source, &Default::default());
    Interpreter::new(c.ir.unwrap_or_else(|| panic!("the model compiles: {:?}", c.diagnostics)))
}

fn experiments(model: &Interpreter, runs: &[zigzag::Run]) -> Vec<Experiment> {
    runs.iter()
        .map(|r| r.experiment(model.ir()).expect("run matches the model"))
        .collect()
}

/// Mean free-run fit per output (`100·(1 − ‖y − ŷ‖/‖y − ȳ‖)`) over the
/// held-out runs, as `leeway validate` prints it (a run that diverges
/// counts −1000).
fn validation_fit(model: &Interpreter, theta: &[f64], runs: &[zigzag::Run]) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for e in experiments(model, runs) {
        let sim = simulate(model, theta, &e, Disturbances::None);
        let f = fits(&e, &sim);
        for o in 0..3 {
            sum[o] += if f[o].is_finite() { f[o] } else { -1000.0 };
        }
    }
    sum.map(|s| s / runs.len() as f64)
}

/// The selection on the training runs (each left out in turn for the
/// free-run criterion) and the held-out fits of the chosen and the
/// hand-written model, both estimated with `estimate`'s defaults (IV3).
fn compare(options: &SelectOptions) -> (Selection, [f64; 3], [f64; 3]) {
    let campaign = zigzag::campaign(&zigzag::CampaignOptions::default());
    let candidate = interpreter(CANDIDATE_TANKER);
    let train = experiments(&candidate, &campaign.train);
    let selection = select(CANDIDATE_TANKER, &train, &[], options)
        .unwrap_or_else(|e| panic!("{}: {}", e.message, e.hint));
    let chosen = interpreter(&selection.chosen_source);
    let chosen_fit = validation_fit(&chosen, &selection.estimate.theta, &campaign.validation);
    let hand = interpreter(&hand_written());
    let data = experiments(&hand, &campaign.train);
    let sources: Vec<&dyn Source> = data.iter().map(|e| e as &dyn Source).collect();
    let est = estimate(&hand, &sources, &options.estimate).expect("the hand-written model");
    let hand_fit = validation_fit(&hand, &est.theta, &campaign.validation);
    (selection, chosen_fit, hand_fit)
}

fn mean(f: [f64; 3]) -> f64 {
    f.iter().sum::<f64>() / 3.0
}

/// The path, one line a step, for the note.
fn print(selection: &Selection, chosen: [f64; 3], hand: [f64; 3]) {
    eprintln!(
        "kept {} of {}: {:?}\ndropped {:?}\nheld-out fit chosen {chosen:.1?} (mean {:.1}) hand-written {hand:.1?} (mean {:.1})",
        selection.kept.len(),
        selection.candidates.len(),
        selection.kept,
        selection.dropped,
        mean(chosen),
        mean(hand)
    );
    for s in &selection.steps {
        eprintln!(
            "{:>6} {:<22} wald {:>9} p {:>9.2e} kept {:>2} J {:>8.2} df {:>2} score {:>8.2} criterion {}",
            s.dropped.clone().unwrap_or_default(),
            s.reason,
            s.wald.map_or("-".into(), |w| format!("{w:.3}")),
            s.p_value.unwrap_or(f64::NAN),
            s.size,
            s.j,
            s.j_df,
            s.score,
            s.criterion.map_or("-".into(), |c| format!("{c:.4}"))
        );
    }
}

/// With the default options, the selected model free-runs on the six
/// held-out runs at least as well as the hand-written one in every output
/// (13 of 40 kept: 92.3 / 97.2 / 95.7 against 88.7 / 95.7 / 95.4). The
/// held-out criterion is sharp here (the best model's is 0.14), so the
/// guard's slack is small: with a slack of a fixed 50 % of the best (last
/// rule, 10 kept) the selection fell short (83.0 / 92.3 / 90.8). See
/// `tanker_tolerance_sweep` and the note of #50.
#[test]
fn the_selected_tanker_validates_at_least_as_well_as_the_hand_written_one() {
    let options = SelectOptions::default();
    let (selection, chosen, hand) = compare(&options);
    print(&selection, chosen, hand);
    assert_eq!(selection.candidates.len(), 40);
    assert!(
        selection.kept.len() < 20,
        "a selection, not the full set: {:?}",
        selection.kept
    );
    for o in 0..3 {
        assert!(
            chosen[o] >= hand[o],
            "output {o}: chosen {chosen:?} vs hand-written {hand:?}"
        );
    }
}

/// The held-out fits against the tolerance (and `LAGS`, default 1), for the note:
/// `cargo test -p leeway-select --test select tanker_tolerance_sweep -- --ignored --nocapture`
#[test]
#[ignore]
fn tanker_tolerance_sweep() {
    let lags = std::env::var("LAGS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    for tolerance in [0.0, 0.25, 0.5, 1.0, 2.0, 4.0] {
        let mut options = SelectOptions {
            tolerance,
            ..SelectOptions::default()
        };
        options.estimate.lags = lags;
        let (selection, chosen, hand) = compare(&options);
        println!(
            "| {tolerance} | {lags} | {} | {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} |",
            selection.kept.len(),
            chosen[0],
            chosen[1],
            chosen[2],
            hand[0],
            hand[1],
            hand[2]
        );
        if tolerance == SelectOptions::default().tolerance {
            print(&selection, chosen, hand);
        }
    }
}

/// The hand-written tanker with its sway and yaw terms as candidates, and
/// three exchangeable ones: `?Y_vv2*|v|*v` (a second candidate for the
/// regressor of `?Y_vv`), `?N_ur2*u*r` (a candidate duplicating the required
/// `N_ur`) and `?N_d2*delta*u` (a candidate for `?N_ud`'s regressor, declared first).
const EXCHANGEABLE_TANKER: &str = "model ExchangeableTanker {
    state u, v, r
    input delta
    der u = X_0 + X_uu*u*|u| + X_vr*v*r + X_dd*delta*delta + X_rr*r*r
    der v = Y_0 + Y_uv*u*v + Y_ur*u*r + ?Y_ud*u*delta + ?Y_vv*v*|v| + ?Y_vv2*|v|*v + ?Y_rr*r*|r|
    der r = N_0 + N_uv*u*v + N_ur*u*r + ?N_d2*delta*u + ?N_ud*u*delta + ?N_vv*v*|v| + ?N_rr*r*|r|
          + ?N_ur2*u*r
    nominal { X_0 = 0.01, X_uu = -0.01, X_vr = 1.0, X_dd = -0.05, X_rr = 0.3,
              Y_uv = -0.08, Y_ur = -0.4, Y_ud = 0.02, Y_vv = -0.1,
              N_uv = -0.04, N_ur = -0.2, N_ud = -0.02, N_vv = 0.02, N_rr = -1.0 }
}
";

/// Selection on data respects identifiability: every exchangeable
/// candidate is dropped before the path (the term it can stand for is the
/// one kept), no two exchangeable terms are ever kept together, and the
/// chosen model is identifiable with nothing `check` calls unidentifiable.
#[test]
fn selection_on_data_drops_exchangeable_candidates_and_never_keeps_two() {
    let campaign = zigzag::campaign(&zigzag::CampaignOptions::default());
    let model = interpreter(EXCHANGEABLE_TANKER);
    assert!(
        !model.ir().report.unidentifiable.is_empty(),
        "the candidate model is not identifiable as written"
    );
    let pairs = leeway_select::exchangeable(model.ir(), &candidate_names(EXCHANGEABLE_TANKER));
    let expected = [("Y_vv2", "Y_vv"), ("N_ud", "N_d2"), ("N_ur2", "N_ur")];
    let named: Vec<(&str, &str)> = pairs
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    assert_eq!(named, expected);
    let train = experiments(&model, &campaign.train);
    let selection = select(EXCHANGEABLE_TANKER, &train, &[], &SelectOptions::default())
        .unwrap_or_else(|e| panic!("{}: {}", e.message, e.hint));
    let pre: Vec<(&str, &str)> = selection
        .steps
        .iter()
        .filter(|s| s.reason.starts_with("exchangeable"))
        .map(|s| (s.dropped.as_deref().unwrap_or("-"), s.reason.as_str()))
        .collect();
    eprintln!("exchangeable steps {pre:?}; kept {:?}", selection.kept);
    for (dropped, with) in &pairs {
        assert!(
            pre.contains(&(
                dropped.as_str(),
                format!("exchangeable with {with}").as_str()
            )),
            "{dropped} not dropped as exchangeable with {with}: {pre:?}"
        );
        assert!(!selection.kept.contains(dropped), "{dropped} kept");
        assert!(
            !selection.estimate.parameters.contains(dropped),
            "{dropped} estimated"
        );
    }
    let chosen = leeway_structure::compile(&selection.chosen_source, &Default::default());
    let ir = chosen.ir.expect("the chosen model compiles");
    assert!(
        ir.report.identifiable && ir.report.unidentifiable.is_empty(),
        "{:?}",
        ir.report.unidentifiable
    );
}

fn candidate_names(source: &str) -> Vec<String> {
    let c = leeway_structure::compile(source, &Default::default());
    let ir = c.ir.expect("compiles");
    let names = ir.parameters.iter().map(|p| p.name.clone()).collect();
    let (syntax, _) = leeway_structure::grammar::parse(source);
    leeway_select::CandidateModel::read(source, &syntax.expect("parses"), &names)
        .expect("candidates")
        .candidates
}
