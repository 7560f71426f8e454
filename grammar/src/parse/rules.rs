//! The pest parser derived from `som.pest`, and the words the grammar
//! reserves, asked of the grammar itself so the two cannot drift.

use pest::Parser;

/// The parser pest derives from the grammar.
#[derive(pest_derive::Parser)]
#[grammar = "som.pest"]
pub(crate) struct SomParser;

/// Whether `word` is a keyword: the grammar's `keyword` rule matches it whole.
/// The reserved words are listed once, in `som.pest`.
pub(crate) fn is_keyword(word: &str) -> bool {
    SomParser::parse(Rule::keyword, word).is_ok_and(|pairs| pairs.as_str() == word)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quoted words of the `keyword` rule, read from the grammar's text.
    fn grammar_keywords() -> Vec<String> {
        let grammar = include_str!("../som.pest");
        let rule = grammar
            .split("\nkeyword = @{")
            .nth(1)
            .and_then(|r| r.split("~ !(").next())
            .unwrap_or_default();
        rule.split('"')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    }

    #[test]
    fn keywords_are_those_of_the_grammar() {
        let words = grammar_keywords();
        assert!(
            words.iter().any(|w| w == "model") && words.iter().any(|w| w == "data"),
            "{words:?}"
        );
        for word in &words {
            assert!(is_keyword(word), "{word}");
        }
        // A keyword only as a whole word; `in` is not reserved.
        for word in [
            "in",
            "inputs",
            "der.u",
            "der_u",
            "u",
            "",
            "end of file",
            "^",
        ] {
            assert!(!is_keyword(word), "{word}");
        }
    }
}
