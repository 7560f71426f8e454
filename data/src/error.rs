//! The one error type of data loading: what is wrong, where, and how to fix it.

/// A data problem, with its place.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{location}: {message}")]
pub struct DataError {
    /// `file`, `file:row` or `file:row:column`.
    pub location: String,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: String,
}

impl DataError {
    /// A problem at `location`, with a hint.
    pub fn new(
        location: impl Into<String>,
        message: impl Into<String>,
        hint: impl Into<String>,
    ) -> DataError {
        DataError {
            location: location.into(),
            message: message.into(),
            hint: hint.into(),
        }
    }
}
