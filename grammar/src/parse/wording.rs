//! Syntax errors worded for the user: what was expected (rules named in
//! words — `Rule::xyz` never reaches a user), the whole token found
//! underlined, the `(` or `|` left open when an expression is cut short, and
//! a help line.

use crate::ast::Span;
use crate::diagnostic::data::Diagnostic;
use crate::parse::rules::{Rule, is_keyword};
use crate::scan::unclosed_delimiter;
use pest::error::{Error, ErrorVariant, InputLocation};

/// How the user reads what a grammar rule expects.
fn rule_name(rule: &Rule) -> &'static str {
    match rule {
        Rule::file | Rule::EOI => "end of file",
        Rule::model => "`model Name { ... }`",
        Rule::item
        | Rule::step_decl
        | Rule::state_decl
        | Rule::input_decl
        | Rule::heading_decl
        | Rule::rotation_decl
        | Rule::disturbance_decl
        | Rule::nominal_block
        | Rule::data_block
        | Rule::delay_decl
        | Rule::equation_kind => "a declaration",
        Rule::delay_word => "a declaration",
        Rule::delay_unit => "`steps` or `s`",
        Rule::axes => "`axes(..)`",
        Rule::rotation_row => "a rotation row `state = [a, b]`",
        Rule::rotation_entry => "a data column name or 0",
        Rule::zero => "0",
        Rule::measurement => "`measured` or `unmeasured`",
        Rule::earth_frame => "`earth(..)`",
        Rule::frame => "`earth(..)` or `body(..)`",
        Rule::ident_list => "a list of names",
        Rule::body_frame => "`body(..)`",
        Rule::body_component => "`state: component`",
        // Both start a declaration; listing them separately only lengthens the message.
        Rule::relative_decl | Rule::equation => "a declaration",
        Rule::nominal_entry => "`parameter = value`",
        Rule::data_entry => "`signal = \"column\"` or `signal in unit`",
        Rule::unit_clause | Rule::in_word => "`in unit`",
        Rule::unit => "a unit such as `deg` or `deg/s`",
        Rule::expr | Rule::product => "an expression",
        Rule::factor | Rule::negated => "an operand",
        Rule::modulus => "`|..|`",
        Rule::paren => "`(`",
        Rule::path => "a name",
        Rule::candidate => "`?` (a candidate parameter)",
        Rule::sign => "`+` or `-`",
        Rule::add_op | Rule::mul_op => "an operator",
        Rule::number => "a number",
        Rule::signed_number => "a number",
        Rule::string | Rule::string_inner => "a quoted column name",
        Rule::keyword => "a keyword",
        Rule::ident => "a name",
        Rule::WHITESPACE | Rule::COMMENT => "whitespace",
    }
}

/// What the parser found at `pos`, as the user reads it, and where it ends:
/// a whole word or number, one character, or the end of the line or file.
fn found_token(source: &str, pos: usize) -> (String, usize) {
    let Some(rest) = source.get(pos..) else {
        return ("end of file".to_string(), pos);
    };
    let Some(first) = rest.chars().next() else {
        return ("end of file".to_string(), pos);
    };
    let word_char = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '.';
    if word_char(first) {
        let len: usize = rest
            .chars()
            .take_while(|c| word_char(*c))
            .map(char::len_utf8)
            .sum();
        (format!("`{}`", &rest[..len]), pos + len)
    } else if first == '\n' || first == '\r' {
        ("end of line".to_string(), pos + 1)
    } else if first.is_control() {
        // Never echo a raw control character (NUL, escape…) to a terminal.
        (
            format!("`\\u{{{:x}}}`", u32::from(first)),
            pos + first.len_utf8(),
        )
    } else {
        (format!("`{first}`"), pos + first.len_utf8())
    }
}

/// The diagnostic for pest's error `e` in `source`.
pub(crate) fn syntax_error(source: &str, e: Error<Rule>) -> Diagnostic {
    let pos = match e.location {
        InputLocation::Pos(p) => p,
        InputLocation::Span((s, _)) => s,
    };
    let (found, end) = found_token(source, pos);
    let keyword = is_keyword(found.trim_matches('`'));
    let (message, expected) = expectation(&e.variant, &found, keyword);
    let label = if found == "end of file" {
        "the file ends here"
    } else {
        "here"
    };
    let mut d = Diagnostic::error("syntax", message).with_primary(Span::new(pos, end), label);
    // An expression cut short by the next declaration, or by the end of the file,
    // usually has an unclosed `(` or `|`: point at it.
    let cut_short = found == "end of file" || (keyword && expected.contains("an operator"));
    let unclosed = if cut_short {
        unclosed_delimiter(source, pos)
    } else {
        None
    };
    if let Some(open) = unclosed {
        let what = if source.as_bytes().get(open) == Some(&b'(') {
            "`(`"
        } else {
            "`|`"
        };
        d = d.with_secondary(
            Span::new(open, open + 1),
            format!("this {what} is never closed"),
        );
    }
    if let Some(h) = help(&found, &expected, keyword, unclosed.is_some()) {
        d = d.with_help(h);
    }
    d
}

/// The message, and the names of what was expected joined by spaces (empty
/// when nothing is named), for the error `variant` at the token `found`.
fn expectation(variant: &ErrorVariant<Rule>, found: &str, keyword: bool) -> (String, String) {
    let found_text = if keyword {
        format!("the keyword {found}")
    } else {
        found.to_string()
    };
    match variant {
        ErrorVariant::ParsingError {
            positives,
            negatives,
        } => {
            let mut names: Vec<&str> = positives.iter().map(rule_name).collect();
            names.sort_unstable();
            names.dedup();
            // At a declaration boundary a name starts `x = relative(..)`: say "a declaration".
            if names.contains(&"a declaration") {
                names.retain(|n| *n != "a name");
            }
            let list = match names.len() {
                0 => String::new(),
                1 => names[0].to_string(),
                n => format!("{} or {}", names[..n - 1].join(", "), names[n - 1]),
            };
            if !names.is_empty() {
                (
                    format!("expected {list}, found {found_text}"),
                    names.join(" "),
                )
            } else if negatives.contains(&Rule::keyword) {
                (
                    format!("{found} is a keyword and cannot be used as a name"),
                    "a name".to_string(),
                )
            } else {
                (format!("unexpected {found_text}"), String::new())
            }
        }
        ErrorVariant::CustomError { message } => (message.clone(), String::new()),
    }
}

/// The help line for a syntax error, from what was `found` and `expected`,
/// whether the token is a keyword and whether a delimiter is left open.
fn help(found: &str, expected: &str, keyword: bool, unclosed: bool) -> Option<String> {
    if found == "`^`" {
        Some("powers are not part of the language; write products such as u*u or u*|u|".to_string())
    } else if expected.contains("a name") && keyword {
        Some(format!("{found} is reserved; choose another name"))
    } else if unclosed {
        Some(
            "close the modulus or parenthesis before the next declaration, e.g. X*u*|water.u|"
                .to_string(),
        )
    } else if expected.contains("an expression") || expected.contains("an operand") {
        Some("each term is a product of a parameter, numbers and at most two signals, e.g. X_uu*water.u*|water.u|".to_string())
    } else if found == "end of file" {
        Some("a model ends with `}`; check for an unclosed `{`, `(` or `|`".to_string())
    } else if expected.contains("a declaration") || expected.contains("end of file") {
        Some(
            "declarations are: step, state, input, heading, rotation, disturbance, `name = relative(..)`, der, next, nominal, data, delay"
                .to_string(),
        )
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::testing::{at, error};

    #[test]
    fn syntax_errors_name_what_was_expected_and_found() {
        let src = "model M {\n    state u\n    der u = X*u^2\n}\n";
        let d = error(src);
        assert_eq!(d.code, "syntax");
        assert_eq!(
            d.message,
            "expected a declaration or an operator, found `^`"
        );
        assert_eq!(at(src, &d), "^");
        assert!(d.help.as_deref().is_some_and(|h| h.contains("powers")));

        let src = "model M {\n    state u, input\n}\n";
        let d = error(src);
        assert_eq!(d.message, "expected a name, found the keyword `input`");
        assert_eq!(at(src, &d), "input", "the whole keyword is underlined");
        assert_eq!(
            d.help.as_deref(),
            Some("`input` is reserved; choose another name")
        );

        let src = "model M {\n    state u\n    der u = X*\n}\n";
        let d = error(src);
        assert!(d.message.starts_with("expected "), "{}", d.message);
        assert!(d.message.ends_with("found `}`"), "{}", d.message);

        let src = "model M {\n    stat u\n}\n";
        let d = error(src);
        assert_eq!(d.message, "expected a declaration, found `stat`");
        assert!(
            d.help
                .as_deref()
                .is_some_and(|h| h.starts_with("declarations are:"))
        );
    }

    #[test]
    fn an_unclosed_modulus_is_pointed_at() {
        let src = "model M {\n    state u, v\n    der u = X*u*|u + Y*v\n    der v = Z*v\n}\n";
        let d = error(src);
        assert_eq!(d.message, "expected an operator, found the keyword `der`");
        let open = d.labels.iter().find(|l| !l.primary).map(|l| l.span);
        assert_eq!(
            open,
            Some(Span::new(
                src.find('|').unwrap_or(0),
                src.find('|').unwrap_or(0) + 1
            ))
        );
        assert!(
            d.labels
                .iter()
                .any(|l| l.message == "this `|` is never closed")
        );

        let src = "model M {\n    state u\n    der u = X*(u\n";
        let d = error(src);
        assert!(d.message.ends_with("found end of file"), "{}", d.message);
        assert!(
            d.labels
                .iter()
                .any(|l| l.message == "this `(` is never closed"),
            "{d:?}"
        );
    }

    #[test]
    fn found_token_is_character_aware() {
        assert_eq!(found_token("é*u", 0), ("`é`".to_string(), 2));
        assert_eq!(found_token("abc_1.u rest", 0), ("`abc_1.u`".to_string(), 7));
        assert_eq!(found_token("x", 1), ("end of file".to_string(), 1));
        assert_eq!(found_token("\nx", 0), ("end of line".to_string(), 1));
        assert_eq!(found_token("\u{0}x", 0), ("`\\u{0}`".to_string(), 1));
        let src = "model M { state é }";
        let d = error(src);
        assert_eq!(at(src, &d), "é");
    }
}
