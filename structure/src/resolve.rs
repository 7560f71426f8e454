//! Pass 1, resolve: declarations → symbol tables, with every naming error
//! (duplicates, unknown names, missing rotation, bad shapes) collected.

use crate::exact::{Q, decimal};
use leeway_grammar::{
    BodyComponent, DataEntry, Diagnostic, EquationKind, Expr, Frame, Ident, Item, Measurement,
    ModelSyntax, Number, RotationRow, Span,
};
use num_traits::Zero;
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
    /// Name table.
    pub symbols: BTreeMap<String, (Symbol, Span)>,
}

/// Names in the data mapping that are not signals but are understood.
pub const SPECIAL_COLUMNS: [&str; 2] = ["time", "experiment"];

/// What is wrong with `signal in unit`, as (message, help), or `None` when the
/// unit is known and of a kind the signal can have. The kinds follow from the
/// signal's role where the model fixes it (the heading is an angle, the rate it
/// integrates an angular rate, its axes speeds, `time` a time); a state, input
/// or measured component may be any physical quantity except a time.
fn unit_problem(r: &Resolved, signal: &str, unit: &str) -> Option<(String, String)> {
    use crate::units::{Kind, names_of};
    let every = [
        Kind::Angle,
        Kind::AngularRate,
        Kind::Speed,
        Kind::RotationRate,
    ];
    let (allowed, role): (&[Kind], &str) = match (signal, r.symbols.get(signal)) {
        ("time", _) => (&[Kind::Time], "the time stamps"),
        ("experiment", _) => (&[], "the experiment names"),
        (_, Some((Symbol::Heading, _))) => (&[Kind::Angle], "the heading"),
        (_, Some((Symbol::RotationColumn(_), _))) => (&[], "an entry of a measured rotation"),
        (_, Some((Symbol::State(i), _))) => match &r.rotation {
            RotationDecl::Planar { integrates, .. } if integrates == i => {
                (&[Kind::AngularRate], "the yaw rate the heading integrates")
            }
            RotationDecl::Planar { axes, .. } if axes.contains(i) => {
                (&[Kind::Speed], "a velocity the heading rotates")
            }
            _ => (&every, "a state"),
        },
        _ => (&every, "a signal"),
    };
    let kind = crate::units::unit(unit).map(|(k, _)| k);
    if kind.is_some_and(|k| allowed.contains(&k)) {
        return None;
    }
    if allowed.is_empty() {
        return Some((
            format!("`{signal}` takes no unit: it is {role}"),
            format!("remove `in {unit}`"),
        ));
    }
    let message = match kind {
        Some(k) => format!("`{unit}` is {}, but `{signal}` is {role}", k.name()),
        None => format!("unknown unit `{unit}` for `{signal}`"),
    };
    Some((message, format!("units for {role}: {}", names_of(allowed))))
}

fn duplicate(name: &Ident, first: Span, what: &str) -> Diagnostic {
    Diagnostic::error("duplicate-declaration", format!("`{}` is declared twice", name.name))
        .with_primary(name.span, format!("second declaration of {what}"))
        .with_secondary(first, "first declared here")
        .with_help("every state, input, heading, disturbance, component and relative velocity needs its own name")
}

/// Resolves the declarations of a parsed model.
pub fn resolve(model: &ModelSyntax, diags: &mut Vec<Diagnostic>) -> Resolved {
    let mut r = Resolved {
        name: model.name.clone(),
        step: None,
        states: Vec::new(),
        inputs: Vec::new(),
        rotation: RotationDecl::None,
        disturbances: Vec::new(),
        components: Vec::new(),
        relatives: Vec::new(),
        equations: Vec::new(),
        nominal: Vec::new(),
        data: Vec::new(),
        units: Vec::new(),
        symbols: BTreeMap::new(),
    };
    // States and inputs first: other declarations refer to them.
    declare_states_and_inputs(&mut r, model, diags);
    let rotation_span = resolve_step_and_rotation(&mut r, model, diags);
    // Disturbances, then relatives.
    for item in &model.items {
        if let Item::Disturbance {
            name,
            measurement,
            frame,
            span,
        } = item
        {
            resolve_disturbance(
                &mut r,
                name,
                *measurement,
                frame,
                *span,
                rotation_span,
                diags,
            );
        }
    }
    for item in &model.items {
        if let Item::Relative {
            name, disturbance, ..
        } = item
        {
            resolve_relative(&mut r, name, disturbance, diags);
        }
    }
    resolve_equations_and_data(&mut r, model, diags);
    missing_equations(&r, diags);
    r
}

/// Enters a name in the table, or reports it declared twice (`false`).
fn declare(
    r: &mut Resolved,
    diags: &mut Vec<Diagnostic>,
    id: &Ident,
    sym: Symbol,
    what: &str,
) -> bool {
    if let Some((_, first)) = r.symbols.get(&id.name) {
        diags.push(duplicate(id, *first, what));
        false
    } else {
        r.symbols.insert(id.name.clone(), (sym, id.span));
        true
    }
}

/// The state a name refers to, if it is one.
fn state_of(r: &Resolved, id: &Ident) -> Option<usize> {
    match r.symbols.get(&id.name) {
        Some((Symbol::State(i), _)) => Some(*i),
        _ => None,
    }
}

/// A name where `role` needs a state.
fn not_a_state(r: &Resolved, id: &Ident, role: &str) -> Diagnostic {
    let what = match r.symbols.get(&id.name) {
        Some((Symbol::Input(_), _)) => "an input",
        Some(_) => "not a state",
        None => "not declared",
    };
    Diagnostic::error(
        "unknown-name",
        format!("`{}` is {what}; {role} must be a state", id.name),
    )
    .with_primary(id.span, "expected a state")
    .with_help(format!("declared states: {}", names(&r.states)))
}

/// The states and inputs, and an error when there is no state.
fn declare_states_and_inputs(r: &mut Resolved, model: &ModelSyntax, diags: &mut Vec<Diagnostic>) {
    for item in &model.items {
        match item {
            Item::States(ids) => {
                for id in ids {
                    let k = r.states.len();
                    if declare(r, diags, id, Symbol::State(k), "a state") {
                        r.states.push(id.clone());
                    }
                }
            }
            Item::Inputs(ids) => {
                for id in ids {
                    let k = r.inputs.len();
                    if declare(r, diags, id, Symbol::Input(k), "an input") {
                        r.inputs.push(id.clone());
                    }
                }
            }
            _ => {}
        }
    }
    if r.states.is_empty() {
        diags.push(
            Diagnostic::error(
                "no-states",
                format!("model `{}` declares no state", model.name.name),
            )
            .with_primary(model.name.span, "this model")
            .with_help(
                "declare the measured states, e.g. `state u, v, r`, and give each an equation",
            ),
        );
    }
}

/// The step and the rotation (a heading or a measured `rotation`), in the
/// order written; returns the span of the first heading or rotation.
fn resolve_step_and_rotation(
    r: &mut Resolved,
    model: &ModelSyntax,
    diags: &mut Vec<Diagnostic>,
) -> Option<Span> {
    let mut rotation_span: Option<Span> = None;
    let mut step_span: Option<Span> = None;
    for item in &model.items {
        match item {
            Item::Step { value, span } => {
                if let Some(first) = step_span {
                    diags.push(
                        Diagnostic::error("duplicate-declaration", "`step` is declared twice")
                            .with_primary(*span, "second step")
                            .with_secondary(first, "first declared here")
                            .with_help("a model has one sample time"),
                    );
                    continue;
                }
                step_span = Some(*span);
                resolve_step(r, value, diags);
            }
            Item::Heading {
                name,
                integrates,
                axes,
                span,
            } => {
                if let Some(first) = rotation_span {
                    diags.push(rotation_conflict(*span, first));
                    continue;
                }
                rotation_span = Some(*span);
                resolve_heading(r, name, integrates, axes.as_ref(), *span, diags);
            }
            Item::Rotation { rows, span } => {
                if let Some(first) = rotation_span {
                    diags.push(rotation_conflict(*span, first));
                    continue;
                }
                rotation_span = Some(*span);
                resolve_rotation(r, rows, diags);
            }
            _ => {}
        }
    }
    rotation_span
}

/// `step h`: a positive decimal.
fn resolve_step(r: &mut Resolved, value: &Number, diags: &mut Vec<Diagnostic>) {
    match decimal(&value.text) {
        Ok(q) if q > Q::zero() => r.step = Some((q, value.span)),
        Err(why) => diags.push(invalid_number(why, value.span)),
        Ok(_) => diags.push(
            Diagnostic::error(
                "invalid-step",
                format!(
                    "the sample time must be positive, found `{}`",
                    crate::exact::shown(&value.text)
                ),
            )
            .with_primary(value.span, "not a positive number")
            .with_help("write the sample time in seconds, e.g. `step 0.1`"),
        ),
    }
}

/// `heading psi integrates r axes(u, v)`: a planar rotation.
fn resolve_heading(
    r: &mut Resolved,
    name: &Ident,
    integrates: &Ident,
    axes: Option<&(Ident, Ident)>,
    span: Span,
    diags: &mut Vec<Diagnostic>,
) {
    declare(r, diags, name, Symbol::Heading, "the heading");
    let Some(yaw) = state_of(r, integrates) else {
        diags.push(not_a_state(r, integrates, "the integrated yaw rate"));
        return;
    };
    if let Some(axes) = heading_axes(r, axes, span, diags) {
        r.rotation = RotationDecl::Planar {
            heading: name.clone(),
            integrates: yaw,
            axes,
        };
    }
}

/// The two states a heading rotates: those named, else the first two.
fn heading_axes(
    r: &Resolved,
    axes: Option<&(Ident, Ident)>,
    span: Span,
    diags: &mut Vec<Diagnostic>,
) -> Option<[usize; 2]> {
    match axes {
        Some((a, b)) => match (state_of(r, a), state_of(r, b)) {
            (Some(i), Some(j)) if i != j => Some([i, j]),
            (Some(_), Some(_)) => {
                diags.push(
                    Diagnostic::error(
                        "heading-axes",
                        "the two heading axes must be different states",
                    )
                    .with_primary(b.span, "same as the first axis")
                    .with_help("name the surge and sway states, e.g. `axes(u, v)`"),
                );
                None
            }
            (None, _) => {
                diags.push(not_a_state(r, a, "a heading axis"));
                None
            }
            (_, None) => {
                diags.push(not_a_state(r, b, "a heading axis"));
                None
            }
        },
        None if r.states.len() >= 2 => Some([0, 1]),
        None => {
            diags.push(
                Diagnostic::error(
                    "heading-axes",
                    "a planar heading rotates two states, but fewer are declared",
                )
                .with_primary(span, "needs two body axes")
                .with_help("declare surge and sway states, or name them with `axes(u, v)`"),
            );
            None
        }
    }
}

/// `rotation { state: [col, ..], .. }`: a measured rotation, its columns
/// declared in the order they first appear.
fn resolve_rotation(r: &mut Resolved, rows: &[RotationRow], diags: &mut Vec<Diagnostic>) {
    let mut columns: Vec<Ident> = Vec::new();
    let mut table = vec![Vec::new(); r.states.len()];
    let mut width: Option<usize> = None;
    let mut seen_rows: BTreeMap<usize, Span> = BTreeMap::new();
    for row in rows {
        let Some(si) = state_of(r, &row.state) else {
            diags.push(not_a_state(r, &row.state, "a rotation row"));
            continue;
        };
        if let Some(first) = seen_rows.insert(si, row.state.span) {
            diags.push(duplicate(&row.state, first, "a rotation row"));
            continue;
        }
        match width {
            None => width = Some(row.entries.len()),
            Some(w) if w != row.entries.len() => diags.push(
                Diagnostic::error(
                    "rotation-shape",
                    format!(
                        "this rotation row has {} entries, the first had {w}",
                        row.entries.len()
                    ),
                )
                .with_primary(row.span, "different length")
                .with_help("every row of R has one entry per earth-frame disturbance component"),
            ),
            Some(_) => {}
        }
        let mut entries = Vec::new();
        for e in &row.entries {
            entries.push(e.as_ref().map(
                |id| match columns.iter().position(|c| c.name == id.name) {
                    Some(k) => k,
                    None => {
                        columns.push(id.clone());
                        columns.len() - 1
                    }
                },
            ));
        }
        table[si] = entries;
    }
    for (k, c) in columns.iter().enumerate() {
        declare(r, diags, c, Symbol::RotationColumn(k), "a rotation column");
    }
    let width = width.unwrap_or(0);
    for row in table.iter_mut() {
        row.resize(width, None);
    }
    r.rotation = RotationDecl::Measured {
        columns,
        rows: table,
        width,
    };
}

/// A disturbance and its components (earth or body frame).
fn resolve_disturbance(
    r: &mut Resolved,
    name: &Ident,
    measurement: Measurement,
    frame: &Frame,
    span: Span,
    rotation_span: Option<Span>,
    diags: &mut Vec<Diagnostic>,
) {
    let di = r.disturbances.len();
    if !declare(r, diags, name, Symbol::Disturbance(di), "a disturbance") {
        return;
    }
    let earth = matches!(frame, Frame::Earth(_));
    let comps = match frame {
        Frame::Earth(ids) => {
            check_earth_shape(r, name, ids.len(), span, rotation_span, diags);
            earth_components(r, di, ids, diags)
        }
        Frame::Body(list) => body_components(r, di, list, diags),
    };
    r.disturbances.push(DisturbanceDecl {
        name: name.clone(),
        measured: measurement == Measurement::Measured,
        earth,
        components: comps,
    });
}

/// An earth-frame disturbance needs a rotation with as many columns as it has
/// components.
fn check_earth_shape(
    r: &Resolved,
    name: &Ident,
    n_components: usize,
    span: Span,
    rotation_span: Option<Span>,
    diags: &mut Vec<Diagnostic>,
) {
    let expected = match &r.rotation {
        RotationDecl::Planar { .. } => Some(2),
        RotationDecl::Measured { width, .. } => Some(*width),
        RotationDecl::None => None,
    };
    match expected {
        // A heading or rotation was declared but is invalid: already reported.
        None if rotation_span.is_some() => {}
        None => diags.push(
            Diagnostic::error(
                "missing-rotation",
                format!("`{}` is given in the earth frame, but the model has no heading or rotation", name.name),
            )
            .with_primary(span, "needs R to reach the body frame")
            .with_help("declare `heading psi integrates r` (planar) or `rotation { .. }` (measured R), or give the disturbance in `body(state: component, ..)`"),
        ),
        Some(n) if n != n_components => diags.push(
            Diagnostic::error(
                "earth-components",
                format!("`{}` has {} earth-frame components, R expects {n}", name.name, n_components),
            )
            .with_primary(span, format!("expected {n} components"))
            .with_help(if matches!(r.rotation, RotationDecl::Planar { .. }) {
                "a planar heading rotates (north, east): write `earth(north, east)`".to_string()
            } else {
                "write one component per column of the rotation rows".to_string()
            }),
        ),
        Some(_) => {}
    }
}

/// The components of an earth-frame disturbance `di`; their global indices.
fn earth_components(
    r: &mut Resolved,
    di: usize,
    ids: &[Ident],
    diags: &mut Vec<Diagnostic>,
) -> Vec<usize> {
    let mut comps = Vec::new();
    for id in ids {
        let ci = r.components.len();
        if declare(
            r,
            diags,
            id,
            Symbol::Component(ci),
            "a disturbance component",
        ) {
            r.components.push(ComponentDecl {
                name: id.clone(),
                disturbance: di,
                state: None,
            });
            comps.push(ci);
        }
    }
    comps
}

/// The components of a body-frame disturbance `di`, each on its own state;
/// their global indices.
fn body_components(
    r: &mut Resolved,
    di: usize,
    list: &[BodyComponent],
    diags: &mut Vec<Diagnostic>,
) -> Vec<usize> {
    let mut comps = Vec::new();
    let mut seen: BTreeMap<usize, Span> = BTreeMap::new();
    for bc in list {
        let Some(si) = state_of(r, &bc.state) else {
            diags.push(not_a_state(r, &bc.state, "a body-frame component's axis"));
            continue;
        };
        if let Some(first) = seen.insert(si, bc.state.span) {
            diags.push(duplicate(&bc.state, first, "a body-frame axis"));
            continue;
        }
        let ci = r.components.len();
        if declare(
            r,
            diags,
            &bc.component,
            Symbol::Component(ci),
            "a disturbance component",
        ) {
            r.components.push(ComponentDecl {
                name: bc.component.clone(),
                disturbance: di,
                state: Some(si),
            });
            comps.push(ci);
        }
    }
    comps
}

/// `rel = relative(disturbance)`.
fn resolve_relative(
    r: &mut Resolved,
    name: &Ident,
    disturbance: &Ident,
    diags: &mut Vec<Diagnostic>,
) {
    match r.symbols.get(&disturbance.name) {
        Some((Symbol::Disturbance(d), _)) => {
            let d = *d;
            let k = r.relatives.len();
            if declare(r, diags, name, Symbol::Relative(k), "a relative velocity") {
                r.relatives.push((name.clone(), d));
            }
        }
        _ => diags.push(
            Diagnostic::error(
                "unknown-name",
                format!("`{}` is not a declared disturbance", disturbance.name),
            )
            .with_primary(disturbance.span, "expected a disturbance")
            .with_help(format!(
                "declared disturbances: {}",
                names(
                    &r.disturbances
                        .iter()
                        .map(|d| d.name.clone())
                        .collect::<Vec<_>>()
                )
            )),
        ),
    }
}

/// Equations, nominal values and the data mapping, in the order written.
fn resolve_equations_and_data(r: &mut Resolved, model: &ModelSyntax, diags: &mut Vec<Diagnostic>) {
    r.equations = vec![None; r.states.len()];
    let mut nominal_seen: BTreeMap<String, Span> = BTreeMap::new();
    let mut data_seen: BTreeMap<String, Span> = BTreeMap::new();
    for item in &model.items {
        match item {
            Item::Equation {
                kind,
                state,
                rhs,
                span,
            } => resolve_equation(r, *kind, state, rhs, *span, diags),
            Item::Nominal { entries, .. } => {
                for (id, num) in entries {
                    if let Some(first) = nominal_seen.insert(id.name.clone(), id.span) {
                        diags.push(duplicate(id, first, "a nominal value"));
                        continue;
                    }
                    match decimal(&num.text) {
                        Ok(q) => r.nominal.push((id.clone(), q, id.span)),
                        Err(why) => diags.push(invalid_number(why, num.span)),
                    }
                }
            }
            Item::Data { entries, .. } => {
                for entry in entries {
                    let id = &entry.signal;
                    if let Some(first) = data_seen.insert(id.name.clone(), id.span) {
                        diags.push(duplicate(id, first, "a data column mapping"));
                        continue;
                    }
                    resolve_data_entry(r, entry, diags);
                }
            }
            _ => {}
        }
    }
}

/// `der x = ...` / `next x = ...`: one per state.
fn resolve_equation(
    r: &mut Resolved,
    kind: EquationKind,
    state: &Ident,
    rhs: &Expr,
    span: Span,
    diags: &mut Vec<Diagnostic>,
) {
    match r.symbols.get(&state.name) {
        Some((Symbol::State(i), _)) => {
            let i = *i;
            if let Some(first) = &r.equations[i] {
                diags.push(
                    Diagnostic::error(
                        "duplicate-equation",
                        format!("state `{}` has two equations", state.name),
                    )
                    .with_primary(state.span, "second equation")
                    .with_secondary(first.span, "first equation")
                    .with_help("write all terms of a state in one equation, joined with `+`"),
                );
            } else {
                r.equations[i] = Some(EquationDecl {
                    kind,
                    state: i,
                    rhs: rhs.clone(),
                    span,
                });
            }
        }
        Some((Symbol::Heading, _)) => diags.push(
            Diagnostic::error(
                "heading-equation",
                format!(
                    "`{}` is the heading; it has no equation of its own",
                    state.name
                ),
            )
            .with_primary(state.span, "the heading integrates its yaw rate")
            .with_help(
                "remove this equation: `heading psi integrates r` already gives psi+ = psi + h r",
            ),
        ),
        _ => diags.push(not_a_state(r, state, "the left-hand side of an equation")),
    }
}

/// One entry of `data { signal = "column" in unit }` (not seen before).
fn resolve_data_entry(r: &mut Resolved, entry: &DataEntry, diags: &mut Vec<Diagnostic>) {
    let id = &entry.signal;
    let ok = SPECIAL_COLUMNS.contains(&id.name.as_str())
        || match r.symbols.get(&id.name) {
            Some((
                Symbol::State(_) | Symbol::Input(_) | Symbol::Heading | Symbol::RotationColumn(_),
                _,
            )) => true,
            Some((Symbol::Component(c), _)) => {
                r.disturbances[r.components[*c].disturbance].measured
            }
            _ => false,
        };
    if !ok {
        diags.push(
            Diagnostic::error("unknown-name", format!("`{}` is not a signal read from data", id.name))
                .with_primary(id.span, "cannot map a column to this")
                .with_help("map states, inputs, the heading, rotation columns, measured disturbance components, `time` or `experiment`"),
        );
        return;
    }
    if let Some((column, cspan)) = &entry.column {
        if column.trim().is_empty() {
            diags.push(
                Diagnostic::error(
                    "empty-column-name",
                    format!("the column name for `{}` is empty", id.name),
                )
                .with_primary(*cspan, "empty")
                .with_help("write the CSV header's name between the quotes"),
            );
        } else {
            r.data.push((id.clone(), column.clone(), *cspan));
        }
    }
    if let Some((unit, uspan)) = &entry.unit {
        match unit_problem(r, &id.name, unit) {
            Some((message, help)) => diags.push(
                Diagnostic::error("unknown-unit", message)
                    .with_primary(*uspan, "not a unit for this column")
                    .with_help(help),
            ),
            None => r.units.push((id.clone(), unit.clone(), *uspan)),
        }
    }
}

/// An error per state without an equation.
fn missing_equations(r: &Resolved, diags: &mut Vec<Diagnostic>) {
    for (i, eq) in r.equations.iter().enumerate() {
        if eq.is_none() {
            let s = &r.states[i];
            diags.push(
                Diagnostic::error(
                    "missing-equation",
                    format!("state `{}` has no equation", s.name),
                )
                .with_primary(s.span, "declared here")
                .with_help(format!(
                    "add `der {0} = ...` (continuous time) or `next {0} = ...` (discrete time)",
                    s.name
                )),
            );
        }
    }
}

fn rotation_conflict(span: Span, first: Span) -> Diagnostic {
    Diagnostic::error("rotation-conflict", "the model declares R twice")
        .with_primary(span, "second heading/rotation")
        .with_secondary(first, "first declared here")
        .with_help("use either `heading .. integrates ..` (planar) or `rotation { .. }` (measured R), once")
}

/// `a, b, c` or `none` (at most `MAX_LISTED` names, then a count).
pub fn names(ids: &[Ident]) -> String {
    if ids.is_empty() {
        "none".to_string()
    } else {
        leeway_grammar::join_capped(ids.iter().map(|i| i.name.as_str()), ", ")
    }
}

/// A literal refused by [`decimal`], with the limits in the help.
pub(crate) fn invalid_number(why: String, span: Span) -> Diagnostic {
    Diagnostic::error("invalid-number", why)
        .with_primary(span, "here")
        .with_help(format!(
            "write a decimal of at most {} significant digits between 1e-{} and 1e{} in magnitude, such as -0.15 or 1.5e-4",
            crate::exact::MAX_SIGNIFICANT_DIGITS,
            crate::exact::MAX_DECIMAL_EXPONENT,
            crate::exact::MAX_DECIMAL_EXPONENT + 1
        ))
}
