//! What resolve produces: the symbol table's entries and the resolved
//! declarations of a model.

use crate::exact::Q;
use leeway_grammar::{EquationKind, Expr, Ident, Span};
use std::collections::BTreeMap;

/// What a name refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symbol {
    /// A state.
    State(usize),
    /// An input.
    Input(usize),
    /// The heading.
    Heading,
    /// A rotation data column.
    RotationColumn(usize),
    /// A disturbance.
    Disturbance(usize),
    /// A disturbance component (global index).
    Component(usize),
    /// A relative velocity.
    Relative(usize),
}

/// A resolved disturbance.
#[derive(Clone, Debug)]
pub struct DisturbanceDecl {
    /// Its name.
    pub name: Ident,
    /// Measured or not.
    pub measured: bool,
    /// Earth frame.
    pub earth: bool,
    /// Global component indices.
    pub components: Vec<usize>,
}

/// A resolved component.
#[derive(Clone, Debug)]
pub struct ComponentDecl {
    /// Its name.
    pub name: Ident,
    /// Disturbance index.
    pub disturbance: usize,
    /// Body frame: the state it acts on.
    pub state: Option<usize>,
}

/// The rotation as resolved.
#[derive(Clone, Debug)]
pub enum RotationDecl {
    /// None declared.
    None,
    /// Planar heading.
    Planar {
        /// Heading name.
        heading: Ident,
        /// Integrated state.
        integrates: usize,
        /// Axes.
        axes: [usize; 2],
    },
    /// Measured from columns.
    Measured {
        /// Column names (rotation variables).
        columns: Vec<Ident>,
        /// `rows[state][component]` → column index.
        rows: Vec<Vec<Option<usize>>>,
        /// Number of earth components.
        width: usize,
    },
}

/// An equation awaiting lowering.
#[derive(Clone, Debug)]
pub struct EquationDecl {
    /// `der`/`next`.
    pub kind: EquationKind,
    /// State index.
    pub state: usize,
    /// Right-hand side.
    pub rhs: Expr,
    /// Span of the whole equation.
    pub span: Span,
}

/// The resolved declarations of a model.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// Model name.
    pub name: Ident,
    /// Step.
    pub step: Option<(Q, Span)>,
    /// States.
    pub states: Vec<Ident>,
    /// Inputs.
    pub inputs: Vec<Ident>,
    /// Rotation.
    pub rotation: RotationDecl,
    /// Disturbances.
    pub disturbances: Vec<DisturbanceDecl>,
    /// Components.
    pub components: Vec<ComponentDecl>,
    /// Relatives: (name, disturbance).
    pub relatives: Vec<(Ident, usize)>,
    /// Equations by state (None where missing).
    pub equations: Vec<Option<EquationDecl>>,
    /// Nominal values.
    pub nominal: Vec<(Ident, Q, Span)>,
    /// Data column mapping.
    pub data: Vec<(Ident, String, Span)>,
    /// Declared units of data columns (`data { r in deg/s }`), checked.
    pub units: Vec<(Ident, String, Span)>,
    /// Declared dead times: (input, lag, declaration).
    pub delays: Vec<(usize, crate::ir::Lag, Span)>,
    /// Name table.
    pub symbols: BTreeMap<String, (Symbol, Span)>,
}

/// Names in the data mapping that are not signals but are understood.
pub const SPECIAL_COLUMNS: [&str; 2] = ["time", "experiment"];
