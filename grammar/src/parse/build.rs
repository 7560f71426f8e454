//! The syntax tree built from pest's pairs: the model, its declarations and
//! the expressions of its equations, each with its span.

use crate::ast::{
    BinOp, BodyComponent, DataEntry, DelayUnit, EquationKind, Expr, Frame, Ident, Item,
    Measurement, ModelSyntax, Number, Path, RotationRow, Span,
};
use crate::parse::rules::Rule;
use pest::iterators::{Pair, Pairs};

fn span_of(p: &Pair<Rule>) -> Span {
    let s = p.as_span();
    Span::new(s.start(), s.end())
}

fn ident(p: Pair<Rule>) -> Ident {
    Ident {
        name: p.as_str().to_string(),
        span: span_of(&p),
    }
}

/// The names among `pairs`.
fn ident_list(pairs: Pairs<Rule>) -> Vec<Ident> {
    pairs
        .filter(|q| q.as_rule() == Rule::ident)
        .map(ident)
        .collect()
}

fn idents(p: Pair<Rule>) -> Vec<Ident> {
    ident_list(p.into_inner())
}

fn number(p: Pair<Rule>) -> Number {
    let text: String = p.as_str().chars().filter(|c| !c.is_whitespace()).collect();
    Number {
        text,
        span: span_of(&p),
    }
}

/// The tree of a `model` pair.
pub(crate) fn build_model(p: Pair<Rule>) -> ModelSyntax {
    let span = span_of(&p);
    let mut inner = p.into_inner();
    let name = inner.next().map(ident).unwrap_or(Ident {
        name: String::new(),
        span,
    });
    let items = inner.filter_map(build_item).collect();
    ModelSyntax { name, items, span }
}

/// One declaration, or `None` for a pair that is none (or is incomplete).
fn build_item(p: Pair<Rule>) -> Option<Item> {
    let span = span_of(&p);
    let rule = p.as_rule();
    let mut inner = p.into_inner();
    Some(match rule {
        Rule::step_decl => Item::Step {
            value: number(inner.next()?),
            span,
        },
        Rule::state_decl => Item::States(ident_list(inner)),
        Rule::input_decl => Item::Inputs(ident_list(inner)),
        Rule::heading_decl => build_heading(inner, span)?,
        Rule::rotation_decl => {
            let rows = inner
                .filter(|q| q.as_rule() == Rule::rotation_row)
                .filter_map(build_rotation_row)
                .collect();
            Item::Rotation { rows, span }
        }
        Rule::disturbance_decl => build_disturbance(inner, span)?,
        Rule::delay_decl => {
            let mut inner = inner.filter(|q| q.as_rule() != Rule::delay_word);
            let input = ident(inner.next()?);
            let amount = number(inner.next()?);
            let unit = match inner.next()?.as_str() {
                "s" => DelayUnit::Seconds,
                _ => DelayUnit::Steps,
            };
            Item::Delay {
                input,
                amount,
                unit,
                span,
            }
        }
        Rule::relative_decl => {
            let name = ident(inner.next()?);
            let disturbance = ident(inner.next()?);
            Item::Relative {
                name,
                disturbance,
                span,
            }
        }
        Rule::equation => build_equation(inner, span)?,
        Rule::nominal_block => {
            let entries = inner
                .filter(|q| q.as_rule() == Rule::nominal_entry)
                .filter_map(|e| {
                    let mut it = e.into_inner();
                    Some((ident(it.next()?), number(it.next()?)))
                })
                .collect();
            Item::Nominal { entries, span }
        }
        Rule::data_block => {
            let entries = inner
                .filter(|q| q.as_rule() == Rule::data_entry)
                .filter_map(build_data_entry)
                .collect();
            Item::Data { entries, span }
        }
        _ => return None,
    })
}

/// `heading psi integrates r [axes(u, v)]`.
fn build_heading(mut inner: Pairs<Rule>, span: Span) -> Option<Item> {
    let name = ident(inner.next()?);
    let integrates = ident(inner.next()?);
    let axes = inner.next().and_then(|a| {
        let v = idents(a);
        let mut it = v.into_iter();
        Some((it.next()?, it.next()?))
    });
    Some(Item::Heading {
        name,
        integrates,
        axes,
        span,
    })
}

/// `u = [r11, r12]` of a `rotation` block; a `0` entry is `None`.
fn build_rotation_row(row: Pair<Rule>) -> Option<RotationRow> {
    let rspan = span_of(&row);
    let mut it = row.into_inner();
    let state = ident(it.next()?);
    let entries = it
        .filter(|q| q.as_rule() == Rule::rotation_entry)
        .map(|e| {
            e.into_inner()
                .next()
                .filter(|x| x.as_rule() == Rule::ident)
                .map(ident)
        })
        .collect();
    Some(RotationRow {
        state,
        entries,
        span: rspan,
    })
}

/// `disturbance c unmeasured earth(n, e)` or `... body(u: cu, v: cv)`.
fn build_disturbance(mut inner: Pairs<Rule>, span: Span) -> Option<Item> {
    let name = ident(inner.next()?);
    let measurement = match inner.next()?.as_str() {
        "measured" => Measurement::Measured,
        _ => Measurement::Unmeasured,
    };
    let f = inner.next()?;
    let frame = match f.as_rule() {
        Rule::earth_frame => Frame::Earth(idents(f)),
        _ => Frame::Body(
            f.into_inner()
                .filter_map(|c| {
                    let mut it = c.into_inner();
                    Some(BodyComponent {
                        state: ident(it.next()?),
                        component: ident(it.next()?),
                    })
                })
                .collect(),
        ),
    };
    Some(Item::Disturbance {
        name,
        measurement,
        frame,
        span,
    })
}

/// `der u = ...` or `next u = ...`.
fn build_equation(mut inner: Pairs<Rule>, span: Span) -> Option<Item> {
    let kind = match inner.next()?.as_str() {
        "next" => EquationKind::Next,
        _ => EquationKind::Der,
    };
    let state = ident(inner.next()?);
    let rhs = build_expr(inner.next()?);
    Some(Item::Equation {
        kind,
        state,
        rhs,
        span,
    })
}

/// `signal = "column" in unit` of a `data` block (column and unit optional).
fn build_data_entry(e: Pair<Rule>) -> Option<DataEntry> {
    let mut it = e.into_inner();
    let signal = ident(it.next()?);
    let mut entry = DataEntry {
        signal,
        column: None,
        unit: None,
    };
    for q in it {
        let qspan = span_of(&q);
        match q.as_rule() {
            Rule::string => {
                let text = q
                    .into_inner()
                    .next()
                    .map(|x| x.as_str().to_string())
                    .unwrap_or_default();
                entry.column = Some((text, qspan));
            }
            Rule::unit => entry.unit = Some((q.as_str().to_string(), qspan)),
            _ => {}
        }
    }
    Some(entry)
}

/// The number `0` at `span`: what a malformed expression pair becomes.
fn zero(span: Span) -> Expr {
    Expr::Number(Number {
        text: "0".into(),
        span,
    })
}

/// `lhs op rhs`, spanning both.
fn binary(op: BinOp, lhs: Expr, rhs: Expr) -> Expr {
    let s = lhs.span().join(rhs.span());
    Expr::Binary {
        op,
        lhs: Box::new(lhs),
        rhs: Box::new(rhs),
        span: s,
    }
}

fn build_expr(p: Pair<Rule>) -> Expr {
    let span = span_of(&p);
    match p.as_rule() {
        Rule::expr => build_sum(p, span),
        Rule::product => build_product(p, span),
        Rule::number => Expr::Number(number(p)),
        Rule::path => {
            let mut inner = p.into_inner().peekable();
            let candidate = inner.next_if(|q| q.as_rule() == Rule::candidate).is_some();
            let base = inner.next().map(ident).unwrap_or(Ident {
                name: String::new(),
                span,
            });
            let field = inner.next().map(ident);
            Expr::Path(Path {
                base,
                field,
                candidate,
                span,
            })
        }
        Rule::modulus | Rule::paren | Rule::negated => {
            let rule = p.as_rule();
            let inner = p.into_inner().next().map(build_expr).unwrap_or(zero(span));
            match rule {
                Rule::modulus => Expr::Abs(Box::new(inner), span),
                Rule::paren => Expr::Paren(Box::new(inner), span),
                _ => Expr::Neg(Box::new(inner), span),
            }
        }
        _ => zero(span),
    }
}

/// An `expr` pair: an optional leading sign, then products joined by `+ -`,
/// left-associative.
fn build_sum(p: Pair<Rule>, span: Span) -> Expr {
    let mut inner = p.into_inner().peekable();
    let negate = match inner.peek().map(|q| q.as_rule()) {
        Some(Rule::sign) => inner.next().is_some_and(|s| s.as_str() == "-"),
        _ => false,
    };
    let Some(first) = inner.next() else {
        return zero(span);
    };
    let mut acc = build_expr(first);
    if negate {
        let s = Span::new(span.start, acc.span().end);
        acc = Expr::Neg(Box::new(acc), s);
    }
    while let (Some(op), Some(rhs)) = (inner.next(), inner.next()) {
        let op = if op.as_str() == "-" {
            BinOp::Sub
        } else {
            BinOp::Add
        };
        acc = binary(op, acc, build_expr(rhs));
    }
    acc
}

/// A `product` pair: factors joined by `* /`, left-associative.
fn build_product(p: Pair<Rule>, span: Span) -> Expr {
    let mut inner = p.into_inner();
    let Some(first) = inner.next() else {
        return zero(span);
    };
    let mut acc = build_expr(first);
    while let (Some(op), Some(rhs)) = (inner.next(), inner.next()) {
        let op = if op.as_str() == "/" {
            BinOp::Div
        } else {
            BinOp::Mul
        };
        acc = binary(op, acc, build_expr(rhs));
    }
    acc
}

#[cfg(test)]
mod tests {
    use crate::ast::{EquationKind, Frame, Ident, Item, Measurement, ModelSyntax, Span};
    use crate::parse::parse;

    #[test]
    fn parses_every_construct() {
        let src = r#"
            /* a block comment */ model M {
                step 0.5;
                state u, v, r
                input tau, delta
                heading psi integrates r axes(u, v)
                disturbance c unmeasured earth(n, e)
                disturbance w measured body(u: wu, v: wv)
                water = relative(c)
                air = relative(w)
                der u = -X*water.u + 2*Y*water.u*|water.u| / 4 + (Z*tau) - K*delta*|delta|
                next v = +A*air.v*|air.v| - B*-v
                der r = 1.5e-3*N*r
                nominal { X = -0.2, Y = +1e-3 }
                data { u = "surge" in knots, time = "t", r in deg/s }
            }
        "#;
        let (model, diags) = parse(src);
        assert!(diags.is_empty(), "{diags:?}");
        let m = model.unwrap_or_else(|| ModelSyntax {
            name: Ident {
                name: String::new(),
                span: Span::default(),
            },
            items: Vec::new(),
            span: Span::default(),
        });
        assert_eq!(m.name.name, "M");
        assert_eq!(m.items.len(), 13);
        assert!(
            matches!(&m.items[3], Item::Heading { axes: Some((a, b)), .. } if a.name == "u" && b.name == "v")
        );
        assert!(
            matches!(&m.items[5], Item::Disturbance { measurement: Measurement::Measured, frame: Frame::Body(c), .. } if c.len() == 2)
        );
        assert!(matches!(
            &m.items[9],
            Item::Equation {
                kind: EquationKind::Next,
                ..
            }
        ));
        assert!(
            matches!(&m.items[11], Item::Nominal { entries, .. } if entries[1].1.text == "+1e-3")
        );
        assert!(
            matches!(&m.items[12], Item::Data { entries, .. } if entries[0].column.as_ref().is_some_and(|c| c.0 == "surge"))
        );
    }
}
