//! Text → syntax tree. pest types never leave this module.

use crate::ast::*;
use crate::diagnostic::Diagnostic;
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

/// Parses a `.som` source. pest stops at the first syntax error, so a failed
/// parse returns exactly one diagnostic.
pub fn parse(source: &str) -> (Option<Model>, Vec<Diagnostic>) {
    if source.len() > MAX_SOURCE_BYTES {
        let d = Diagnostic::error(
            "file-too-large",
            format!("the model file is {} bytes; at most {} are accepted", source.len(), MAX_SOURCE_BYTES),
        )
        .with_primary(Span::new(0, 0), "")
        .with_help("a model file holds one craft's equations; split generated text or remove embedded data");
        return (None, vec![d]);
    }
    if let Some(d) = nesting_guard(source) {
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
        Rule::data_entry => "`signal = \"column\"`",
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

fn build_model(p: Pair<Rule>) -> Model {
    let span = span_of(&p);
    let mut inner = p.into_inner();
    let name = inner.next().map(ident).unwrap_or(Ident {
        name: String::new(),
        span,
    });
    let items = inner.filter_map(build_item).collect();
    Model { name, items, span }
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
                    let sig = ident(it.next()?);
                    let s = it.next()?;
                    let sspan = span_of(&s);
                    let text = s
                        .into_inner()
                        .next()
                        .map(|x| x.as_str().to_string())
                        .unwrap_or_default();
                    Some((sig, text, sspan))
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
