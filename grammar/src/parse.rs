//! Text → syntax tree. pest types never leave this module.

use crate::ast::*;
use crate::diagnostic::data::Diagnostic;
use pest::Parser;
use pest::iterators::Pair;

#[derive(pest_derive::Parser)]
#[grammar = "som.pest"]
struct SomParser;

/// Deepest nesting of parentheses and moduli accepted. Deeper input is
/// rejected before pest sees it, so no input can exhaust the stack.
pub const MAX_NESTING: usize = 64;

/// Largest model file accepted, in bytes.
pub const MAX_SOURCE_BYTES: usize = 1 << 20;

/// Most operands (names and numbers) in one expression, a chain of operands
/// joined by `+ - * /` (through parentheses and moduli). Checked before
/// parsing: every later pass may then recurse over an expression, whose tree
/// is at most this deep (plus [`MAX_NESTING`] and [`MAX_SIGNS`] levels).
pub const MAX_OPERANDS: usize = 1000;

/// Most unary signs in a row (`- -u` is two). Checked before parsing.
pub const MAX_SIGNS: usize = 8;

/// Parses a `.som` source. pest stops at the first syntax error, so a failed
/// parse returns exactly one diagnostic.
pub fn parse(source: &str) -> (Option<ModelSyntax>, Vec<Diagnostic>) {
    if source.len() > MAX_SOURCE_BYTES {
        return (None, vec![crate::source::too_large(source.len() as u64)]);
    }
    if let Some(d) = nesting_guard(source).or_else(|| size_guard(source)) {
        return (None, vec![d]);
    }
    match SomParser::parse(Rule::file, source) {
        Ok(mut pairs) => {
            let Some(file) = pairs.next() else {
                return (None, vec![Diagnostic::error("syntax", "empty parse")]);
            };
            let model = file.into_inner().find(|p| p.as_rule() == Rule::model);
            match model {
                Some(m) => (Some(build_model(m)), Vec::new()),
                None => (None, vec![Diagnostic::error("syntax", "no model found")]),
            }
        }
        Err(e) => (None, vec![syntax_error(source, e)]),
    }
}

/// Rejects input nested deeper than [`MAX_NESTING`].
fn nesting_guard(source: &str) -> Option<Diagnostic> {
    let deepest = scan_delimiters(source, 0, source.len(), MAX_NESTING).err()?;
    Some(
        Diagnostic::error("nesting-too-deep", format!("expression nested more than {MAX_NESTING} levels deep"))
            .with_primary(Span::new(deepest, deepest + 1), "too deep here")
            .with_help("second-order modulus terms never need deep nesting; write the term as a product such as X*u*|v|"),
    )
}

/// Rejects an expression of more than [`MAX_OPERANDS`] operands or a run of
/// more than [`MAX_SIGNS`] unary signs, before pest (or any recursion over
/// the tree) sees it. Skips comments and strings like [`scan_delimiters`].
/// An operand directly after an operand (no operator between) starts a new
/// expression, as do `=`, `,`, `;`, braces and brackets.
fn size_guard(source: &str) -> Option<Diagnostic> {
    let bytes = source.as_bytes();
    let word = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || b == b'.';
    let mut operands = 0usize;
    let mut chain_start = 0usize;
    // After an operand (name, number, `)` or closing `|`): an operator may follow.
    let mut after_operand = false;
    let mut modulus_depth = 0usize;
    let mut signs = 0usize;
    let mut signs_start = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        let next = bytes.get(i + 1).copied();
        match b {
            b'/' if next == Some(b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'/' if next == Some(b'*') => {
                i += 2;
                while i < bytes.len() && !(bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/')) {
                    i += 1;
                }
                i += 2;
                continue;
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                    i += 1;
                }
                operands = 0;
                after_operand = false;
            }
            _ if word(b) => {
                let start = i;
                let number = b.is_ascii_digit() || b == b'.';
                while i < bytes.len() && word(bytes[i]) {
                    // `1e-3`: the exponent's sign belongs to the number.
                    if number
                        && matches!(bytes[i], b'e' | b'E')
                        && matches!(bytes.get(i + 1), Some(b'+' | b'-'))
                    {
                        i += 1;
                    }
                    i += 1;
                }
                if after_operand {
                    operands = 0;
                }
                if operands == 0 {
                    chain_start = start;
                }
                operands += 1;
                if operands > MAX_OPERANDS {
                    return Some(
                        Diagnostic::error("expression-too-large", format!("this expression has more than {MAX_OPERANDS} operands"))
                            .with_primary(Span::new(chain_start, i), "too many operands")
                            .with_help("write the terms out; a second-order model has a handful per equation, and a number may be written once (e.g. 2.5e-3)"),
                    );
                }
                after_operand = true;
                signs = 0;
                continue;
            }
            b'(' => after_operand = false,
            b')' => after_operand = true,
            b'|' if after_operand && modulus_depth > 0 => modulus_depth -= 1,
            b'|' => {
                modulus_depth += 1;
                after_operand = false;
            }
            b'+' | b'-' if !after_operand => {
                if signs == 0 {
                    signs_start = i;
                }
                signs += 1;
                if signs > MAX_SIGNS {
                    return Some(
                        Diagnostic::error(
                            "expression-too-large",
                            format!("more than {MAX_SIGNS} signs in a row"),
                        )
                        .with_primary(Span::new(signs_start, i + 1), "too many signs")
                        .with_help("write one sign: `- -u` is `u`, `- - -u` is `-u`"),
                    );
                }
            }
            b'+' | b'-' | b'*' | b'/' => {
                after_operand = false;
                signs = 0;
            }
            b' ' | b'\t' | b'\r' | b'\n' => {}
            _ => {
                // `=`, `,`, `;`, braces, brackets, `:` and anything else end an expression.
                operands = 0;
                after_operand = false;
                modulus_depth = 0;
                signs = 0;
            }
        }
        i += 1;
    }
    None
}

/// Scans `source[from..to]` for the delimiters of expressions, skipping
/// comments and string literals, and returns the byte offsets of the `(` and
/// `|` still open at `to`, innermost last. A `|` opens a modulus where an
/// operand is expected (after an operator, `(`, `|`, `=`, `,`), else closes one.
/// Fails with the offset of the first delimiter nested deeper than `limit`.
fn scan_delimiters(
    source: &str,
    from: usize,
    to: usize,
    limit: usize,
) -> Result<Vec<usize>, usize> {
    let bytes = source.as_bytes();
    let to = to.min(bytes.len());
    let mut open: Vec<usize> = Vec::new();
    let mut operand_expected = true;
    let mut i = from;
    while i < to {
        let b = bytes[i];
        let next = bytes.get(i + 1).copied();
        match b {
            b'/' if next == Some(b'/') => {
                while i < to && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'/' if next == Some(b'*') => {
                i += 2;
                while i < to && !(bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/')) {
                    i += 1;
                }
                i += 2;
                continue;
            }
            b'"' => {
                i += 1;
                while i < to && bytes[i] != b'"' && bytes[i] != b'\n' {
                    i += 1;
                }
                operand_expected = false;
            }
            b'(' => {
                open.push(i);
                operand_expected = true;
            }
            b')' => {
                open.pop();
                operand_expected = false;
            }
            b'|' if operand_expected => open.push(i),
            b'|' => {
                open.pop();
            }
            b'+' | b'-' | b'*' | b'/' | b'=' | b',' | b'{' | b'[' => operand_expected = true,
            b' ' | b'\t' | b'\r' | b'\n' => {}
            _ => operand_expected = false,
        }
        if open.len() > limit {
            return Err(i);
        }
        i += 1;
    }
    Ok(open)
}

/// The innermost `(` or `|` left open by the expression that ends at `pos`
/// (the text after the last `=` before it), if any.
fn unclosed_delimiter(source: &str, pos: usize) -> Option<usize> {
    let pos = pos.min(source.len());
    let start = source.get(..pos)?.rfind('=').map_or(0, |i| i + 1);
    scan_delimiters(source, start, pos, usize::MAX)
        .ok()?
        .last()
        .copied()
}

fn rule_name(rule: &Rule) -> &'static str {
    match rule {
        Rule::file | Rule::EOI => "end of file",
        Rule::model => "`model Name { ... }`",
        Rule::item
        | Rule::step_decl
        | Rule::state_decl
        | Rule::input_decl
        | Rule::heading_decl
        | Rule::rotation_decl
        | Rule::disturbance_decl
        | Rule::nominal_block
        | Rule::data_block
        | Rule::equation_kind => "a declaration",
        Rule::axes => "`axes(..)`",
        Rule::rotation_row => "a rotation row `state = [a, b]`",
        Rule::rotation_entry => "a data column name or 0",
        Rule::zero => "0",
        Rule::measurement => "`measured` or `unmeasured`",
        Rule::earth_frame => "`earth(..)`",
        Rule::frame => "`earth(..)` or `body(..)`",
        Rule::ident_list => "a list of names",
        Rule::body_frame => "`body(..)`",
        Rule::body_component => "`state: component`",
        // Both start a declaration; listing them separately only lengthens the message.
        Rule::relative_decl | Rule::equation => "a declaration",
        Rule::nominal_entry => "`parameter = value`",
        Rule::data_entry => "`signal = \"column\"` or `signal in unit`",
        Rule::unit_clause | Rule::in_word => "`in unit`",
        Rule::unit => "a unit such as `deg` or `deg/s`",
        Rule::expr | Rule::product => "an expression",
        Rule::factor | Rule::negated => "an operand",
        Rule::modulus => "`|..|`",
        Rule::paren => "`(`",
        Rule::path => "a name",
        Rule::sign => "`+` or `-`",
        Rule::add_op | Rule::mul_op => "an operator",
        Rule::number => "a number",
        Rule::signed_number => "a number",
        Rule::string | Rule::string_inner => "a quoted column name",
        Rule::keyword => "a keyword",
        Rule::ident => "a name",
        Rule::WHITESPACE | Rule::COMMENT => "whitespace",
    }
}

/// What the parser found at `pos`, as the user reads it, and where it ends:
/// a whole word or number, one character, or the end of the line or file.
fn found_token(source: &str, pos: usize) -> (String, usize) {
    let Some(rest) = source.get(pos..) else {
        return ("end of file".to_string(), pos);
    };
    let Some(first) = rest.chars().next() else {
        return ("end of file".to_string(), pos);
    };
    let word_char = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '.';
    if word_char(first) {
        let len: usize = rest
            .chars()
            .take_while(|c| word_char(*c))
            .map(char::len_utf8)
            .sum();
        (format!("`{}`", &rest[..len]), pos + len)
    } else if first == '\n' || first == '\r' {
        ("end of line".to_string(), pos + 1)
    } else if first.is_control() {
        // Never echo a raw control character (NUL, escape…) to a terminal.
        (
            format!("`\\u{{{:x}}}`", u32::from(first)),
            pos + first.len_utf8(),
        )
    } else {
        (format!("`{first}`"), pos + first.len_utf8())
    }
}

fn syntax_error(source: &str, e: pest::error::Error<Rule>) -> Diagnostic {
    use pest::error::{ErrorVariant, InputLocation};
    let pos = match e.location {
        InputLocation::Pos(p) => p,
        InputLocation::Span((s, _)) => s,
    };
    let (found, end) = found_token(source, pos);
    let keyword = is_keyword(found.trim_matches('`'));
    let found_text = if keyword {
        format!("the keyword {found}")
    } else {
        found.clone()
    };
    let (message, expected) = match &e.variant {
        ErrorVariant::ParsingError {
            positives,
            negatives,
        } => {
            let mut names: Vec<&str> = positives.iter().map(rule_name).collect();
            names.sort_unstable();
            names.dedup();
            // At a declaration boundary a name starts `x = relative(..)`: say "a declaration".
            if names.contains(&"a declaration") {
                names.retain(|n| *n != "a name");
            }
            let list = match names.len() {
                0 => String::new(),
                1 => names[0].to_string(),
                n => format!("{} or {}", names[..n - 1].join(", "), names[n - 1]),
            };
            if !names.is_empty() {
                (
                    format!("expected {list}, found {found_text}"),
                    names.join(" "),
                )
            } else if negatives.contains(&Rule::keyword) {
                (
                    format!("{found} is a keyword and cannot be used as a name"),
                    "a name".to_string(),
                )
            } else {
                (format!("unexpected {found_text}"), String::new())
            }
        }
        ErrorVariant::CustomError { message } => (message.clone(), String::new()),
    };
    let label = if found == "end of file" {
        "the file ends here"
    } else {
        "here"
    };
    let mut d = Diagnostic::error("syntax", message).with_primary(Span::new(pos, end), label);
    // An expression cut short by the next declaration, or by the end of the file,
    // usually has an unclosed `(` or `|`: point at it.
    let cut_short = found == "end of file" || (keyword && expected.contains("an operator"));
    let unclosed = if cut_short {
        unclosed_delimiter(source, pos)
    } else {
        None
    };
    if let Some(open) = unclosed {
        let what = if source.as_bytes().get(open) == Some(&b'(') {
            "`(`"
        } else {
            "`|`"
        };
        d = d.with_secondary(
            Span::new(open, open + 1),
            format!("this {what} is never closed"),
        );
    }
    let help = if found == "`^`" {
        Some("powers are not part of the language; write products such as u*u or u*|u|".to_string())
    } else if expected.contains("a name") && keyword {
        Some(format!("{found} is reserved; choose another name"))
    } else if unclosed.is_some() {
        Some(
            "close the modulus or parenthesis before the next declaration, e.g. X*u*|water.u|"
                .to_string(),
        )
    } else if expected.contains("an expression") || expected.contains("an operand") {
        Some("each term is a product of a parameter, numbers and at most two signals, e.g. X_uu*water.u*|water.u|".to_string())
    } else if found == "end of file" {
        Some("a model ends with `}`; check for an unclosed `{`, `(` or `|`".to_string())
    } else if expected.contains("a declaration") || expected.contains("end of file") {
        Some(
            "declarations are: step, state, input, heading, rotation, disturbance, `name = relative(..)`, der, next, nominal, data"
                .to_string(),
        )
    } else {
        None
    };
    if let Some(h) = help {
        d = d.with_help(h);
    }
    d
}

fn is_keyword(word: &str) -> bool {
    matches!(
        word,
        "model"
            | "step"
            | "state"
            | "input"
            | "heading"
            | "integrates"
            | "axes"
            | "rotation"
            | "disturbance"
            | "unmeasured"
            | "measured"
            | "earth"
            | "body"
            | "relative"
            | "der"
            | "next"
            | "nominal"
            | "data"
    )
}

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

fn idents(p: Pair<Rule>) -> Vec<Ident> {
    p.into_inner()
        .filter(|q| q.as_rule() == Rule::ident)
        .map(ident)
        .collect()
}

fn number(p: Pair<Rule>) -> Number {
    let text: String = p.as_str().chars().filter(|c| !c.is_whitespace()).collect();
    Number {
        text,
        span: span_of(&p),
    }
}

fn build_model(p: Pair<Rule>) -> ModelSyntax {
    let span = span_of(&p);
    let mut inner = p.into_inner();
    let name = inner.next().map(ident).unwrap_or(Ident {
        name: String::new(),
        span,
    });
    let items = inner.filter_map(build_item).collect();
    ModelSyntax { name, items, span }
}

fn build_item(p: Pair<Rule>) -> Option<Item> {
    let span = span_of(&p);
    let rule = p.as_rule();
    let mut inner = p.into_inner();
    Some(match rule {
        Rule::step_decl => Item::Step {
            value: number(inner.next()?),
            span,
        },
        Rule::state_decl => Item::States(
            inner
                .filter(|q| q.as_rule() == Rule::ident)
                .map(ident)
                .collect(),
        ),
        Rule::input_decl => Item::Inputs(
            inner
                .filter(|q| q.as_rule() == Rule::ident)
                .map(ident)
                .collect(),
        ),
        Rule::heading_decl => {
            let name = ident(inner.next()?);
            let integrates = ident(inner.next()?);
            let axes = inner.next().and_then(|a| {
                let v = idents(a);
                let mut it = v.into_iter();
                Some((it.next()?, it.next()?))
            });
            Item::Heading {
                name,
                integrates,
                axes,
                span,
            }
        }
        Rule::rotation_decl => {
            let rows = inner
                .filter(|q| q.as_rule() == Rule::rotation_row)
                .filter_map(|row| {
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
                })
                .collect();
            Item::Rotation { rows, span }
        }
        Rule::disturbance_decl => {
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
            Item::Disturbance {
                name,
                measurement,
                frame,
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
        Rule::equation => {
            let kind = match inner.next()?.as_str() {
                "next" => EquationKind::Next,
                _ => EquationKind::Der,
            };
            let state = ident(inner.next()?);
            let rhs = build_expr(inner.next()?);
            Item::Equation {
                kind,
                state,
                rhs,
                span,
            }
        }
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
                .filter_map(|e| {
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
                })
                .collect();
            Item::Data { entries, span }
        }
        _ => return None,
    })
}

fn build_expr(p: Pair<Rule>) -> Expr {
    let span = span_of(&p);
    match p.as_rule() {
        Rule::expr => {
            let mut inner = p.into_inner().peekable();
            let negate = match inner.peek().map(|q| q.as_rule()) {
                Some(Rule::sign) => inner.next().is_some_and(|s| s.as_str() == "-"),
                _ => false,
            };
            let Some(first) = inner.next() else {
                return Expr::Number(Number {
                    text: "0".into(),
                    span,
                });
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
                let rhs = build_expr(rhs);
                let s = acc.span().join(rhs.span());
                acc = Expr::Binary {
                    op,
                    lhs: Box::new(acc),
                    rhs: Box::new(rhs),
                    span: s,
                };
            }
            acc
        }
        Rule::product => {
            let mut inner = p.into_inner();
            let Some(first) = inner.next() else {
                return Expr::Number(Number {
                    text: "0".into(),
                    span,
                });
            };
            let mut acc = build_expr(first);
            while let (Some(op), Some(rhs)) = (inner.next(), inner.next()) {
                let op = if op.as_str() == "/" {
                    BinOp::Div
                } else {
                    BinOp::Mul
                };
                let rhs = build_expr(rhs);
                let s = acc.span().join(rhs.span());
                acc = Expr::Binary {
                    op,
                    lhs: Box::new(acc),
                    rhs: Box::new(rhs),
                    span: s,
                };
            }
            acc
        }
        Rule::number => Expr::Number(number(p)),
        Rule::path => {
            let mut inner = p.into_inner();
            let base = inner.next().map(ident).unwrap_or(Ident {
                name: String::new(),
                span,
            });
            let field = inner.next().map(ident);
            Expr::Path(Path { base, field, span })
        }
        Rule::modulus | Rule::paren | Rule::negated => {
            let rule = p.as_rule();
            let inner = p
                .into_inner()
                .next()
                .map(build_expr)
                .unwrap_or(Expr::Number(Number {
                    text: "0".into(),
                    span,
                }));
            match rule {
                Rule::modulus => Expr::Abs(Box::new(inner), span),
                Rule::paren => Expr::Paren(Box::new(inner), span),
                _ => Expr::Neg(Box::new(inner), span),
            }
        }
        _ => Expr::Number(Number {
            text: "0".into(),
            span,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(src: &str) -> Diagnostic {
        let (model, diags) = parse(src);
        assert!(model.is_none(), "{src:?} should not parse");
        assert_eq!(diags.len(), 1, "{diags:?}");
        diags
            .into_iter()
            .next()
            .unwrap_or_else(|| Diagnostic::error("none", ""))
    }

    fn at(src: &str, d: &Diagnostic) -> String {
        let span = d.primary_span().unwrap_or_default();
        src.get(span.start..span.end)
            .unwrap_or("<bad span>")
            .to_string()
    }

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

    #[test]
    fn syntax_errors_name_what_was_expected_and_found() {
        let src = "model M {\n    state u\n    der u = X*u^2\n}\n";
        let d = error(src);
        assert_eq!(d.code, "syntax");
        assert_eq!(
            d.message,
            "expected a declaration or an operator, found `^`"
        );
        assert_eq!(at(src, &d), "^");
        assert!(d.help.as_deref().is_some_and(|h| h.contains("powers")));

        let src = "model M {\n    state u, input\n}\n";
        let d = error(src);
        assert_eq!(d.message, "expected a name, found the keyword `input`");
        assert_eq!(at(src, &d), "input", "the whole keyword is underlined");
        assert_eq!(
            d.help.as_deref(),
            Some("`input` is reserved; choose another name")
        );

        let src = "model M {\n    state u\n    der u = X*\n}\n";
        let d = error(src);
        assert!(d.message.starts_with("expected "), "{}", d.message);
        assert!(d.message.ends_with("found `}`"), "{}", d.message);

        let src = "model M {\n    stat u\n}\n";
        let d = error(src);
        assert_eq!(d.message, "expected a declaration, found `stat`");
        assert!(
            d.help
                .as_deref()
                .is_some_and(|h| h.starts_with("declarations are:"))
        );
    }

    #[test]
    fn an_unclosed_modulus_is_pointed_at() {
        let src = "model M {\n    state u, v\n    der u = X*u*|u + Y*v\n    der v = Z*v\n}\n";
        let d = error(src);
        assert_eq!(d.message, "expected an operator, found the keyword `der`");
        let open = d.labels.iter().find(|l| !l.primary).map(|l| l.span);
        assert_eq!(
            open,
            Some(Span::new(
                src.find('|').unwrap_or(0),
                src.find('|').unwrap_or(0) + 1
            ))
        );
        assert!(
            d.labels
                .iter()
                .any(|l| l.message == "this `|` is never closed")
        );

        let src = "model M {\n    state u\n    der u = X*(u\n";
        let d = error(src);
        assert!(d.message.ends_with("found end of file"), "{}", d.message);
        assert!(
            d.labels
                .iter()
                .any(|l| l.message == "this `(` is never closed"),
            "{d:?}"
        );
    }

    #[test]
    fn nesting_guard_counts_expressions_only() {
        let deep = format!(
            "model M {{ state u der u = X*{}u{} }}",
            "(".repeat(65),
            ")".repeat(65)
        );
        let d = error(&deep);
        assert_eq!(d.code, "nesting-too-deep");
        assert_eq!(at(&deep, &d), "(");
        let ok = format!(
            "model M {{ state u der u = X*{}u{} }}",
            "(".repeat(64),
            ")".repeat(64)
        );
        assert!(parse(&ok).1.is_empty());
        // Parentheses and bars in comments and strings do not count.
        let quiet = format!(
            "// {}\n/* {} */ model M {{ state u der u = X*u data {{ u = \"{}\" }} }}",
            "(".repeat(100),
            "|".repeat(100),
            "(".repeat(100)
        );
        assert!(parse(&quiet).1.is_empty(), "{:?}", parse(&quiet).1);
    }

    /// Runs `f` on a thread with a small stack, so that recursion proportional
    /// to the input aborts the test instead of passing on a large main stack.
    fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
        let handle = std::thread::Builder::new()
            .stack_size(256 * 1024)
            .spawn(f)
            .unwrap_or_else(|e| panic!("cannot spawn: {e}"));
        handle
            .join()
            .unwrap_or_else(|_| panic!("the parser panicked"))
    }

    #[test]
    fn long_chains_and_sign_runs_are_rejected_before_parsing() {
        // Issue 10 reproducers: 7,200 `*1`, `+1`, `/1` after `X*u`, and 7,200 unary `-`.
        for op in ["*1", "+1", "/1", "+X*u"] {
            let src = format!("model M {{ state u der u = X*u{} }}", op.repeat(7200));
            let (model, d) = on_small_stack(move || {
                let (m, d) = parse(&src);
                (m.is_some(), d)
            });
            assert!(!model);
            assert_eq!(d.len(), 1, "{op}");
            assert_eq!(d[0].code, "expression-too-large");
            assert_eq!(d[0].message, "this expression has more than 1000 operands");
        }
        let src = format!("model M {{ state u der u = X*{}u }}", "-".repeat(7200));
        let d = error(&src);
        assert_eq!(d.code, "expression-too-large");
        assert_eq!(d.message, "more than 8 signs in a row");
        assert_eq!(at(&src, &d), "-".repeat(9));
        // At the limits, the model parses (on a small stack: the tree is bounded).
        let ok = format!(
            "model M {{ state u der u = X*u{} + {}u }}",
            "*1".repeat(MAX_OPERANDS - 3),
            "- ".repeat(MAX_SIGNS)
        );
        let diags = on_small_stack(move || parse(&ok).1);
        assert!(diags.is_empty(), "{diags:?}");
        // Exponent signs are part of the number; declarations start new expressions.
        let many = format!(
            "model M {{ state u {} nominal {{ {} }} }}",
            "der u = 1e-3*X*u ".repeat(1200),
            (0..1200)
                .map(|i| format!("P{i} = -1e-3,"))
                .collect::<String>()
        );
        assert!(
            parse(&many)
                .1
                .iter()
                .all(|d| d.code != "expression-too-large")
        );
    }

    #[test]
    fn oversized_input_is_rejected_up_front() {
        let big = " ".repeat(MAX_SOURCE_BYTES + 1);
        let d = error(&big);
        assert_eq!(d.code, "file-too-large");
        assert_eq!(d.primary_span(), Some(Span::new(0, 0)));
    }

    #[test]
    fn found_token_is_character_aware() {
        assert_eq!(found_token("é*u", 0), ("`é`".to_string(), 2));
        assert_eq!(found_token("abc_1.u rest", 0), ("`abc_1.u`".to_string(), 7));
        assert_eq!(found_token("x", 1), ("end of file".to_string(), 1));
        assert_eq!(found_token("\nx", 0), ("end of line".to_string(), 1));
        assert_eq!(found_token("\u{0}x", 0), ("`\\u{0}`".to_string(), 1));
        let src = "model M { state é }";
        let d = error(src);
        assert_eq!(at(src, &d), "é");
    }
}
