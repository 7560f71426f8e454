//! The chosen model written back as source.

use crate::craft::CANDIDATE_SHIP;
use leeway_select::CandidateModel;
use leeway_structure::grammar;
use std::collections::BTreeSet;

fn read(src: &str) -> CandidateModel {
    let c = leeway_structure::compile(src, &Default::default());
    let ir = c.ir.expect("compiles");
    let names: BTreeSet<String> = ir.parameters.iter().map(|p| p.name.clone()).collect();
    let (syntax, _) = grammar::parse(src);
    CandidateModel::read(src, &syntax.expect("parses"), &names).expect("candidates")
}

#[test]
fn candidates_are_the_marked_parameters_in_order() {
    let m = read(CANDIDATE_SHIP);
    assert_eq!(m.candidates.len(), 22);
    assert_eq!(&m.candidates[..3], ["X_vr", "X_uu", "W_u"]);
}

#[test]
fn the_chosen_model_keeps_unmarked_terms_and_drops_the_others() {
    let src = "model M {\n    state u, v\n    input t\n    der u = -X_u*u + ?X_uu*u*|u| - ?X_v*v + X_t*t\n    der v = ?Y_v*v + Y_t*t\n    nominal { X_u = -0.2, X_uu = -0.1, X_v = 0.3, Y_v = -1 }\n}\n";
    let m = read(src);
    let kept: BTreeSet<String> = ["X_uu".to_string()].into();
    let chosen = m.chosen(&kept).expect("writes");
    assert_eq!(
        chosen,
        "model M {\n    state u, v\n    input t\n    der u = -X_u*u + X_uu*u*|u| + X_t*t\n    der v = Y_t*t\n    nominal { X_u = -0.2, X_uu = -0.1,   }\n}\n"
    );
    // It compiles, with no candidate left.
    let c = leeway_structure::compile(&chosen, &Default::default());
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    assert!(read(&chosen).candidates.is_empty());
    // Every candidate kept: only the marks go.
    let all: BTreeSet<String> = m.candidates.iter().cloned().collect();
    assert_eq!(m.chosen(&all).expect("writes"), src.replace('?', ""));
}

#[test]
fn a_candidate_sharing_a_term_with_another_parameter_is_refused_where_written() {
    let src = "model M {\n    state u\n    input t\n    der u = (X + ?Y)*u + Z*t\n}\n";
    let c = leeway_structure::compile(src, &Default::default());
    let ir = c.ir.expect("compiles");
    let names: BTreeSet<String> = ir.parameters.iter().map(|p| p.name.clone()).collect();
    let (syntax, _) = grammar::parse(src);
    let Err(e) = CandidateModel::read(src, &syntax.expect("parses"), &names) else {
        panic!("a candidate beside another parameter is refused");
    };
    assert_eq!(
        e.message,
        "4:13: a term of `u` with candidate `Y` also holds `X` and `Y`: a candidate's term must have no other parameter"
    );
}

#[test]
fn check_names_the_candidates_and_the_exchangeable_ones() {
    // Two candidates for one regressor (`u*|u|` written twice): one can
    // stand for the other; so can a candidate for a required term.
    let src = "model M {\n    state u, v\n    input tau\n    der u = X_u*u + ?X_a*u*|u| + ?X_b*|u|*u + X_t*tau + ?X_v*v\n    der v = Y_v*v + Y_u*u + ?Y_w*u\n}\n";
    let c = leeway_structure::compile(src, &Default::default());
    let ir = c.ir.expect("compiles");
    let text = leeway_select::describe(src, &ir).expect("candidates");
    assert_eq!(
        text,
        "candidates: 4 (X_a, X_b, X_v, Y_w)\n  the full candidate set: not-identifiable\n  exchangeable: `X_b` can stand for `X_a` (select keeps `X_a`)\n  exchangeable: `Y_w` can stand for `Y_u` (select keeps `Y_u`)\n"
    );
}
