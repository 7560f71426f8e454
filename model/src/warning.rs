//! A warning as a user meets it: one line saying what and why in plain
//! words, one line saying what to do, and the exact detail (the full
//! combination, every figure) for `--verbose` and the JSON documents. Every
//! producer of estimate-time warnings builds one, so that text output keeps
//! each warning to two lines whatever the model's size.

use serde::Serialize;

/// One warning: short in text, complete in its detail.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Warning {
    /// A kebab-case kind (`not-excited`, `sign-violation`, ...).
    pub code: &'static str,
    /// What happened and why, in one short line.
    pub summary: String,
    /// What to do about it, in one short line (empty when nothing is to be done).
    pub help: String,
    /// The complete message: exact combinations, figures, the paper's terms.
    pub detail: String,
    /// Whether what it reports can bias the estimate (`--strict` then fails the run).
    pub can_bias: bool,
}

impl Warning {
    /// A warning with its summary, help and detail; not biasing.
    pub fn new(
        code: &'static str,
        summary: impl Into<String>,
        help: impl Into<String>,
        detail: impl Into<String>,
    ) -> Warning {
        Warning {
            code,
            summary: summary.into(),
            help: help.into(),
            detail: detail.into(),
            can_bias: false,
        }
    }

    /// A message that is short already: the summary is the detail, no help.
    pub fn plain(code: &'static str, text: impl Into<String>) -> Warning {
        let text = text.into();
        Warning::new(code, text.clone(), String::new(), text)
    }

    /// The same warning, marked as one that can bias the estimate.
    pub fn biasing(mut self) -> Warning {
        self.can_bias = true;
        self
    }
}

/// Names listed in a summary: the first `shown`, then `and N others`.
pub fn names_capped(names: &[String], shown: usize) -> String {
    match names.len() {
        0 => "several columns".to_string(),
        n if n <= shown + 1 => match names.split_last() {
            Some((last, [])) => last.clone(),
            Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
            None => String::new(),
        },
        n => format!("{} and {} others", names[..shown].join(", "), n - shown),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_capped() {
        let n: Vec<String> = ["a", "b", "c", "d", "e"].map(String::from).to_vec();
        assert_eq!(names_capped(&n, 2), "a, b and 3 others");
        assert_eq!(names_capped(&n[..3], 2), "a, b and c");
        assert_eq!(names_capped(&n[..1], 2), "a");
    }
}
