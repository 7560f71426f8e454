//! The syntax tree → lines of code with the source spans they print, each
//! declaration broken where its author broke it or where it passes the width.

use crate::comments::{Comment, brace_after};
use crate::expr;
use leeway_grammar::{
    BinOp, DataEntry, DelayUnit, EquationKind, Frame, Ident, Item, Measurement, ModelSyntax, Span,
};

/// The column a continued line is broken before (when a break is allowed there).
pub const WIDTH: usize = 100;

/// One line of code: what it prints and the source it came from.
#[derive(Clone, Debug)]
pub(crate) struct Line {
    /// Spaces before the text.
    pub indent: usize,
    /// The code.
    pub text: String,
    /// The first source byte of its code.
    pub start: usize,
    /// One past the last source byte of its code.
    pub end: usize,
    /// Whether it begins a declaration (a blank line may precede it).
    pub item_start: bool,
}

/// A piece of a declaration that is never broken, with the source it prints.
struct Seg {
    text: String,
    span: Span,
}

/// A declaration as its head (which starts the line), the pieces that may
/// each begin a continuation line, and a closing `}`.
struct Run {
    head: Seg,
    body: Vec<Seg>,
    /// Between the head and the first piece on one line.
    join_first: &'static str,
    /// Between two pieces on one line.
    join: &'static str,
    /// After a piece that ends a line with more pieces to come.
    line_end: &'static str,
    /// `}` of a block.
    tail: Option<Seg>,
    /// Where continuation lines start (relative to the declaration) when
    /// the first piece shares the head's line.
    hang: usize,
}

const INDENT: usize = 4;

/// The model's lines: `model Name {`, each declaration, `}`.
pub(crate) fn lines(model: &ModelSyntax, source: &str, comments: &[Comment]) -> Vec<Line> {
    let brace = brace_after(source, model.name.span.end).unwrap_or(model.name.span.end);
    let mut out = vec![Line {
        indent: 0,
        text: format!("model {} {{", model.name.name),
        start: model.span.start,
        end: brace + 1,
        item_start: true,
    }];
    for item in &model.items {
        let mut run = run(item);
        // pest's spans of rules ending in an optional part (`axes?`, `","?`)
        // reach over the blanks and comments that follow them.
        for seg in std::iter::once(&mut run.head).chain(run.body.iter_mut()) {
            seg.span = trim(source, comments, seg.span);
        }
        lay_out(&run, source, INDENT, &mut out);
    }
    let close = model.span.end.saturating_sub(1);
    out.push(Line {
        indent: 0,
        text: "}".into(),
        start: close,
        end: model.span.end,
        item_start: true,
    });
    out
}

/// `span` without the blanks and comments at its end.
fn trim(source: &str, comments: &[Comment], span: Span) -> Span {
    let mut end = span.end.min(source.len());
    loop {
        let Some(text) = source.get(span.start..end) else {
            return span;
        };
        end = span.start + text.trim_end().len();
        match comments
            .iter()
            .find(|c| c.span.end == end && c.span.start >= span.start)
        {
            Some(c) => end = c.span.start,
            None => return Span::new(span.start, end),
        }
    }
}

fn broken(source: &str, from: usize, to: usize) -> bool {
    from < to && source.get(from..to).is_some_and(|gap| gap.contains('\n'))
}

/// Breaks a run into lines: where the source had a newline between two
/// pieces, and before a piece that would pass the width.
fn lay_out(run: &Run, source: &str, indent: usize, out: &mut Vec<Line>) {
    let first = out.len();
    out.push(Line {
        indent,
        text: run.head.text.clone(),
        start: run.head.span.start,
        end: run.head.span.end,
        item_start: true,
    });
    let mut block = false;
    let mut prev_end = run.head.span.end;
    for (i, seg) in run.body.iter().enumerate() {
        let Some(line) = out.last_mut() else { return };
        let join = if i == 0 { run.join_first } else { run.join };
        // What may still follow on the line: a list's comma, a block's ` }`.
        let reserve = if i + 1 < run.body.len() {
            run.line_end.len()
        } else if run.tail.is_some() {
            2
        } else {
            0
        };
        let width = line.indent
            + line.text.chars().count()
            + join.len()
            + seg.text.chars().count()
            + reserve;
        if broken(source, prev_end, seg.span.start) || width > WIDTH {
            if i == 0 && run.tail.is_some() {
                block = true;
            } else {
                line.text.push_str(run.line_end);
            }
            let cont = if block { INDENT } else { run.hang };
            out.push(Line {
                indent: indent + cont,
                text: seg.text.clone(),
                start: seg.span.start,
                end: seg.span.end,
                item_start: false,
            });
        } else {
            line.text.push_str(join);
            line.text.push_str(&seg.text);
            line.end = seg.span.end;
        }
        prev_end = seg.span.end;
    }
    if let Some(tail) = &run.tail {
        let own_line = block || broken(source, prev_end, tail.span.start);
        match out.last_mut() {
            Some(line) if !own_line => {
                line.text.push(' ');
                line.text.push_str(&tail.text);
                line.end = tail.span.end;
            }
            _ => out.push(Line {
                indent,
                text: tail.text.clone(),
                start: tail.span.start,
                end: tail.span.end,
                item_start: false,
            }),
        }
    }
    debug_assert!(out.len() > first);
}

fn seg(text: impl Into<String>, span: Span) -> Seg {
    Seg {
        text: text.into(),
        span,
    }
}

/// A declaration that is one piece.
fn whole(text: String, span: Span) -> Run {
    Run {
        head: seg(text, span),
        body: Vec::new(),
        join_first: "",
        join: "",
        line_end: "",
        tail: None,
        hang: 0,
    }
}

/// `keyword a, b, c`.
fn list(keyword: &str, names: &[Ident]) -> Run {
    let (head, rest) = match names.split_first() {
        Some((h, rest)) => (seg(format!("{keyword} {}", h.name), h.span), rest),
        None => (seg(keyword, Span::default()), &[][..]),
    };
    Run {
        head,
        body: rest.iter().map(|n| seg(n.name.clone(), n.span)).collect(),
        join_first: ", ",
        join: ", ",
        line_end: ",",
        tail: None,
        hang: keyword.len() + 1,
    }
}

/// `keyword { entries }`, the `}` at the block's end.
fn block(keyword: &str, span: Span, body: Vec<Seg>, separator: &'static str) -> Run {
    let open = span.start;
    Run {
        head: seg(
            format!("{keyword} {{"),
            Span::new(open, open + keyword.len()),
        ),
        body,
        join_first: " ",
        join: if separator.is_empty() { " " } else { ", " },
        line_end: separator,
        tail: Some(seg("}", Span::new(span.end.saturating_sub(1), span.end))),
        hang: keyword.len() + 3,
    }
}

fn names(list: &[Ident]) -> String {
    list.iter()
        .map(|n| n.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

fn run(item: &Item) -> Run {
    match item {
        Item::Step { value, span } => whole(format!("step {}", value.text), *span),
        Item::States(names) => list("state", names),
        Item::Inputs(names) => list("input", names),
        Item::Heading {
            name,
            integrates,
            axes,
            span,
        } => {
            let mut text = format!("heading {} integrates {}", name.name, integrates.name);
            if let Some((a, b)) = axes {
                text.push_str(&format!(" axes({}, {})", a.name, b.name));
            }
            whole(text, *span)
        }
        Item::Rotation { rows, span } => {
            let body = rows
                .iter()
                .map(|row| {
                    let entries: Vec<&str> = row
                        .entries
                        .iter()
                        .map(|e| e.as_ref().map_or("0", |i| i.name.as_str()))
                        .collect();
                    seg(
                        format!("{} = [{}]", row.state.name, entries.join(", ")),
                        row.span,
                    )
                })
                .collect();
            block("rotation", *span, body, "")
        }
        Item::Disturbance {
            name,
            measurement,
            frame,
            span,
        } => {
            let measured = match measurement {
                Measurement::Unmeasured => "unmeasured",
                Measurement::Measured => "measured",
            };
            let frame = match frame {
                Frame::Earth(components) => format!("earth({})", names(components)),
                Frame::Body(components) => {
                    let parts: Vec<String> = components
                        .iter()
                        .map(|c| format!("{}: {}", c.state.name, c.component.name))
                        .collect();
                    format!("body({})", parts.join(", "))
                }
            };
            whole(
                format!("disturbance {} {measured} {frame}", name.name),
                *span,
            )
        }
        Item::Delay {
            input,
            amount,
            unit,
            span,
        } => {
            let unit = match unit {
                DelayUnit::Steps => "steps",
                DelayUnit::Seconds => "s",
            };
            whole(
                format!("delay {} {} {unit}", input.name, amount.text),
                *span,
            )
        }
        Item::Relative {
            name,
            disturbance,
            span,
        } => whole(
            format!("{} = relative({})", name.name, disturbance.name),
            *span,
        ),
        Item::Equation {
            kind,
            state,
            rhs,
            span,
        } => {
            let kind = match kind {
                EquationKind::Der => "der",
                EquationKind::Next => "next",
            };
            let lead = format!("{kind} {} ", state.name);
            let hang = lead.len();
            let terms = expr::terms(rhs);
            let mut pieces = terms.iter().map(|(op, term)| {
                let text = expr::text(term);
                match op {
                    Some(BinOp::Sub) => seg(format!("- {text}"), term.span()),
                    Some(_) => seg(format!("+ {text}"), term.span()),
                    None => seg(text, term.span()),
                }
            });
            let head = match pieces.next() {
                Some(first) => seg(
                    format!("{lead}= {}", first.text),
                    Span::new(span.start, first.span.end),
                ),
                None => seg(format!("{lead}="), *span),
            };
            Run {
                head,
                body: pieces.collect(),
                join_first: " ",
                join: " ",
                line_end: "",
                tail: None,
                hang,
            }
        }
        Item::Nominal { entries, span } => {
            let body = entries
                .iter()
                .map(|(name, value)| {
                    seg(
                        format!("{} = {}", name.name, value.text),
                        name.span.join(value.span),
                    )
                })
                .collect();
            block("nominal", *span, body, ",")
        }
        Item::Data { entries, span } => {
            let body = entries.iter().map(data_entry).collect();
            block("data", *span, body, ",")
        }
    }
}

fn data_entry(e: &DataEntry) -> Seg {
    let mut text = e.signal.name.clone();
    let mut span = e.signal.span;
    if let Some((column, at)) = &e.column {
        text.push_str(&format!(" = \"{column}\""));
        span = span.join(*at);
    }
    if let Some((unit, at)) = &e.unit {
        text.push_str(&format!(" in {unit}"));
        span = span.join(*at);
    }
    seg(text, span)
}
