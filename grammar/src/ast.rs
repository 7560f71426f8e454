//! The typed syntax tree of a `.som` file. Every node carries the byte span
//! of its source text so later passes can point at it.

use serde::{Deserialize, Serialize};

/// A byte range `start..end` into the source text.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
pub struct Span {
    /// First byte.
    pub start: usize,
    /// One past the last byte.
    pub end: usize,
}

impl Span {
    /// A span from `start` to `end`.
    pub fn new(start: usize, end: usize) -> Self {
        Span { start, end }
    }
    /// The smallest span covering both.
    pub fn join(self, other: Span) -> Span {
        Span::new(self.start.min(other.start), self.end.max(other.end))
    }
}

/// A name as written, with its span.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ident {
    /// The identifier text.
    pub name: String,
    /// Where it was written.
    pub span: Span,
}

/// A numeric literal, kept as written so later passes convert it exactly.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Number {
    /// The literal text, including a leading sign where the grammar allows one.
    pub text: String,
    /// Where it was written.
    pub span: Span,
}

/// A whole model file as written: the syntax tree [`parse`](crate::parse) returns.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelSyntax {
    /// `model Name`.
    pub name: Ident,
    /// The declarations in source order.
    pub items: Vec<Item>,
    /// The whole `model { ... }`.
    pub span: Span,
}

/// Continuous (`der`, explicit Euler) or discrete (`next`) state equation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum EquationKind {
    /// `der x = f`: `x(k+1) = x(k) + h f`.
    Der,
    /// `next x = f`: `x(k+1) = f`.
    Next,
}

/// Whether a disturbance is measured (by an auxiliary sensor) or not.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Measurement {
    /// Unknown; its moments are estimated as nuisance parameters.
    Unmeasured,
    /// Given in the data (IV3's `y_aux`).
    Measured,
}

/// The frame a disturbance is expressed in.
#[derive(Clone, Debug, PartialEq)]
pub enum Frame {
    /// Earth-fixed components, rotated into the body frame by `R`.
    Earth(Vec<Ident>),
    /// Body-frame components, each acting on one named state.
    Body(Vec<BodyComponent>),
}

/// `state: component` inside `body(...)`.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyComponent {
    /// The state the component acts on.
    pub state: Ident,
    /// The component's name (a data column when measured).
    pub component: Ident,
}

/// One row of a measured rotation matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationRow {
    /// The state this row belongs to.
    pub state: Ident,
    /// Data columns (or `None` for a literal zero).
    pub entries: Vec<Option<Ident>>,
    /// The whole row.
    pub span: Span,
}

/// The unit of a declared dead time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DelayUnit {
    /// Samples (`steps`).
    Steps,
    /// Seconds (`s`).
    Seconds,
}

/// A declaration inside `model { ... }`.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    /// `step h`.
    Step {
        /// The sample time.
        value: Number,
        /// The declaration.
        span: Span,
    },
    /// `state a, b`.
    States(Vec<Ident>),
    /// `input a, b`.
    Inputs(Vec<Ident>),
    /// `heading psi integrates r [axes(u, v)]`.
    Heading {
        /// The heading signal.
        name: Ident,
        /// The yaw-rate state it integrates.
        integrates: Ident,
        /// The body axes the rotation acts on (default: the first two states).
        axes: Option<(Ident, Ident)>,
        /// The declaration.
        span: Span,
    },
    /// `rotation { row = [..] ... }`.
    Rotation {
        /// Rows by state.
        rows: Vec<RotationRow>,
        /// The declaration.
        span: Span,
    },
    /// `disturbance name (un)measured frame(...)`.
    Disturbance {
        /// The disturbance's name.
        name: Ident,
        /// Measured or not.
        measurement: Measurement,
        /// Earth or body frame with its components.
        frame: Frame,
        /// The declaration.
        span: Span,
    },
    /// `delay input amount steps` or `delay input amount s`.
    Delay {
        /// The delayed input.
        input: Ident,
        /// The dead time as written (may carry a sign: checked later).
        amount: Number,
        /// Samples or seconds.
        unit: DelayUnit,
        /// The declaration.
        span: Span,
    },
    /// `name = relative(disturbance)`.
    Relative {
        /// The relative velocity's name.
        name: Ident,
        /// The medium.
        disturbance: Ident,
        /// The declaration.
        span: Span,
    },
    /// `der x = expr` or `next x = expr`.
    Equation {
        /// `der` or `next`.
        kind: EquationKind,
        /// The state.
        state: Ident,
        /// The right-hand side.
        rhs: Expr,
        /// The declaration.
        span: Span,
    },
    /// `nominal { name = value, ... }`.
    Nominal {
        /// Entries in order.
        entries: Vec<(Ident, Number)>,
        /// The block.
        span: Span,
    },
    /// `data { signal = "column" in unit, ... }`.
    Data {
        /// Entries in order.
        entries: Vec<DataEntry>,
        /// The block.
        span: Span,
    },
}

/// One entry of `data { }`: a signal with its column name, its unit, or both.
#[derive(Clone, Debug, PartialEq)]
pub struct DataEntry {
    /// The model's signal (or `time`, `experiment`).
    pub signal: Ident,
    /// The CSV column name, with the string literal's span.
    pub column: Option<(String, Span)>,
    /// The unit as written after `in`, with its span.
    pub unit: Option<(String, Span)>,
}

/// `base` or `base.field` (a relative-velocity component such as `water.u`).
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    /// The first name.
    pub base: Ident,
    /// The component after the dot.
    pub field: Option<Ident>,
    /// Written `?name`: a candidate parameter, kept or dropped by `leeway
    /// select` (a dropped one is held at 0). The `?` is the first byte of
    /// [`Path::span`]; the compiler treats the parameter like any other.
    pub candidate: bool,
    /// The whole path, the `?` included.
    pub span: Span,
}

impl Path {
    /// The path as written, without a candidate's `?`: `water.u` or `u`.
    pub fn text(&self) -> String {
        match &self.field {
            Some(f) => format!("{}.{}", self.base.name, f.name),
            None => self.base.name.clone(),
        }
    }
}

/// Binary operators of the expression language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
}

/// An expression on the right-hand side of an equation.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A numeric literal.
    Number(Number),
    /// A name: signal, relative-velocity component or parameter.
    Path(Path),
    /// `|e|`.
    Abs(Box<Expr>, Span),
    /// `-e`.
    Neg(Box<Expr>, Span),
    /// `(e)`.
    Paren(Box<Expr>, Span),
    /// `a op b`.
    Binary {
        /// The operator.
        op: BinOp,
        /// Left operand.
        lhs: Box<Expr>,
        /// Right operand.
        rhs: Box<Expr>,
        /// The whole expression.
        span: Span,
    },
}

impl Expr {
    /// The source span of the expression.
    pub fn span(&self) -> Span {
        match self {
            Expr::Number(n) => n.span,
            Expr::Path(p) => p.span,
            Expr::Abs(_, s) | Expr::Neg(_, s) | Expr::Paren(_, s) => *s,
            Expr::Binary { span, .. } => *span,
        }
    }
}
