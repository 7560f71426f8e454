//! Pass 1, resolve: declarations → symbol tables, with every naming error
//! (duplicates, unknown names, missing rotation, bad shapes) collected.
//!
//! The steps, in the order [`resolve()`] runs them: `symbols` declares the
//! states and inputs; `rotation` the step and the heading or rotation;
//! `media` the disturbances, then the relative velocities; `equations` the
//! equations, nominal values and data mapping, then the states without an
//! equation; `delay` the inputs' dead times (after `step`, which resolves
//! one in seconds). `decl` holds what they produce.

pub(crate) mod decl;
pub(crate) mod delay;
pub(crate) mod equations;
pub(crate) mod media;
pub(crate) mod rotation;
pub(crate) mod symbols;

use leeway_grammar::{Diagnostic, Item, ModelSyntax};
use std::collections::BTreeMap;

pub use decl::{
    ComponentDecl, DisturbanceDecl, EquationDecl, Resolved, RotationDecl, SPECIAL_COLUMNS, Symbol,
};
pub use symbols::names;

use delay::resolve_delays;
use equations::{missing_equations, resolve_equations_and_data};
use media::{resolve_disturbance, resolve_relative};
use rotation::resolve_step_and_rotation;
use symbols::declare_states_and_inputs;

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
        delays: Vec::new(),
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
    resolve_delays(&mut r, model, diags);
    r
}
