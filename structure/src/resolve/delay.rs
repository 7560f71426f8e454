//! The inputs' dead times: `delay tau 10 steps` or `delay tau 1.0 s`, one
//! per input, a whole number of samples (a dead time in seconds is one when
//! the model declares its `step`; without it, each record's sample time
//! decides when data is loaded).

use crate::exact::{Q, decimal, shown, to_f64};
use crate::ir::{Lag, LagProblem, MAX_DELAY_SAMPLES, samples_in};
use leeway_grammar::{DelayUnit, Diagnostic, Ident, Item, ModelSyntax, Number};
use num_traits::{ToPrimitive, Zero};

use super::decl::{Resolved, Symbol};
use super::symbols::{invalid_number, names};

/// The longest dead time in seconds on a model without `step` (a day): past
/// it, a value is a typing slip whatever the sample time.
pub const MAX_DELAY_SECONDS: f64 = 86_400.0;

/// Every `delay` declaration, in the order written.
pub(super) fn resolve_delays(r: &mut Resolved, model: &ModelSyntax, diags: &mut Vec<Diagnostic>) {
    for item in &model.items {
        if let Item::Delay {
            input,
            amount,
            unit,
            span,
        } = item
        {
            let Some(i) = input_of(r, input, diags) else {
                continue;
            };
            if let Some((_, _, first)) = r.delays.iter().find(|(j, _, _)| *j == i) {
                diags.push(
                    Diagnostic::error(
                        "duplicate-delay",
                        format!("the dead time of `{}` is declared twice", input.name),
                    )
                    .with_primary(*span, "second dead time")
                    .with_secondary(*first, "first declared here")
                    .with_help("an input has one dead time: keep one declaration"),
                );
                continue;
            }
            if let Some(lag) = lag_of(r, amount, *unit, diags) {
                r.delays.push((i, lag, *span));
            }
        }
    }
}

/// The input a delay names, or its diagnostic.
fn input_of(r: &Resolved, id: &Ident, diags: &mut Vec<Diagnostic>) -> Option<usize> {
    let what = match r.symbols.get(&id.name) {
        Some((Symbol::Input(i), _)) => return Some(*i),
        Some((Symbol::State(_), _)) => "a state",
        Some(_) => "not an input",
        None => "not declared",
    };
    diags.push(
        Diagnostic::error(
            "delay-not-input",
            format!(
                "`{}` is {what}; only an input can have a dead time",
                id.name
            ),
        )
        .with_primary(id.span, "expected an input")
        .with_help(format!("declared inputs: {}", names(&r.inputs))),
    );
    None
}

/// The dead time written as `amount unit`, checked.
fn lag_of(
    r: &Resolved,
    amount: &Number,
    unit: DelayUnit,
    diags: &mut Vec<Diagnostic>,
) -> Option<Lag> {
    let q = match decimal(&amount.text) {
        Ok(q) => q,
        Err(why) => {
            diags.push(invalid_number(why, amount.span));
            return None;
        }
    };
    let invalid = |message: String, help: &str| {
        Diagnostic::error("invalid-delay", message)
            .with_primary(amount.span, "here")
            .with_help(help.to_string())
    };
    if q < Q::zero() {
        diags.push(invalid(
            format!(
                "a dead time cannot be negative, found `{}`",
                shown(&amount.text)
            ),
            "an input acts after it is logged: write its dead time as a positive number, e.g. `delay tau 10 steps`",
        ));
        return None;
    }
    let too_long = |samples: String| {
        Diagnostic::error(
            "delay-too-long",
            format!("a dead time of {samples} samples is longer than {MAX_DELAY_SAMPLES}"),
        )
        .with_primary(amount.span, "too long")
        .with_help("check the unit: `steps` counts samples, `s` seconds")
    };
    match unit {
        DelayUnit::Steps => {
            if !q.is_integer() {
                diags.push(invalid(
                    format!(
                        "a dead time in steps is a whole number of samples, found `{}`",
                        shown(&amount.text)
                    ),
                    "write a whole number of samples, or the dead time in seconds, e.g. `delay tau 1.0 s`",
                ));
                return None;
            }
            match q.to_integer().to_usize() {
                Some(n) if n <= MAX_DELAY_SAMPLES => Some(Lag::Samples(n)),
                _ => {
                    diags.push(too_long(shown(&amount.text)));
                    None
                }
            }
        }
        DelayUnit::Seconds => seconds(r, &q, amount, diags, too_long),
    }
}

/// A dead time in seconds: samples when the model's step is known, else
/// seconds left for each record's sample time.
fn seconds(
    r: &Resolved,
    q: &Q,
    amount: &Number,
    diags: &mut Vec<Diagnostic>,
    too_long: impl Fn(String) -> Diagnostic,
) -> Option<Lag> {
    let s = to_f64(q);
    let Some((step, step_span)) = &r.step else {
        if s > MAX_DELAY_SECONDS {
            diags.push(
                Diagnostic::error(
                    "delay-too-long",
                    format!(
                        "a dead time of {} s is longer than a day ({MAX_DELAY_SECONDS} s)",
                        shown(&amount.text)
                    ),
                )
                .with_primary(amount.span, "too long")
                .with_help("check the unit: `steps` counts samples, `s` seconds"),
            );
            return None;
        }
        return Some(Lag::Seconds(s));
    };
    let h = to_f64(step);
    match samples_in(s, h) {
        Ok(n) => Some(Lag::Samples(n)),
        Err(LagProblem::TooLong { samples }) => {
            diags.push(too_long(format!("{samples}")));
            None
        }
        Err(LagProblem::NotWhole { ratio }) => {
            diags.push(
                Diagnostic::error(
                    "delay-not-whole-samples",
                    format!(
                        "a dead time of {} s is {ratio:.3} sample times of {h} s, not a whole number",
                        shown(&amount.text)
                    ),
                )
                .with_primary(amount.span, "not a multiple of the step")
                .with_secondary(*step_span, "the sample time")
                .with_help(format!(
                    "give a multiple of the step, e.g. `{} s`, or the dead time in steps",
                    to_f64(&(step * Q::from_integer(num_bigint::BigInt::from(ratio.round().max(1.0) as i64))))
                )),
            );
            None
        }
    }
}
