//! What a design reports instead of a plan: a plan file the design cannot
//! read (with its line and column), or a model no plan can serve.

/// A design's error: a stable code, the message, a hint, and where in the
/// plan file when the file is at fault.
#[derive(Clone, Debug, PartialEq)]
pub struct DesignError {
    /// `plan` (the plan file), `cannot-design` (the model or conditions
    /// admit no plan), `not-identifiable`.
    pub code: &'static str,
    /// What is wrong.
    pub message: String,
    /// What to do.
    pub hint: String,
    /// Line in the plan file (1-based).
    pub line: Option<usize>,
    /// Column in the plan file (1-based).
    pub column: Option<usize>,
    /// The plan's value at fault (`budget.time`), located in the file's
    /// text by [`crate::plan::locate`].
    pub key: Option<String>,
}

impl DesignError {
    /// A problem in the plan file.
    pub fn plan(message: String, hint: &str) -> DesignError {
        DesignError {
            code: "plan",
            message,
            hint: hint.to_string(),
            line: None,
            column: None,
            key: None,
        }
    }
    /// A model or conditions no plan can serve.
    pub fn cannot(message: &str, hint: &str) -> DesignError {
        DesignError {
            code: "cannot-design",
            message: message.to_string(),
            hint: hint.to_string(),
            line: None,
            column: None,
            key: None,
        }
    }
    /// An option out of its bounds (`pilot`).
    pub fn option(message: String, hint: &str) -> DesignError {
        DesignError {
            code: "invalid-option",
            ..DesignError::cannot(&message, hint)
        }
    }
    /// About the plan's value `key` (`budget.time`, `inputs.f.range`).
    pub fn key(mut self, key: &str) -> DesignError {
        self.key = Some(key.to_string());
        self
    }
    /// Located at a line and column of the plan file.
    pub fn at(mut self, line: usize, column: usize) -> DesignError {
        self.line = Some(line);
        self.column = Some(column);
        self
    }
}

impl std::fmt::Display for DesignError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for DesignError {}
