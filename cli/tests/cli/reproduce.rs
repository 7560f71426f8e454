//! End-to-end tests of `leeway reproduce`: the built binary runs the paper's
//! study with few runs (fixed seeds, the generated ship model) and the tests
//! check results.json against the contract of docs/json.md, the figures, that the
//! thread count changes no figure, the input design's margins, and the
//! paper's claims as they actually come out of this design — (b), (c) and
//! (d) hold; (a) does not at N ≥ 1000, and LS is ahead on parameter error
//! only far below it (N = 150) — with margins measured on these seeds.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// A scratch directory, removed when dropped; under cargo's target tmp
/// directory, so that one a static keeps (the shared study's) is not left in
/// the system's temporary directory.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("leeway-reproduce-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        Scratch(dir)
    }
    fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `leeway reproduce ARGS --out DIR`.
fn reproduce(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_leeway"))
        .arg("reproduce")
        .args(args)
        .arg("--out")
        .arg(dir)
        .env_remove("NO_COLOR")
        .output()
        .expect("run leeway")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn succeeded(o: &Output) {
    assert_eq!(o.status.code(), Some(0), "{}\n{}", stdout(o), stderr(o));
}

/// One study kept for every test that reads it.
struct Study {
    _dir: Scratch,
    out: Output,
    text: String,
    json: Value,
    dir: PathBuf,
}

/// The default seed, 12 runs, N = 1000 and 5000, both cases, two threads:
/// the first 12 runs of the full study (a run's seed does not depend on
/// how many runs there are).
const MAIN: [&str; 6] = ["--runs", "12", "--n", "1000,5000", "--threads", "2"];

fn main_study() -> &'static Study {
    static STUDY: OnceLock<Study> = OnceLock::new();
    STUDY.get_or_init(|| {
        let dir = Scratch::new("main");
        let out = reproduce(&dir.0, &MAIN);
        succeeded(&out);
        let text = std::fs::read_to_string(dir.path("results.json"))
            .unwrap_or_else(|e| panic!("results.json: {e}"));
        let json = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"));
        Study {
            dir: dir.0.clone(),
            _dir: dir,
            out,
            text,
            json,
        }
    })
}

const ESTIMATORS: [&str; 4] = ["LS", "IV1", "IV2", "IV3"];
const OUTPUTS: [&str; 3] = ["surge", "sway", "yaw"];

/// A number or null (a non-finite figure).
fn number_or_null(v: &Value) -> bool {
    v.is_number() || v.is_null()
}

fn f(v: &Value) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("expected a number, found {v}"))
}

fn estimator<'a>(json: &'a Value, case: &str, est: &str) -> &'a Value {
    &json["cases"][case]["estimators"][est]
}

fn fit(json: &Value, case: &str, est: &str, output: &str, ni: usize) -> f64 {
    f(&estimator(json, case, est)["fit_mean"][output][ni])
}

fn claim<'a>(json: &'a Value, id: &str) -> &'a Value {
    json["claims"]
        .as_array()
        .and_then(|cs| cs.iter().find(|c| c["id"] == id))
        .unwrap_or_else(|| panic!("claim ({id}) missing"))
}

#[test]
fn results_json_follows_the_contract() {
    let s = main_study();
    let j = &s.json;
    assert_eq!(j["runs"], 12);
    assert_eq!(j["seed"], 2024);
    assert!(f(&j["seconds"]) >= 0.0);
    assert_eq!(j["threads"], 2);
    let cases = j["cases"].as_object().expect("cases");
    assert_eq!(
        cases.keys().collect::<Vec<_>>(),
        ["high", "low"],
        "both cases"
    );
    for (name, wind) in [("low", 1.0), ("high", 10.0)] {
        let case = &j["cases"][name];
        assert_eq!(f(&case["wind"]), wind);
        assert_eq!(case["N"], serde_json::json!([1000, 5000]));
        let ests = case["estimators"].as_object().expect("estimators");
        assert_eq!(ests.len(), 4);
        for est in ESTIMATORS {
            let e = &case["estimators"][est];
            for field in ["fit_mean", "fit_std", "fit_median"] {
                for o in OUTPUTS {
                    let a = e[field][o]
                        .as_array()
                        .unwrap_or_else(|| panic!("{name} {est} {field} {o}"));
                    assert_eq!(a.len(), 2, "{name} {est} {field} {o} aligned with N");
                    assert!(a.iter().all(number_or_null));
                }
                assert_eq!(e[field].as_object().map(|m| m.len()), Some(3));
            }
            for field in [
                "param_error",
                "param_error_median",
                "param_error_median_all",
            ] {
                let a = e[field].as_array().expect(field);
                assert_eq!(a.len(), 2);
                assert!(a.iter().all(number_or_null));
            }
            for field in ["diverged", "estimated"] {
                let a = e[field].as_array().expect(field);
                assert_eq!(a.len(), 2);
                assert!(a.iter().all(|v| v.as_u64().is_some_and(|d| d <= 12)));
            }
        }
    }
    let claims = j["claims"].as_array().expect("claims");
    let ids: Vec<&str> = claims.iter().filter_map(|c| c["id"].as_str()).collect();
    assert_eq!(ids, ["a", "b", "c", "d"]);
    for c in claims {
        for field in ["statement", "criterion", "evidence"] {
            assert!(c[field].as_str().is_some_and(|t| !t.is_empty()), "{c}");
        }
        assert!(c["holds"].is_boolean(), "{c}");
    }
    assert_eq!(j["config"]["N"], serde_json::json!([1000, 5000]));
    assert_eq!(j["config"]["refined_iv"], "leeway");
    assert_eq!(j["config"]["model"], "examples/models/ship.som");
    assert_eq!(f(&j["config"]["theta0"]["X_vr"]), 1.0);
    assert_eq!(f(&j["input_design"]["check"]["cases"]["low"]["wind"]), 1.0);
    // Non-finite numbers would be `null`; the writer never emits NaN tokens.
    assert!(!s.text.contains("NaN") && !s.text.contains("Infinity"));
}

#[test]
fn stdout_has_a_table_per_case_the_design_and_the_claims() {
    let s = main_study();
    let text = stdout(&s.out);
    for needle in [
        "low wind (w̄ = 1 m/s",
        "high wind (w̄ = 10 m/s",
        "estimator  N",
        "Input design",
        "water.u",
        "air.v",
        "The paper's claims",
        "(a) LS fits best at the smallest N",
        "investigation:",
        "results.json",
    ] {
        assert!(text.contains(needle), "`{needle}` missing from\n{text}");
    }
    // One row per estimator and N in each case.
    for est in ESTIMATORS {
        let rows = text
            .lines()
            .filter(|l| l.trim_start().starts_with(&format!("{est} ")))
            .count();
        assert_eq!(rows, 4, "{est}: 2 N × 2 cases");
    }
    // The LS row at N = 1000 of the low case shows the JSON's mean fit.
    let ls = fit(&s.json, "low", "LS", "surge", 0);
    assert!(text.contains(&format!("{ls:.1} ±")), "{text}");
    // Non-terminal stderr: no progress bar, no errors.
    assert!(stderr(&s.out).is_empty(), "{}", stderr(&s.out));
}

#[test]
fn every_figure_is_written_as_svg_and_png() {
    let s = main_study();
    for (name, labels) in [
        (
            "fit-low",
            &["surge u (m/s)", "IV3", "fit (%)", "N (samples"][..],
        ),
        ("fit-high", &["yaw rate r (rad/s)", "LS", "not shown"][..]),
        ("trajectory", &["east (m)", "north (m)", "first 300 s"][..]),
        (
            "validation-low",
            &["true (undisturbed)", "time (s)", "IV2"][..],
        ),
        ("validation-high", &["sway v (m/s)", "fit (%)"][..]),
    ] {
        let svg = std::fs::read_to_string(s.dir.join(format!("{name}.svg")))
            .unwrap_or_else(|e| panic!("{name}.svg: {e}"));
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{name}"
        );
        assert!(svg.contains("<text"), "{name}.svg has no text");
        for label in labels {
            assert!(svg.contains(label), "`{label}` missing from {name}.svg");
        }
        let png = std::fs::read(s.dir.join(format!("{name}.png")))
            .unwrap_or_else(|e| panic!("{name}.png: {e}"));
        assert!(png.len() > 10_000, "{name}.png is {} bytes", png.len());
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "{name}.png header");
    }
    let listed = stdout(&s.out);
    assert!(listed.contains("fit-low.svg") && listed.contains("validation-high.png"));
}

/// The document without the fields that legitimately vary between runs.
fn figures_only(text: &str) -> String {
    text.lines()
        .filter(|l| !l.starts_with("  \"seconds\":") && !l.starts_with("  \"threads\":"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn the_thread_count_changes_no_figure() {
    let s = main_study();
    let dir = Scratch::new("one-thread");
    let mut args = MAIN;
    args[5] = "1";
    let one = reproduce(&dir.0, &args);
    succeeded(&one);
    let text = std::fs::read_to_string(dir.path("results.json")).unwrap_or_default();
    let one_json: Value = serde_json::from_str(&text).unwrap_or_default();
    assert_eq!(one_json["threads"], 1);
    // Every number, written with the shortest representation that reads
    // back to the same bits: equal text is bit-identical figures.
    assert_eq!(figures_only(&text), figures_only(&s.text));
    let strip = |t: &str| {
        t.lines()
            .filter(|l| !l.starts_with("study:") && !l.starts_with("wrote "))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(strip(&stdout(&one)), strip(&stdout(&s.out)));
}

#[test]
fn the_design_keeps_the_current_signs_and_the_wind_signs_only_at_low_wind() {
    let j = &main_study().json;
    let check = &j["input_design"]["check"];
    assert_eq!(check["experiments"], 12);
    assert_eq!(check["samples"], 5000);
    for case in ["low", "high"] {
        let c = &check["cases"][case];
        // Water-relative surge and sway positive in every sample of every run.
        assert_eq!(c["water_positive"], true, "{case}");
        for arg in ["water.u", "water.v"] {
            assert!(
                f(&c["arguments"][arg]["min"]) > 0.5,
                "{case} {arg}: {}",
                c["arguments"][arg]
            );
        }
        // The turn never stops on average: every run's mean yaw rate is
        // well above zero, and the excitation dwarfs the noise (std 0.014).
        assert!(f(&c["yaw_rate_run_means"]["min"]) > 0.1, "{case}");
        assert!(f(&c["yaw_rate"]["std"]) > 5.0 * f(&check["yaw_rate_noise_std"]));
    }
    let low = &check["cases"]["low"];
    assert_eq!(low["air_positive"], true);
    assert!(
        f(&low["arguments"]["air.v"]["min"]) > 0.3,
        "{}",
        low["arguments"]["air.v"]
    );
    let high = &check["cases"]["high"];
    assert_eq!(high["air_positive"], false);
    for arg in ["air.u", "air.v"] {
        let frac = f(&high["arguments"][arg]["negative_fraction"]);
        assert!((0.2..0.8).contains(&frac), "high {arg}: {frac}");
    }
    // The validation input steps the thrust: surge varies (the fit's normaliser).
    assert!(f(&check["validation_std"]["u"]) > 0.3);
}

#[test]
fn the_claims_come_out_as_measured() {
    let j = &main_study().json;
    // Figures measured on these seeds (12 runs; IV2/IV3 at N = 5000, low
    // wind: 90.9/94.4/97.6 and 90.9/94.2/97.5; high wind: 85.4/92.2/97.6 and
    // 91.4/95.9/97.9). The margins below are several points inside them.
    //
    // (b) low wind: IV2 ≈ IV3 at the largest N.
    assert_eq!(claim(j, "b")["holds"], true, "{}", claim(j, "b"));
    for o in OUTPUTS {
        let gap = (fit(j, "low", "IV2", o, 1) - fit(j, "low", "IV3", o, 1)).abs();
        assert!(gap < 1.0, "low wind {o}: |IV2 − IV3| = {gap}");
    }
    // (c) is a few fit points (3.3 in surge over the full study): too small
    // for 12 runs; it is tested on paired runs in
    // `high_wind_degrades_iv2_most_in_surge_on_paired_runs`. Here only that
    // IV3 stays good at high wind.
    for o in OUTPUTS {
        assert!(fit(j, "high", "IV3", o, 1) > 85.0, "IV3 {o} at high wind");
    }
    // (d) IV1 fits poorly: far below IV3 in surge and sway everywhere.
    assert_eq!(claim(j, "d")["holds"], true, "{}", claim(j, "d"));
    for case in ["low", "high"] {
        for ni in 0..2 {
            for o in ["surge", "sway"] {
                let gap = fit(j, case, "IV3", o, ni) - fit(j, case, "IV1", o, ni);
                assert!(gap > 30.0, "{case} N#{ni} {o}: IV3 − IV1 = {gap}");
            }
        }
    }
    // (a) does not hold at N ≥ 1000: LS's errors-in-variables bias (the
    // velocity noise enters target and regressors) already exceeds the IV
    // estimators' small-sample variance at N = 1000. IV2 and IV3 beat LS
    // in every output, and IV3's parameter error is far below LS's.
    assert_eq!(claim(j, "a")["holds"], false, "{}", claim(j, "a"));
    for case in ["low", "high"] {
        for est in ["IV2", "IV3"] {
            for o in OUTPUTS {
                let gap = fit(j, case, est, o, 0) - fit(j, case, "LS", o, 0);
                assert!(gap > 15.0, "{case} N = 1000 {o}: {est} − LS = {gap}");
            }
        }
        let ls = &estimator(j, case, "LS")["param_error_median_all"];
        let iv3 = &estimator(j, case, "IV3")["param_error_median_all"];
        assert!(
            f(&ls[0]) > 3.0 * f(&iv3[0]),
            "{case} N = 1000: LS {ls} IV3 {iv3}"
        );
        // LS is biased: more data does not bring its error down much.
        assert!(f(&ls[1]) > 0.5, "{case}: LS error at N = 5000 {ls}");
        assert!(f(&iv3[1]) < 0.1, "{case}: IV3 error at N = 5000 {iv3}");
        assert_eq!(
            j["ls_parameter_error_below_iv3"][case],
            serde_json::json!([])
        );
    }
}

#[test]
fn least_squares_is_ahead_only_far_below_n_1000() {
    // N = 150: the IV estimators diverge in most runs and LS's median
    // parameter error over every estimate is far below IV3's (measured:
    // LS 3.9 and 2.5, IV3 11.0 and 6.0, low and high wind; IV3 diverged in
    // 10 and 9 of 12 runs). Claim (a)'s breakpoint exists, between N = 200
    // and 300 with these instruments.
    let dir = Scratch::new("small");
    let o = reproduce(&dir.0, &["--runs", "12", "--n", "150", "--threads", "2"]);
    succeeded(&o);
    let text = std::fs::read_to_string(dir.path("results.json")).unwrap_or_default();
    let j: Value = serde_json::from_str(&text).unwrap_or_default();
    for case in ["low", "high"] {
        let ls = f(&estimator(&j, case, "LS")["param_error_median_all"][0]);
        let iv3 = f(&estimator(&j, case, "IV3")["param_error_median_all"][0]);
        assert!(2.0 * ls < iv3, "{case}: LS {ls} vs IV3 {iv3}");
        let div = |est: &str| {
            estimator(&j, case, est)["diverged"][0]
                .as_u64()
                .unwrap_or(0)
        };
        assert!(
            div("IV3") >= 6 && div("IV3") > div("LS"),
            "{case}: diverged IV3 {} LS {}",
            div("IV3"),
            div("LS")
        );
        assert_eq!(
            j["ls_parameter_error_below_iv3"][case],
            serde_json::json!([150])
        );
    }
    assert!(stdout(&o).contains("investigation: LS's median parameter error over every estimate is below IV3's: high wind at N = 150; low wind at N = 150"));
}

#[test]
fn bad_options_are_usage_errors() {
    let dir = Scratch::new("options");
    for (args, message) in [
        (&["--runs", "0"][..], "not a positive whole number"),
        (&["--n", "1000,5"][..], "too short"),
        (&["--n", "many"][..], "not a record length"),
        (&["--threads", "0"][..], "not a positive whole number"),
        (&["--case", "medium"][..], "invalid value"),
        (&["--seed", "-1"][..], "unexpected argument"),
    ] {
        let o = reproduce(&dir.0, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(message), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
    }
    assert!(!dir.path("results.json").exists());
}

#[test]
fn an_unwritable_output_fails_before_the_study() {
    // --out names a file: nothing can be written (exit 2), and that is said
    // before the study runs.
    let dir = Scratch::new("unwritable");
    let file = dir.path("a-file");
    std::fs::write(&file, "not a directory").unwrap_or_else(|e| panic!("{e}"));
    let o = reproduce(
        &file,
        &["--runs", "2", "--n", "300", "--case", "low", "--paper-iv"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // The directory is checked before the study: no minutes spent, no table.
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    assert!(
        stderr(&o).contains("error[io]")
            && stderr(&o).contains("cannot create the output directory"),
        "{}",
        stderr(&o)
    );
    assert!(!stderr(&o).contains("panicked"));
}

#[test]
fn paper_iv_and_one_case_write_their_own_document() {
    let dir = Scratch::new("paper-iv");
    let o = reproduce(
        &dir.0,
        &[
            "--runs",
            "2",
            "--n",
            "300,400",
            "--case",
            "high",
            "--paper-iv",
            "--seed",
            "5",
        ],
    );
    succeeded(&o);
    let text = std::fs::read_to_string(dir.path("results.json")).unwrap_or_default();
    let j: Value = serde_json::from_str(&text).unwrap_or_default();
    assert_eq!(j["config"]["refined_iv"], "paper");
    assert_eq!(j["seed"], 5);
    assert_eq!(j["cases"].as_object().map(|m| m.len()), Some(1));
    assert_eq!(j["cases"]["high"]["N"], serde_json::json!([300, 400]));
    assert!(claim(&j, "b")["holds"].is_null() && claim(&j, "c")["holds"].is_null());
    assert!(dir.path("fit-high.png").exists() && !dir.path("fit-low.png").exists());
}

#[test]
fn a_study_where_every_estimate_fails_writes_null_figures() {
    // Ten samples cannot support an estimate: every run diverges, every mean
    // is undefined — `null` in results.json, `-` in the table, still exit 0.
    let dir = Scratch::new("nulls");
    let o = reproduce(&dir.0, &["--runs", "2", "--n", "10", "--case", "low"]);
    succeeded(&o);
    let text = std::fs::read_to_string(dir.path("results.json")).unwrap_or_default();
    let j: Value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"));
    for est in ESTIMATORS {
        let e = estimator(&j, "low", est);
        assert_eq!(e["diverged"], serde_json::json!([2]), "{est}");
        assert!(
            e["fit_mean"]["surge"][0].is_null() && e["param_error"][0].is_null(),
            "{e}"
        );
    }
    assert!(
        stdout(&o).contains("  LS         10  -      -     -    -"),
        "{}",
        stdout(&o)
    );
    assert!(dir.path("fit-low.svg").exists() && dir.path("validation-low.png").exists());
}

/// Claim (c) on paired runs: the 100 high-wind records of the full study
/// (same seeds, so the same data as `leeway reproduce`), N = 5000, each
/// estimated by IV2 and IV3. IV2 assumes the wind-relative velocities keep their
/// sign, which fails at 10 m/s; IV3 evaluates them pointwise. The paired
/// difference of the validation fits removes the run-to-run variation of the
/// data, so a loss of a few points is resolved with a few dozen runs.
#[test]
fn high_wind_degrades_iv2_most_in_surge_on_paired_runs() {
    use leeway_scenarios::study;
    use leeway_scenarios::study::Case;
    use leeway_scenarios::study::StudyConfig;
    leeway::include_model!("../../../examples/models/ship.som");
    let config = StudyConfig {
        runs: 100,
        n: vec![5000],
        cases: vec![Case {
            name: "high".into(),
            wind: 10.0,
        }],
        ..StudyConfig::default()
    };
    let out = study::run_study(&Ship, &config, &|| {});
    let (iv2, iv3) = (2, 3); // Method::ALL order: LS, IV1, IV2, IV3
    let diffs: Vec<[f64; 3]> = out.outcomes[0]
        .iter()
        .filter(|r| !r[0][iv2].diverged && !r[0][iv3].diverged)
        .map(|r| {
            let (a, b) = (&r[0][iv2].fit, &r[0][iv3].fit);
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]]
        })
        .collect();
    assert!(diffs.len() >= 95, "{} paired runs", diffs.len());
    let stats: Vec<(f64, f64)> = (0..3)
        .map(|k| {
            let (mean, std, n) = study::mean_std(diffs.iter().map(|d| d[k]));
            (mean, std / (n as f64).sqrt())
        })
        .collect();
    eprintln!("IV3 − IV2 (mean, standard error) surge/sway/yaw: {stats:?}");
    let (surge, se) = stats[0];
    assert!(
        surge > 2.0 && surge > 3.0 * se,
        "IV2 loses in surge: {stats:?}"
    );
    assert!(surge > stats[2].0, "more in surge than in yaw: {stats:?}");
}
