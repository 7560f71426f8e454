//! One document's analysis: its syntax tree, its compilation (as `leeway
//! check` compiles it) and its names. Computed once per version, when a
//! request or the diagnostics first need it.

use crate::symbols::Symbols;
use leeway_grammar::ModelSyntax;
use leeway_structure::{Compilation, CompileOptions, compile};

/// What the server knows of one version of a document.
pub struct Analysis {
    /// The syntax tree, when the text parses.
    pub model: Option<ModelSyntax>,
    /// `check`'s compilation: the IR when the model is valid, every diagnostic.
    pub compilation: Compilation,
    /// Declarations and uses of names.
    pub symbols: Symbols,
}

impl Analysis {
    /// Parses and compiles `text` with `check`'s default options. The text
    /// is parsed twice (here and in `compile`): the parse is the cheap part.
    pub fn of(text: &str) -> Analysis {
        let (model, _) = leeway_grammar::parse(text);
        let compilation = compile(text, &CompileOptions::default());
        let symbols = model.as_ref().map(Symbols::of).unwrap_or_default();
        Analysis {
            model,
            compilation,
            symbols,
        }
    }
}
