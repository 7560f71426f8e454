//! The expansion of a valid model: a unit struct named as the model that
//! implements `leeway::Model` with straight-line code, its typed parameter
//! struct `<Model>Params`, typed constants, and the IR embedded as data: a
//! JSON literal, checked at expansion to read back to the identical IR, read
//! once into a `LazyLock`.

use crate::eval;
use crate::tokens::{doc, doc_escape, float, index, rust_ident, str_array};
use leeway_structure::identify::patterns_text;
use leeway_structure::ir::{Ir, PredictorKind};
use proc_macro2::{Ident, Span, TokenStream};
use quote::quote;

/// The names, shapes and counts a model's constants describe. Built from the
/// IR for a valid model, and from whatever could be read for a broken one.
#[derive(Clone, Debug, Default)]
pub(crate) struct Shape {
    pub name: String,
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub rotation: Vec<String>,
    pub components: Vec<String>,
    pub sign_args: Vec<String>,
    pub parameters: Vec<String>,
    pub nominal: Vec<f64>,
    pub step: Option<f64>,
    pub basic: Vec<String>,
    pub augmented: Vec<String>,
    pub measured: Vec<String>,
}

impl Shape {
    pub fn of(ir: &Ir) -> Shape {
        let names =
            |cols: &[leeway_structure::ir::Column]| cols.iter().map(|c| c.name.clone()).collect();
        Shape {
            name: ir.name.clone(),
            states: ir.states.clone(),
            inputs: ir.inputs.clone(),
            rotation: ir.rotation_vars.clone(),
            components: ir.components.iter().map(|c| c.name.clone()).collect(),
            sign_args: ir.sign_args.iter().map(|s| s.name.clone()).collect(),
            parameters: ir.parameters.iter().map(|p| p.name.clone()).collect(),
            nominal: ir.parameters.iter().map(|p| p.nominal).collect(),
            step: ir.step,
            basic: names(&ir.predictors.basic),
            augmented: names(&ir.predictors.augmented),
            measured: names(&ir.predictors.measured),
        }
    }
}

/// The Rust names of a model's items.
pub(crate) struct Names {
    pub model: Ident,
    pub params: Ident,
    /// One field per parameter, `None` where the name is no Rust identifier.
    pub fields: Vec<Option<Ident>>,
}

/// Rust names for the model and its parameters, and a message for each name
/// Rust cannot spell.
pub(crate) fn names(shape: &Shape) -> (Option<Names>, Vec<String>) {
    let mut errors = Vec::new();
    // A struct named `f64` would shadow the primitive the generated code uses.
    const PRIMITIVES: [&str; 17] = [
        "bool", "char", "str", "f32", "f64", "i8", "i16", "i32", "i64", "i128", "isize", "u8",
        "u16", "u32", "u64", "u128", "usize",
    ];
    let model = rust_ident(&shape.name).filter(|_| !PRIMITIVES.contains(&shape.name.as_str()));
    if model.is_none() {
        errors.push(format!(
            "model `{}` cannot be a Rust type name; rename the model (`model {}Model {{ … }}`)",
            shape.name,
            shape.name.trim_matches('_')
        ));
    }
    let fields: Vec<Option<Ident>> = shape
        .parameters
        .iter()
        .map(|p| {
            let id = rust_ident(p);
            if id.is_none() {
                errors.push(format!(
                    "parameter `{p}` cannot be a Rust field name; rename it in the model"
                ));
            }
            id
        })
        .collect();
    let names = model.map(|model| {
        let params = Ident::new(&format!("{}Params", shape.name), Span::call_site());
        Names {
            model,
            params,
            fields,
        }
    });
    (names, errors)
}

/// The model's type with `doc`, its constants and its parameter struct:
/// what a model compiled or not declares alike.
pub(crate) fn declared(doc: TokenStream, shape: &Shape, names: &Names) -> TokenStream {
    let ty = &names.model;
    let consts = consts(shape);
    let params = params(shape, names);
    quote! {
        #doc
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        #[allow(non_camel_case_types)]
        pub struct #ty;

        #[allow(clippy::all, clippy::pedantic, clippy::nursery)]
        impl #ty {
            #consts
        }

        #params
    }
}

/// The inherent constants of the model struct.
pub(crate) fn consts(shape: &Shape) -> TokenStream {
    let arr = |items: &[String]| {
        let n = index(items.len());
        let v = str_array(items);
        quote!([&'static str; #n] = #v)
    };
    let name = &shape.name;
    let states = arr(&shape.states);
    let inputs = arr(&shape.inputs);
    let rotation = arr(&shape.rotation);
    let components = arr(&shape.components);
    let sign_args = arr(&shape.sign_args);
    let parameters = arr(&shape.parameters);
    let basic = arr(&shape.basic);
    let augmented = arr(&shape.augmented);
    let measured = arr(&shape.measured);
    let n_out = shape.states.len();
    let basic_len = index(n_out * shape.basic.len());
    let augmented_len = index(n_out * shape.augmented.len());
    let measured_len = index(n_out * shape.measured.len());
    let step = match shape.step {
        Some(h) => {
            let h = float(h);
            quote!(::core::option::Option::Some(#h))
        }
        None => quote!(::core::option::Option::None),
    };
    quote! {
        /// The model's name, as declared.
        pub const NAME: &'static str = #name;
        /// The states (outputs), in declaration order: the layout of `Signals::states`.
        pub const STATES: #states;
        /// The exact inputs: the layout of `Signals::inputs`.
        pub const INPUTS: #inputs;
        /// The rotation variables: the layout of `Signals::rotation`.
        pub const ROTATION: #rotation;
        /// The disturbance components by global index: the layout of `Signals::disturbances`.
        pub const COMPONENTS: #components;
        /// The sign arguments: one `±1` each in a sign pattern.
        pub const SIGN_ARGS: #sign_args;
        /// The physical parameters θ, in θ order.
        pub const PARAMETERS: #parameters;
        /// The declared sample time `h` of `der` equations, if any.
        pub const STEP: ::core::option::Option<f64> = #step;
        /// The columns of the basic predictor (IV1's `Φ`).
        pub const BASIC_COLUMNS: #basic;
        /// The columns of the augmented predictor (IV2's `[Φ; Φ_ρ; Φ_λ]`).
        pub const AUGMENTED_COLUMNS: #augmented;
        /// The columns of the measured-disturbance predictor (IV3).
        pub const MEASURED_COLUMNS: #measured;
        /// Length of a basic regressor buffer (outputs × columns, row-major by output).
        pub const BASIC_LEN: usize = #basic_len;
        /// Length of an augmented regressor buffer (outputs × columns, row-major by output).
        pub const AUGMENTED_LEN: usize = #augmented_len;
        /// Length of a measured-disturbance regressor buffer (outputs × columns, row-major by output).
        pub const MEASURED_LEN: usize = #measured_len;
    }
}

/// The typed parameter struct `<Model>Params` and its conversions.
pub(crate) fn params(shape: &Shape, names: &Names) -> TokenStream {
    let fields: Vec<(&Ident, &String, f64)> = names
        .fields
        .iter()
        .zip(&shape.parameters)
        .zip(shape.nominal.iter().copied().chain(std::iter::repeat(0.0)))
        .filter_map(|((id, name), nominal)| id.as_ref().map(|id| (id, name, nominal)))
        .collect();
    let n = index(fields.len());
    let ty = &names.params;
    let model = &shape.name;
    let struct_doc = doc(&[
        format!("The physical parameters θ of model `{model}`, named as in the model, in θ order."),
        String::new(),
        "Convert with `to_array`/`from_array` (or `From`), `to_vec`/`from_slice` (or `TryFrom<&[f64]>`)".to_string(),
        "to the θ slices `leeway::Model::rhs` and the estimators use.".to_string(),
    ]);
    let decls = fields.iter().map(|(id, name, nominal)| {
        let d = format!(" `{name}` (nominal {nominal:?}).");
        quote!(#[doc = #d] pub #id: f64,)
    });
    let nominal = fields.iter().map(|(id, _, v)| {
        let v = float(*v);
        quote!(#id: #v,)
    });
    let from_array = fields.iter().enumerate().map(|(i, (id, _, _))| {
        let i = index(i);
        quote!(#id: theta[#i],)
    });
    let to_array = fields.iter().map(|(id, _, _)| quote!(self.#id));
    let field_names: Vec<&String> = fields.iter().map(|(_, name, _)| *name).collect();
    let names_arr = str_array(&field_names);
    quote! {
        #struct_doc
        #[derive(Clone, Copy, Debug, PartialEq)]
        #[allow(non_snake_case)]
        pub struct #ty {
            #(#decls)*
        }

        #[allow(clippy::all, clippy::pedantic, clippy::nursery)]
        impl #ty {
            /// The parameter names, in θ order.
            pub const NAMES: [&'static str; #n] = #names_arr;
            /// The number of parameters.
            pub const LEN: usize = #n;
            /// The nominal values of the model's `nominal { }` block (0 where unlisted).
            pub const fn nominal() -> Self {
                Self { #(#nominal)* }
            }
            /// The parameters from θ in θ order.
            pub const fn from_array(theta: [f64; #n]) -> Self {
                Self { #(#from_array)* }
            }
            /// θ in θ order.
            pub const fn to_array(&self) -> [f64; #n] {
                [#(#to_array),*]
            }
            /// The parameters from θ in θ order; fails unless `theta` holds exactly `LEN` values.
            pub fn from_slice(theta: &[f64]) -> ::core::result::Result<Self, ::leeway::__private::TryFromSliceError> {
                <[f64; #n]>::try_from(theta).map(Self::from_array)
            }
            /// θ in θ order, as a vector.
            pub fn to_vec(&self) -> ::std::vec::Vec<f64> {
                self.to_array().to_vec()
            }
        }

        impl ::core::default::Default for #ty {
            fn default() -> Self {
                Self::nominal()
            }
        }

        impl ::core::convert::From<[f64; #n]> for #ty {
            fn from(theta: [f64; #n]) -> Self {
                Self::from_array(theta)
            }
        }

        impl ::core::convert::From<#ty> for [f64; #n] {
            fn from(params: #ty) -> Self {
                params.to_array()
            }
        }

        impl ::core::convert::TryFrom<&[f64]> for #ty {
            type Error = ::leeway::__private::TryFromSliceError;
            fn try_from(theta: &[f64]) -> ::core::result::Result<Self, Self::Error> {
                Self::from_slice(theta)
            }
        }
    }
}

/// One sentence on identifiability, from the report.
fn identifiability(ir: &Ir) -> Vec<String> {
    let r = &ir.report;
    let mut lines = Vec::new();
    if r.identifiable && r.any_single_pattern {
        lines.push("θ is identifiable from one experiment of any sign pattern.".to_string());
    } else if r.identifiable {
        let n = r.required_patterns.len();
        let set = patterns_text(ir, &r.required_patterns, PredictorKind::Measured);
        if n == 1 {
            lines.push(format!(
                "θ is identifiable from one experiment with sign pattern {set}."
            ));
        } else {
            lines.push(format!(
                "θ is identifiable from {n} experiments with sign patterns {set}."
            ));
        }
    } else if r.aggregates.is_empty() {
        lines.push("θ is not identifiable:".to_string());
        lines.extend(r.unidentifiable.iter().map(|c| format!("- {}", c.message)));
    } else {
        lines.push(
            "θ is not identifiable; as asked (`aggregate`), these parameters estimate combinations \
             and the ones they absorb stay at their nominal values:"
                .to_string(),
        );
        for a in &r.aggregates {
            let p = ir
                .parameters
                .get(a.parameter)
                .map_or("?", |p| p.name.as_str());
            lines.push(format!("- `{p}` estimates {}", a.estimates));
        }
    }
    lines
}

/// The model struct's documentation: what it is, its size, its
/// identifiability, and the compiler's warnings and notes (a proc macro
/// cannot emit warnings on stable Rust; they are kept here instead).
fn model_doc(ir: &Ir, label: &str, remarks: &[String]) -> TokenStream {
    let list = |v: &[String]| {
        v.iter()
            .map(|s| format!("`{s}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let p = &ir.predictors;
    let mut lines = vec![
        format!(
            "The model `{}` of `{}`, compiled by leeway at build time.",
            ir.name, label
        ),
        String::new(),
        format!(
            "{} states ({}), {} inputs ({}), {} parameters θ (see the `{}Params` struct).",
            ir.states.len(),
            list(&ir.states),
            ir.inputs.len(),
            list(&ir.inputs),
            ir.parameters.len(),
            ir.name
        ),
        format!(
            "Regressor columns: basic {}, augmented {}, measured {}; sign arguments: {}.",
            p.basic.len(),
            p.augmented.len(),
            p.measured.len(),
            if ir.sign_args.is_empty() {
                "none".to_string()
            } else {
                list(
                    &ir.sign_args
                        .iter()
                        .map(|s| s.name.clone())
                        .collect::<Vec<_>>(),
                )
            }
        ),
        String::new(),
    ];
    lines.extend(identifiability(ir).iter().map(|l| doc_escape(l)));
    if !remarks.is_empty() {
        lines.push(String::new());
        lines.push("From the structure compiler:".to_string());
        lines.extend(remarks.iter().map(|r| format!("- {}", doc_escape(r))));
    }
    doc(&lines)
}

/// The JSON of the IR, checked to read back to exactly the same IR (every
/// f64 bit for bit), so `Model::ir` of generated code equals the compiler's.
fn ir_json(ir: &Ir) -> Result<String, String> {
    let json = serde_json::to_string(ir).map_err(|e| {
        format!(
            "internal error: the IR of `{}` cannot be serialized: {e}",
            ir.name
        )
    })?;
    match serde_json::from_str::<Ir>(&json) {
        Ok(back) if back == *ir => Ok(json),
        _ => Err(format!(
            "the IR of `{}` does not survive its JSON embedding exactly (a non-finite number?); check the model's numbers",
            ir.name
        )),
    }
}

/// The whole expansion of a valid model, or the messages of why it cannot be
/// emitted (the caller then emits the fallback).
pub(crate) fn model(ir: &Ir, label: &str, remarks: &[String]) -> Result<TokenStream, Vec<String>> {
    let shape = Shape::of(ir);
    let (names, mut errors) = names(&shape);
    let json = match ir_json(ir) {
        Ok(j) => Some(j),
        Err(e) => {
            errors.push(e);
            None
        }
    };
    let (Some(names), Some(json), true) = (names, json, errors.is_empty()) else {
        return Err(errors);
    };
    let ty = &names.model;
    let declared = declared(model_doc(ir, label, remarks), &shape, &names);
    let predictors = eval::predictors(ir);
    let rhs = eval::rhs(ir);
    let step = eval::step(ir);
    let n_basic = index(shape.basic.len());
    let n_augmented = index(shape.augmented.len());
    let n_measured = index(shape.measured.len());
    let n_out = index(shape.states.len());
    Ok(quote! {
        #declared

        #[allow(non_snake_case, unused_qualifications, clippy::all, clippy::pedantic, clippy::nursery)]
        impl ::leeway::__private::Model for #ty {
            fn ir(&self) -> &::leeway::__private::Ir {
                const IR_JSON: &str = #json;
                static IR: ::leeway::__private::LazyLock<::leeway::__private::Ir> =
                    ::leeway::__private::LazyLock::new(|| ::leeway::__private::ir_from_json(IR_JSON));
                &IR
            }
            fn name(&self) -> &str {
                Self::NAME
            }
            fn n_columns(&self, kind: ::leeway::__private::PredictorKind) -> usize {
                match kind {
                    ::leeway::__private::PredictorKind::Basic => #n_basic,
                    ::leeway::__private::PredictorKind::Augmented => #n_augmented,
                    ::leeway::__private::PredictorKind::Measured => #n_measured,
                }
            }
            fn n_outputs(&self) -> usize {
                #n_out
            }
            #predictors
            fn rhs #rhs
            fn step #step
        }
    })
}
