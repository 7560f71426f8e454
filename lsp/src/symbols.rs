//! Every name of a model's syntax tree: where it is declared and where it
//! is used, by what it names. Built from the tree alone, so it answers for
//! a model that parses but does not compile.

use leeway_grammar::{Expr, Frame, Ident, Item, ModelSyntax, Span};
use std::collections::BTreeSet;

/// What a name names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    /// A state (`state u`).
    State,
    /// A known input.
    Input,
    /// The heading signal of `heading psi integrates r`.
    Heading,
    /// A column of a measured rotation.
    RotationColumn,
    /// A disturbance (a medium): `disturbance current ...`.
    Medium,
    /// A component of a disturbance (`north`).
    Component,
    /// A relative velocity (`water = relative(current)`).
    Relative,
    /// A parameter of θ.
    Parameter,
}

impl Kind {
    /// The word for it in hovers and symbols.
    pub fn word(self) -> &'static str {
        match self {
            Kind::State => "state",
            Kind::Input => "input",
            Kind::Heading => "heading",
            Kind::RotationColumn => "rotation column",
            Kind::Medium => "disturbance",
            Kind::Component => "disturbance component",
            Kind::Relative => "relative velocity",
            Kind::Parameter => "parameter",
        }
    }
}

/// One place a name is written.
#[derive(Clone, Debug)]
pub struct Occurrence {
    /// The name.
    pub name: String,
    /// What it names.
    pub kind: Kind,
    /// Where.
    pub span: Span,
    /// A declaration (or, for a parameter, its `nominal` entry).
    pub declaration: bool,
    /// The declaration item's span, for declarations.
    pub item: Span,
}

/// Every occurrence of every name, in source order.
#[derive(Clone, Debug, Default)]
pub struct Symbols {
    /// The occurrences.
    pub occurrences: Vec<Occurrence>,
}

fn item_span(item: &Item) -> Span {
    match item {
        Item::States(v) | Item::Inputs(v) => v
            .iter()
            .map(|i| i.span)
            .reduce(Span::join)
            .unwrap_or_default(),
        Item::Step { span, .. }
        | Item::Heading { span, .. }
        | Item::Rotation { span, .. }
        | Item::Disturbance { span, .. }
        | Item::Delay { span, .. }
        | Item::Relative { span, .. }
        | Item::Equation { span, .. }
        | Item::Nominal { span, .. }
        | Item::Data { span, .. } => *span,
    }
}

impl Symbols {
    /// The names of `model`.
    pub fn of(model: &ModelSyntax) -> Symbols {
        let mut s = Symbols::default();
        // Signals first: a name in an equation that is none of them is a parameter.
        let mut signals: Vec<(String, Kind)> = Vec::new();
        for item in &model.items {
            let at = item_span(item);
            let mut decl = |s: &mut Symbols, i: &Ident, kind: Kind| {
                signals.push((i.name.clone(), kind));
                s.push(i, kind, true, at);
            };
            match item {
                Item::States(v) => v.iter().for_each(|i| decl(&mut s, i, Kind::State)),
                Item::Inputs(v) => v.iter().for_each(|i| decl(&mut s, i, Kind::Input)),
                Item::Heading { name, .. } => decl(&mut s, name, Kind::Heading),
                Item::Rotation { rows, .. } => rows
                    .iter()
                    .flat_map(|r| r.entries.iter().flatten())
                    .for_each(|i| decl(&mut s, i, Kind::RotationColumn)),
                Item::Disturbance { name, frame, .. } => {
                    decl(&mut s, name, Kind::Medium);
                    match frame {
                        Frame::Earth(c) => c.iter().for_each(|i| decl(&mut s, i, Kind::Component)),
                        Frame::Body(c) => c
                            .iter()
                            .for_each(|b| decl(&mut s, &b.component, Kind::Component)),
                    }
                }
                Item::Relative { name, .. } => decl(&mut s, name, Kind::Relative),
                _ => {}
            }
        }
        let kind_of = |name: &str| {
            signals
                .iter()
                .find(|(n, _)| n == name)
                .map_or(Kind::Parameter, |(_, k)| *k)
        };
        for item in &model.items {
            let at = item_span(item);
            match item {
                Item::Heading {
                    integrates, axes, ..
                } => {
                    s.push(integrates, kind_of(&integrates.name), false, at);
                    if let Some((a, b)) = axes {
                        s.push(a, kind_of(&a.name), false, at);
                        s.push(b, kind_of(&b.name), false, at);
                    }
                }
                Item::Rotation { rows, .. } => {
                    for r in rows {
                        s.push(&r.state, kind_of(&r.state.name), false, at);
                    }
                }
                Item::Disturbance {
                    frame: Frame::Body(c),
                    ..
                } => c
                    .iter()
                    .for_each(|b| s.push(&b.state, kind_of(&b.state.name), false, at)),
                Item::Delay { input, .. } => s.push(input, kind_of(&input.name), false, at),
                Item::Relative { disturbance, .. } => {
                    s.push(disturbance, kind_of(&disturbance.name), false, at)
                }
                Item::Equation { state, rhs, .. } => {
                    s.push(state, kind_of(&state.name), false, at);
                    s.expr(rhs, &kind_of, at);
                }
                Item::Nominal { entries, .. } => {
                    for (name, _) in entries {
                        s.push(name, kind_of(&name.name), true, at);
                    }
                }
                Item::Data { entries, .. } => {
                    for e in entries {
                        s.push(&e.signal, kind_of(&e.signal.name), false, at);
                    }
                }
                _ => {}
            }
        }
        s.occurrences.sort_by_key(|o| o.span.start);
        s
    }

    fn push(&mut self, i: &Ident, kind: Kind, declaration: bool, item: Span) {
        self.occurrences.push(Occurrence {
            name: i.name.clone(),
            kind,
            span: i.span,
            declaration,
            item,
        });
    }

    fn expr(&mut self, e: &Expr, kind_of: &dyn Fn(&str) -> Kind, at: Span) {
        // Iterative: a right-hand side may hold a thousand operands.
        let mut stack = vec![e];
        while let Some(e) = stack.pop() {
            match e {
                Expr::Number(_) => {}
                Expr::Path(p) => {
                    self.push(&p.base, kind_of(&p.base.name), false, at);
                    if let Some(f) = &p.field {
                        self.push(f, kind_of(&f.name), false, at);
                    }
                }
                Expr::Abs(x, _) | Expr::Neg(x, _) | Expr::Paren(x, _) => stack.push(x),
                Expr::Binary { lhs, rhs, .. } => {
                    stack.push(rhs);
                    stack.push(lhs);
                }
            }
        }
    }

    /// The occurrence whose name covers byte `at` (or ends there).
    pub fn at(&self, at: usize) -> Option<&Occurrence> {
        self.occurrences
            .iter()
            .find(|o| o.span.start <= at && at <= o.span.end)
    }

    /// The declarations of a name (a parameter without a `nominal` entry:
    /// its first use).
    pub fn declarations(&self, name: &str, kind: Kind) -> Vec<&Occurrence> {
        let same = || {
            self.occurrences
                .iter()
                .filter(move |o| o.name == name && o.kind == kind)
        };
        let declared: Vec<&Occurrence> = same().filter(|o| o.declaration).collect();
        if declared.is_empty() {
            same().take(1).collect()
        } else {
            declared
        }
    }

    /// Every occurrence of a name.
    pub fn references(&self, name: &str, kind: Kind) -> Vec<&Occurrence> {
        self.occurrences
            .iter()
            .filter(|o| o.name == name && o.kind == kind)
            .collect()
    }

    /// The declared names and the parameters, each once.
    pub fn names(&self) -> BTreeSet<(String, Kind)> {
        self.occurrences
            .iter()
            .map(|o| (o.name.clone(), o.kind))
            .collect()
    }
}
