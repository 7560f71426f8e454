//! Lists inside messages, capped at [`MAX_LISTED`] items so no message grows
//! with the model: `a, b, … (N more)` and `a, b and c`.

/// Most items a list inside a message, note or help names: the rest are
/// counted (`… (491 more)`), so no message grows with the model. Structured
/// output (JSON fields) keeps full lists.
pub const MAX_LISTED: usize = 8;

/// At most [`MAX_LISTED`] items joined by `sep`, then `sep… (N more)`:
/// `x0, x1, …, x7, … (9992 more)`.
pub fn join_capped<I>(items: I, sep: &str) -> String
where
    I: IntoIterator,
    I::Item: std::fmt::Display,
{
    let mut out = String::new();
    let mut rest = 0usize;
    for (i, item) in items.into_iter().enumerate() {
        if i < MAX_LISTED {
            if i > 0 {
                out.push_str(sep);
            }
            out.push_str(&item.to_string());
        } else {
            rest += 1;
        }
    }
    if rest > 0 {
        out.push_str(&format!("{sep}… ({rest} more)"));
    }
    out
}

/// `a`, `a and b`, `a, b and c`; beyond [`MAX_LISTED`] items
/// `a, b, …, h and 491 more`.
pub fn and_list<I>(items: I) -> String
where
    I: IntoIterator,
    I::Item: std::fmt::Display,
{
    let mut shown: Vec<String> = Vec::new();
    let mut rest = 0usize;
    for item in items {
        if shown.len() < MAX_LISTED + 1 {
            shown.push(item.to_string());
        } else {
            rest += 1;
        }
    }
    if rest > 0 {
        // Nine kept: the ninth is counted with the rest.
        shown.truncate(MAX_LISTED);
        return format!("{} and {} more", shown.join(", "), rest + 1);
    }
    match shown.len() {
        0 => String::new(),
        1 => shown.remove(0),
        n => format!("{} and {}", shown[..n - 1].join(", "), shown[n - 1]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_are_capped() {
        assert_eq!(join_capped(["a", "b"], ", "), "a, b");
        assert_eq!(
            join_capped((0..10).map(|i| format!("x{i}")), ", "),
            "x0, x1, x2, x3, x4, x5, x6, x7, … (2 more)"
        );
        assert_eq!(and_list(["a"]), "a");
        assert_eq!(and_list(["a", "b", "c"]), "a, b and c");
        assert_eq!(
            and_list((0..9).map(|i| i.to_string())),
            "0, 1, 2, 3, 4, 5, 6, 7 and 8"
        );
        assert_eq!(
            and_list((0..10).map(|i| i.to_string())),
            "0, 1, 2, 3, 4, 5, 6, 7 and 2 more"
        );
        assert_eq!(and_list(Vec::<String>::new()), "");
    }
}
