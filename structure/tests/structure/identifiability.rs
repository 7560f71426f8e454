//! The identifiability verdicts of the example models, checked against the
//! hand analysis of the paper (§IV-A, Remark 1): which sign patterns identify
//! θ, which parameter pairs enter only as aggregates, and what separates them.

use leeway_structure::identify::{
    Analysis, Centring, ExperimentStructure, Patterns, all_patterns, parse_pattern,
};
use leeway_structure::ir::{ColumnKind, Ir, PredictorKind, SignPattern};
use leeway_structure::{Compilation, CompileOptions, compile, render};

fn source(path: &str) -> String {
    let full = format!("{}/../examples/models/{path}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{full}: {e}"))
}

fn with(path: &str, aggregate: bool, patterns: Option<Vec<SignPattern>>) -> Compilation {
    compile(
        &source(path),
        &CompileOptions {
            aggregate,
            patterns,
            centring: None,
        },
    )
}

fn ir_of(c: &Compilation) -> &Ir {
    c.ir.as_ref()
        .unwrap_or_else(|| panic!("expected an IR: {:?}", c.diagnostics))
}

fn errors(c: &Compilation) -> Vec<String> {
    c.diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| format!("{}: {}", d.code, d.message))
        .collect()
}

fn sign_index(ir: &Ir, name: &str) -> usize {
    ir.sign_args
        .iter()
        .position(|s| s.name == name)
        .unwrap_or_else(|| panic!("no sign argument {name}"))
}

/// The parameter name sets of the unidentifiable groups, sorted.
fn groups(ir: &Ir) -> Vec<Vec<String>> {
    let mut g: Vec<Vec<String>> = ir
        .report
        .unidentifiable
        .iter()
        .map(|c| {
            let mut names: Vec<String> = c
                .parameters
                .iter()
                .map(|p| ir.parameters[*p].name.clone())
                .collect();
            names.sort();
            names
        })
        .collect();
    g.sort();
    g
}

fn pair(a: &str, b: &str) -> Vec<String> {
    let mut v = vec![a.to_string(), b.to_string()];
    v.sort();
    v
}

// ---------------------------------------------------------------- the ship

#[test]
fn ship_phi_is_the_papers() {
    let c = with("ship.som", false, None);
    let ir = ir_of(&c);
    assert!(errors(&c).is_empty(), "{:?}", errors(&c));
    assert_eq!(ir.parameters.len(), 17);
    // φ_u, φ_v, φ_r of paper §V, as expanded regressors (s[a] = sign of a in the
    // experiment, air terms evaluated pointwise from the anemometer).
    let expected: [&[(&str, &str)]; 3] = [
        &[
            ("X_u", "u"),
            ("X_vr", "v*r"),
            ("X_uu", "s[water.u]*u^2"),
            ("W_uu", "air.u*|air.u| (pointwise)"),
            ("X_tau", "tau1"),
        ],
        &[
            ("Y_v", "v"),
            ("Y_ur", "u*r"),
            ("Y_vv", "s[water.v]*v^2"),
            ("Y_vr", "s[water.v]*v*r"),
            ("W_vv", "air.v*|air.v| (pointwise)"),
            ("Y_tau", "tau2"),
        ],
        &[
            ("N_r", "r"),
            ("N_uv", "u*v"),
            ("N_vv", "s[water.v]*v^2"),
            ("N_vr", "s[water.v]*v*r"),
            ("W_uv", "air.u*air.v (pointwise)"),
            ("N_tau", "tau3"),
        ],
    ];
    for (out, want) in expected.iter().enumerate() {
        let got: Vec<(String, String)> = ir
            .predictors
            .measured
            .iter()
            .filter(|col| !col.kind.is_nuisance() && col.outputs().contains(&out))
            .map(|col| (col.name.clone(), render::column_text(ir, col, out)))
            .collect();
        let want: Vec<(String, String)> = want
            .iter()
            .map(|(p, e)| (p.to_string(), e.to_string()))
            .collect();
        assert_eq!(got, want, "output {}", ir.states[out]);
    }
    // Identifiable from one experiment, whatever its sign pattern.
    assert!(ir.report.identifiable && ir.report.any_single_pattern);
    assert_eq!(ir.report.required_patterns.len(), 1);
    for p in all_patterns(ir.sign_args.len()) {
        let c = with("ship.som", false, Some(vec![p.clone()]));
        assert!(errors(&c).is_empty(), "pattern {p:?}: {:?}", errors(&c));
        assert!(ir_of(&c).report.identifiable);
    }
    // 32 nuisance columns, 24 after reduction (see the snapshot for which).
    assert_eq!(
        (ir.report.nuisance.before, ir.report.nuisance.after),
        (32, 24)
    );
}

// ------------------------------------------------------------ ship, IV2

#[test]
fn ship_iv2_is_refused_from_any_single_pattern_naming_the_three_pairs() {
    let probe = with("ship_iv2.som", false, None);
    let n = ir_of(&probe).sign_args.len();
    assert_eq!(n, 4);
    for p in all_patterns(n) {
        let c = with("ship_iv2.som", false, Some(vec![p.clone()]));
        let ir = ir_of(&c);
        assert!(!ir.report.identifiable, "{p:?}");
        assert!(
            c.only_unidentifiable() && c.has_errors(),
            "{p:?}: {:?}",
            errors(&c)
        );
        assert_eq!(
            groups(ir),
            vec![
                pair("N_uv", "W_uv"),
                pair("X_uu", "W_uu"),
                pair("Y_vv", "W_vv")
            ],
            "{p:?}"
        );
        for e in errors(&c) {
            assert!(
                e.starts_with("unidentifiable-combination: θ is not identifiable: "),
                "{e}"
            );
        }
    }
    // At the all-plus pattern the combinations are plain sums.
    let c = with("ship_iv2.som", false, Some(vec![vec![1; n]]));
    let messages = errors(&c).join("\n");
    for combo in ["X_uu + W_uu", "Y_vv + W_vv", "N_uv + W_uv"] {
        assert!(messages.contains(combo), "{combo} in {messages}");
    }
    // With water.u negative and air.u positive, s_u·X_uu + s_q·W_uu = W_uu − X_uu.
    let ir = ir_of(&probe);
    let mut p = vec![1i8; n];
    p[sign_index(ir, "water.u")] = -1;
    let c = with("ship_iv2.som", false, Some(vec![p]));
    assert!(
        errors(&c).join("\n").contains("enter only as X_uu - W_uu"),
        "{:?}",
        errors(&c)
    );
}

#[test]
fn ship_iv2_separations() {
    let c = with("ship_iv2.som", false, None);
    let ir = ir_of(&c);
    assert!(!ir.report.identifiable);
    assert!(ir.report.required_patterns.is_empty());
    let sep = |a: &str, b: &str| {
        ir.report
            .separations
            .iter()
            .find(|s| {
                let mut names: Vec<String> = s
                    .parameters
                    .iter()
                    .map(|p| ir.parameters[*p].name.clone())
                    .collect();
                names.sort();
                names == pair(a, b)
            })
            .unwrap_or_else(|| panic!("no separation for {a}/{b}"))
    };
    let (wu, au, wv, av) = (
        sign_index(ir, "water.u"),
        sign_index(ir, "air.u"),
        sign_index(ir, "water.v"),
        sign_index(ir, "air.v"),
    );
    // X_uu / W_uu: experiments where sign(water.u)·sign(air.u) differs.
    for (a, b, (i, j)) in [("X_uu", "W_uu", (wu, au)), ("Y_vv", "W_vv", (wv, av))] {
        let s = sep(a, b);
        assert!(
            s.message.contains(&format!(
                "sign({}) ≠ sign({})",
                ir.sign_args[i].name, ir.sign_args[j].name
            )),
            "{}",
            s.message
        );
        let full = s.full(ir.sign_args.len());
        let set = full
            .as_ref()
            .unwrap_or_else(|| panic!("{a}/{b} are separable"));
        let products: Vec<i8> = set.iter().map(|p| p[i] * p[j]).collect();
        assert!(
            products.contains(&1) && products.contains(&-1),
            "{a}/{b}: {set:?}"
        );
        // Those experiments really separate the pair (and leave N_uv/W_uv).
        let c2 = with("ship_iv2.som", false, Some(set.clone()));
        let g = groups(ir_of(&c2));
        assert!(!g.contains(&pair(a, b)), "{a}/{b} still confounded: {g:?}");
        assert!(g.contains(&pair("N_uv", "W_uv")));
    }
    let s = sep("N_uv", "W_uv");
    assert!(s.patterns.is_none());
    assert!(
        s.message
            .starts_with("no experiment separates `N_uv` and `W_uv`"),
        "{}",
        s.message
    );
    // Exhaustively: no set of sign patterns separates N_uv from W_uv.
    let every = all_patterns(ir.sign_args.len());
    let c_all = with("ship_iv2.som", false, Some(every));
    assert_eq!(groups(ir_of(&c_all)), vec![pair("N_uv", "W_uv")]);
}

#[test]
fn ship_iv2_is_accepted_with_aggregation() {
    let c = with("ship_iv2.som", true, None);
    let ir = ir_of(&c);
    assert!(errors(&c).is_empty(), "{:?}", errors(&c));
    let aggregates: Vec<(String, String, Vec<String>)> = ir
        .report
        .aggregates
        .iter()
        .map(|a| {
            let absorbed = a
                .absorbed
                .iter()
                .map(|p| ir.parameters[*p].name.clone())
                .collect();
            (
                ir.parameters[a.parameter].name.clone(),
                a.estimates.clone(),
                absorbed,
            )
        })
        .collect();
    assert_eq!(
        aggregates,
        vec![
            (
                "X_uu".to_string(),
                "X_uu + W_uu".to_string(),
                vec!["W_uu".to_string()]
            ),
            (
                "Y_vv".to_string(),
                "Y_vv + W_vv".to_string(),
                vec!["W_vv".to_string()]
            ),
            (
                "N_uv".to_string(),
                "N_uv + W_uv".to_string(),
                vec!["W_uv".to_string()]
            ),
        ]
    );
    let warnings: Vec<&str> = c
        .diagnostics
        .iter()
        .filter(|d| d.code == "aggregated-combination")
        .map(|d| d.message.as_str())
        .collect();
    assert_eq!(warnings.len(), 3, "{warnings:?}");
}

// ------------------------------------------------------------------ the ROV

#[test]
fn rov_needs_two_sign_patterns() {
    let c = with("rov.som", false, None);
    let ir = ir_of(&c);
    assert!(errors(&c).is_empty(), "{:?}", errors(&c));
    assert!(ir.report.identifiable);
    assert!(!ir.report.any_single_pattern);
    assert_eq!(
        ir.report.required_patterns.len(),
        2,
        "{:?}",
        ir.report.required_patterns
    );
    let (v, r) = (sign_index(ir, "water.v"), sign_index(ir, "r"));
    let products: Vec<i8> = ir
        .report
        .required_patterns
        .iter()
        .map(|p| p[v] * p[r])
        .collect();
    assert!(
        products.contains(&1) && products.contains(&-1),
        "{:?}",
        ir.report.required_patterns
    );
    assert!(
        c.diagnostics
            .iter()
            .any(|d| d.code == "required-experiments")
    );

    // Refused from every single pattern, naming Y_vr and Y_rv.
    let every = all_patterns(ir.sign_args.len());
    for p in &every {
        let c1 = with("rov.som", false, Some(vec![p.clone()]));
        assert!(c1.only_unidentifiable() && c1.has_errors(), "{p:?}");
        assert_eq!(groups(ir_of(&c1)), vec![pair("Y_rv", "Y_vr")], "{p:?}");
        let e = errors(&c1).join("\n");
        assert!(e.contains("`Y_vr` and `Y_rv`"), "{e}");
    }
    // From two patterns: accepted exactly when sign(water.v)·sign(r) differs.
    for (i, a) in every.iter().enumerate() {
        for b in &every[i + 1..] {
            let c2 = with("rov.som", false, Some(vec![a.clone(), b.clone()]));
            let separated = a[v] * a[r] != b[v] * b[r];
            assert_eq!(
                ir_of(&c2).report.identifiable,
                separated,
                "{a:?} {b:?}: {:?}",
                errors(&c2)
            );
            assert_eq!(c2.has_errors(), !separated);
        }
    }
}

#[test]
fn patterns_parse_by_name() {
    let c = with("rov.som", false, None);
    let ir = ir_of(&c);
    let (u, v, r) = (
        sign_index(ir, "water.u"),
        sign_index(ir, "water.v"),
        sign_index(ir, "r"),
    );
    let p = parse_pattern(&ir.sign_args, "water.v:-, r:+").expect("valid");
    assert_eq!((p[u], p[v], p[r]), (1, -1, 1));
    assert_eq!(
        parse_pattern(&ir.sign_args, "").expect("empty is all plus"),
        vec![1; 3]
    );
    assert_eq!(parse_pattern(&ir.sign_args, "r:-1").expect("-1")[r], -1);
    for (bad, says) in [
        (
            "water.w:+",
            "`water.w` is not a sign argument of this model; its sign arguments are water.u, water.v, r",
        ),
        (
            "water.v",
            "expected `argument:+` or `argument:-`, found `water.v`",
        ),
        (
            "water.v:x",
            "the sign of `water.v` must be `+` or `-`, found `x`",
        ),
        ("r:+,r:-", "`r` is given twice in one pattern"),
    ] {
        assert_eq!(parse_pattern(&ir.sign_args, bad), Err(says.to_string()));
    }
}

// ------------------------------------------------------- other example craft

#[test]
fn blimp_and_hovercraft_are_identifiable_from_one_experiment() {
    for (name, params, signs, nuisance) in [
        ("blimp.som", 11, 3, (23, 20)),
        ("hovercraft.som", 8, 0, (0, 0)),
    ] {
        let c = with(name, false, None);
        let ir = ir_of(&c);
        assert!(errors(&c).is_empty(), "{name}: {:?}", errors(&c));
        assert_eq!(ir.parameters.len(), params, "{name}");
        assert_eq!(
            ir.sign_args.iter().filter(|s| !s.measured).count(),
            signs,
            "{name}"
        );
        assert!(
            ir.report.identifiable && ir.report.any_single_pattern,
            "{name}"
        );
        assert_eq!(
            (ir.report.nuisance.before, ir.report.nuisance.after),
            nuisance,
            "{name}"
        );
    }
    // The hovercraft's wind is measured: every wind term is a pointwise Φ2 column.
    let c = with("hovercraft.som", false, None);
    let ir = ir_of(&c);
    let measured: Vec<&str> = ir
        .parameters
        .iter()
        .filter(|p| p.measured)
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(measured, ["X_uu", "Y_vv", "N_uv"]);
    assert!(
        ir.predictors
            .measured
            .iter()
            .all(|c| matches!(c.kind, ColumnKind::Theta { .. }))
    );
}

#[test]
fn common_input_term_is_refused_naming_both_parameters() {
    let c = with("broken/common-input-term.som", false, None);
    assert!(c.ir.is_none());
    let e: Vec<_> = c
        .diagnostics
        .iter()
        .filter(|d| d.code == "common-input-term")
        .collect();
    assert_eq!(e.len(), 1, "{:?}", c.diagnostics);
    assert!(
        e[0].message.contains("`X_t`") && e[0].message.contains("`W_t`"),
        "{}",
        e[0].message
    );
    assert!(e[0].message.contains("X_t + W_t"), "{}", e[0].message);
}

/// A pointwise modulus of a measured medium still carries a sign: `a·|b|`
/// and `a·b` in that medium are told apart by a sign change of `b`, which
/// may happen within one experiment (IV3 evaluates it pointwise).
#[test]
fn measured_medium_modulus_is_separated_by_a_sign_change() {
    let src = "model M {
        step 0.1
        state u, v
        input t1, t2
        disturbance gust measured body(u: gu, v: gv)
        air = relative(gust)
        der u = A*air.u + T1*t1
        der v = B*air.v*|air.u| + F*air.u*air.v + T2*t2
    }";
    let c = leeway_structure::compile(src, &CompileOptions::default());
    let ir = ir_of(&c);
    assert!(ir.report.identifiable, "{:?}", c.diagnostics);
    assert!(!ir.report.any_single_pattern);
    let u = sign_index(ir, "air.u");
    let signs: Vec<i8> = ir.report.required_patterns.iter().map(|p| p[u]).collect();
    assert_eq!(signs, [1, -1], "both signs of the measured air.u");
    let sep = &ir.report.separations[0].message;
    assert!(sep.contains("within one experiment"), "{sep}");
}

fn compile_with(source: &str, centring: Option<Centring>) -> Compilation {
    compile(
        source,
        &CompileOptions {
            aggregate: false,
            patterns: None,
            centring,
        },
    )
}

const CONSTANT_WITH_CURRENT: &str = "model S {
    state u, v, r
    input tau
    heading psi integrates r
    disturbance current unmeasured earth(north, east)
    water = relative(current)
    der u = X_u*water.u + X_t*tau + X_0
    der v = Y_v*water.v
    der r = N_r*r
}";

/// A constant term is identifiable exactly when the instruments keep
/// constants: the tanker (no disturbance) by default, a craft in a current
/// only with uncentred or pooled instruments — and the verdict says so.
#[test]
fn constant_terms_are_identifiable_where_the_centring_keeps_constants() {
    let tanker = with("tanker.som", false, None);
    assert!(errors(&tanker).is_empty(), "{:?}", errors(&tanker));
    let ir = ir_of(&tanker);
    assert_eq!(ir.report.centring, Some(Centring::None));
    assert!(ir.report.identifiable && ir.report.any_single_pattern);
    assert!(
        ir.report
            .notes
            .iter()
            .any(|n| n.contains("`X_0`, `Y_0` and `N_0`: constant terms")),
        "{:?}",
        ir.report.notes
    );
    // The same model analysed with per-experiment centring loses its constants.
    let centred = compile_with(&source("tanker.som"), Some(Centring::Experiment));
    assert_eq!(
        groups(ir_of(&centred)),
        vec![vec!["N_0"], vec!["X_0"], vec!["Y_0"]]
    );

    let current = compile_with(CONSTANT_WITH_CURRENT, None);
    let ir = ir_of(&current);
    assert_eq!(ir.report.centring, Some(Centring::Experiment));
    assert!(!ir.report.identifiable);
    assert_eq!(groups(ir), vec![vec!["X_0"]]);
    assert!(
        ir.report.unidentifiable[0]
            .message
            .contains("annihilated by per-experiment centring")
    );
    let sep = &ir.report.separations[0].message;
    assert!(sep.contains("`--centring none` or `pooled`"), "{sep}");
    for centring in [Centring::None, Centring::Pooled] {
        let c = compile_with(CONSTANT_WITH_CURRENT, Some(centring));
        assert!(errors(&c).is_empty(), "{centring:?}: {:?}", errors(&c));
        assert!(ir_of(&c).report.identifiable, "{centring:?}");
    }
}

/// A constant force beside quadratic drag in a current: per-experiment
/// centring annihilates it, and the way out named is a centring *and* the
/// experiments it needs — exactly what the analysis under that centring
/// requires (one answer, whichever centring is asked).
#[test]
fn a_constant_beside_quadratic_drag_is_told_its_centring_and_its_experiments() {
    let source = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/models/catamaran.som"
    ))
    .unwrap_or_default();
    let by_default = compile_with(&source, None);
    let report = &ir_of(&by_default).report;
    assert!(!report.identifiable);
    let sep = &report.separations[0];
    assert_eq!(
        sep.message,
        "`X_0`: θ is identifiable with `--centring none` or `pooled` from experiments with sign patterns {+water.u +water.v}, {-water.u +water.v} (uncentred instruments are valid only when the current and the process disturbance have zero mean, or their means are modelled (constant terms, nuisance columns))"
    );
    for centring in [Centring::None, Centring::Pooled] {
        let c = compile_with(&source, Some(centring));
        let r = &ir_of(&c).report;
        assert!(r.identifiable, "{centring:?}");
        assert_eq!(
            Some(&r.required_patterns),
            sep.patterns.as_ref(),
            "{centring:?}"
        );
    }
}

/// Pooled centring annihilates a constant common to every experiment but
/// keeps one that differs between experiments (here through a sign).
#[test]
fn pooled_centring_keeps_constants_that_differ_between_experiments() {
    // |water.u| = s·(u − cos ψ·north − sin ψ·east): its λ moments give the
    // sign-only constant s·E[…] once cos² = 1 − sin² is applied.
    let src = "model P {
        state u, v, r
        heading psi integrates r
        disturbance current unmeasured earth(north, east)
        water = relative(current)
        der u = X_uu*water.u*|water.u| + X_r*r
        der v = Y_v*water.v
        der r = N_r*r
    }";
    let ir = ir_of(&compile_with(src, Some(Centring::Pooled))).clone();
    let s = sign_index(&ir, "water.u");
    let plus = vec![1i8; ir.sign_args.len()];
    let mut minus = plus.clone();
    minus[s] = -1;
    let kept = |centring: Centring, set: &[SignPattern]| {
        Analysis::with_centring(&ir, PredictorKind::Measured, centring)
            .reduce(Patterns::Set(set))
            .kept()
            .len()
    };
    let one = std::slice::from_ref(&plus);
    let both = [plus.clone(), minus];
    // One experiment: pooled is per-experiment centring.
    assert_eq!(kept(Centring::Pooled, one), kept(Centring::Experiment, one));
    // Two experiments of opposite sign: the sign-only constant differs between
    // them, so pooled centring keeps a column that per-experiment centring
    // annihilates; no centring keeps at least as much.
    let (e, p, n) = (
        kept(Centring::Experiment, &both),
        kept(Centring::Pooled, &both),
        kept(Centring::None, &both),
    );
    assert!(e < p && p <= n, "experiment {e}, pooled {p}, none {n}");
}

/// Moduli of plain states are pointwise: `r*|r|` and `r*r` are told apart
/// by a sign change of r, which may happen within one experiment.
#[test]
fn plain_state_moduli_are_pointwise_and_separated_by_a_sign_change() {
    let c = compile_with(
        "model R { state r\n input d\n der r = N_d*d + N_a*r*|r| + N_b*r*r }",
        None,
    );
    let ir = ir_of(&c);
    assert!(ir.sign_args.iter().all(|a| a.pointwise));
    assert!(ir.report.identifiable);
    assert_eq!(ir.report.required_patterns.len(), 2, "{:?}", ir.report);
    let sep = &ir.report.separations[0].message;
    assert!(
        sep.contains("both signs of r")
            && sep.contains("a sign change within one experiment suffices"),
        "{sep}"
    );
    // One experiment in which r changes sign identifies θ.
    let analysis = Analysis::new(ir, PredictorKind::Measured);
    let varying = ExperimentStructure {
        pattern: vec![1],
        frozen_rotation: None,
        varying: vec![0],
    };
    let fixed = ExperimentStructure {
        varying: Vec::new(),
        ..varying.clone()
    };
    assert!(analysis.identifiable(Patterns::Experiments(std::slice::from_ref(&varying))));
    assert!(!analysis.identifiable(Patterns::Experiments(std::slice::from_ref(&fixed))));
}
