//! The design's JSON document (`design --json`, `design.json`, Python's
//! `leeway.design`): the design's report with its verification, when run
//! (docs/json.md).

use crate::compare::Comparison;
use crate::report::Design;
use crate::verify::Verification;
use serde::Serialize;

/// The design (and its verification) as one document.
#[derive(Serialize)]
struct Document<'a> {
    #[serde(flatten)]
    design: &'a Design,
    verification: Option<&'a Verification>,
    #[serde(skip_serializing_if = "Option::is_none")]
    comparison: Option<&'a Comparison>,
}

/// The document as pretty JSON (non-finite numbers as `null`).
pub fn json(design: &Design, verification: Option<&Verification>) -> String {
    json_with(design, verification, None)
}

/// [`json`], with the comparison of a given input (`design --compare`).
pub fn json_with(
    design: &Design,
    verification: Option<&Verification>,
    comparison: Option<&Comparison>,
) -> String {
    let doc = Document {
        design,
        verification,
        comparison,
    };
    // Serialising plain data with string keys cannot fail; an error
    // would still be reported as a document rather than lost.
    serde_json::to_string_pretty(&doc).unwrap_or_else(|e| {
        format!(
            "{{\"error\": {}}}",
            serde_json::Value::String(e.to_string())
        )
    })
}
