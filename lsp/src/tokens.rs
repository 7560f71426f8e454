//! Semantic tokens: every name coloured by what it names (a parameter of θ
//! apart from the signals, a medium, its components, a relative velocity);
//! keywords, numbers and comments are left to the editor's grammar.

use crate::analysis::Analysis;
use crate::symbols::Kind;
use crate::text::position;
use lsp_types::{SemanticToken, SemanticTokenType, SemanticTokensLegend};

/// The token types, in the order their indices refer to.
pub fn legend() -> SemanticTokensLegend {
    SemanticTokensLegend {
        token_types: vec![
            SemanticTokenType::VARIABLE,
            SemanticTokenType::PARAMETER,
            SemanticTokenType::NAMESPACE,
            SemanticTokenType::ENUM_MEMBER,
            SemanticTokenType::PROPERTY,
        ],
        token_modifiers: vec![],
    }
}

fn index(kind: Kind) -> u32 {
    match kind {
        Kind::State | Kind::Input | Kind::Heading | Kind::RotationColumn => 0,
        Kind::Parameter => 1,
        Kind::Medium => 2,
        Kind::Component => 3,
        Kind::Relative => 4,
    }
}

/// The tokens of a document, delta-encoded as the protocol wants them.
pub fn tokens(text: &str, analysis: &Analysis) -> Vec<SemanticToken> {
    let mut out = Vec::new();
    let (mut line, mut start) = (0, 0);
    for o in &analysis.symbols.occurrences {
        let at = position(text, o.span.start);
        let end = position(text, o.span.end);
        if end.line != at.line {
            continue;
        }
        let delta_line = at.line - line;
        let delta_start = if delta_line == 0 {
            at.character - start
        } else {
            at.character
        };
        out.push(SemanticToken {
            delta_line,
            delta_start,
            length: end.character - at.character,
            token_type: index(o.kind),
            token_modifiers_bitset: 0,
        });
        (line, start) = (at.line, at.character);
    }
    out
}
