//! Diagnostics of one code and severity on one source line, grouped and
//! merged into one, so a line is printed once however many errors point at it.

use crate::diagnostic::data::{Diagnostic, Severity};
use crate::diagnostic::lists::MAX_LISTED;

/// The diagnostics as [`render`](crate::diagnostic::render::render) shows them: those of one code and severity
/// whose primary labels lie on one source line form one group (in the order
/// of their first member), so a line is printed once however many errors
/// point at it (`state u` 4,000 times on one line printed the line 4,000
/// times). Each group is a list of indices into `diagnostics`.
pub(crate) fn line_groups(diagnostics: &[Diagnostic], source: &str) -> Vec<Vec<usize>> {
    let line_starts: Vec<usize> = std::iter::once(0)
        .chain(source.match_indices('\n').map(|(i, _)| i + 1))
        .collect();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut by_key: std::collections::BTreeMap<(&str, Severity, usize), usize> =
        std::collections::BTreeMap::new();
    for (i, d) in diagnostics.iter().enumerate() {
        let Some(span) = d.primary_span() else {
            groups.push(vec![i]);
            continue;
        };
        let line = line_starts
            .partition_point(|s| *s <= span.start.min(source.len()))
            .saturating_sub(1);
        match by_key.entry((d.code.as_str(), d.severity, line)) {
            std::collections::btree_map::Entry::Occupied(e) => groups[*e.get()].push(i),
            std::collections::btree_map::Entry::Vacant(e) => {
                e.insert(groups.len());
                groups.push(vec![i]);
            }
        }
    }
    groups
}

/// One diagnostic for a group of [`line_groups`]: the first member's
/// message (with the count), notes and help; the primary label of at most
/// [`MAX_LISTED`] members (each saying its own message when the messages
/// differ) and their other labels once each; a note counting the rest.
pub(crate) fn merge(diagnostics: &[Diagnostic], members: &[usize]) -> Diagnostic {
    let first = &diagnostics[members[0]];
    let same_message = members
        .iter()
        .all(|i| diagnostics[*i].message == first.message);
    let mut d = first.clone();
    d.message = if same_message {
        format!("{} ({} times on this line)", first.message, members.len())
    } else {
        format!(
            "{} (and {} more on this line)",
            first.message,
            members.len() - 1
        )
    };
    d.labels = Vec::new();
    for (k, i) in members.iter().take(MAX_LISTED).enumerate() {
        let m = &diagnostics[*i];
        for l in &m.labels {
            let mut l = l.clone();
            if l.primary && !same_message {
                l.message = m.message.clone();
            } else if l.primary && k > 0 {
                // Said once, at the first caret.
                l.message = String::new();
            }
            if !d
                .labels
                .iter()
                .any(|x| x.span == l.span && x.primary == l.primary)
            {
                d.labels.push(l);
            }
        }
    }
    // Notes and helps of the marked members, each distinct one once.
    let mut helps: Vec<&str> = Vec::new();
    for i in members.iter().take(MAX_LISTED) {
        let m = &diagnostics[*i];
        for n in &m.notes {
            if !d.notes.contains(n) {
                d.notes.push(n.clone());
            }
        }
        if let Some(h) = &m.help
            && !helps.contains(&h.as_str())
        {
            helps.push(h);
        }
    }
    if !helps.is_empty() {
        d.help = Some(helps.join("; "));
    }
    if members.len() > MAX_LISTED {
        d.notes.push(format!(
            "… and {} more on this line, not marked",
            members.len() - MAX_LISTED
        ));
    }
    d
}

#[cfg(test)]
mod tests {
    use crate::ast::Span;
    use crate::diagnostic::data::Diagnostic;
    use crate::diagnostic::lists::MAX_LISTED;
    use crate::diagnostic::render::{RenderStyle, render};

    #[test]
    fn a_line_is_printed_once_however_many_errors_point_at_it() {
        // `state u` 4,000 times on one line must not give 257 MB of stderr
        // (or 50 copies of the line): one diagnostic marks the first 8.
        let src = format!("model M {{ {}}}\n", "state u ".repeat(4000));
        let first = Span::new(16, 17);
        let ds: Vec<Diagnostic> = (1..4000)
            .map(|k| {
                let at = 10 + 8 * k + 6;
                Diagnostic::error("duplicate-declaration", "`u` is declared twice")
                    .with_primary(Span::new(at, at + 1), "second declaration of a state")
                    .with_secondary(first, "first declared here")
                    .with_help("keep one")
            })
            .collect();
        let text = render(&ds, "m.som", &src, RenderStyle::Plain);
        assert!(text.len() < 3000, "{} bytes:\n{text}", text.len());
        assert_eq!(text.matches("\n1 │").count(), 1, "{text}");
        assert!(text.starts_with(
            "error[duplicate-declaration]: `u` is declared twice (3999 times on this line)\n  ┌─ m.som:1:25\n"
        ), "{text}");
        assert_eq!(text.matches('^').count(), MAX_LISTED, "{text}");
        assert!(
            text.contains("= note: … and 3991 more on this line, not marked"),
            "{text}"
        );
        assert!(!text.contains("not shown"), "{text}");
        // Different messages on one line: each caret says its own.
        let src = "model M { state u state v state u state v }\n";
        let ds = vec![
            Diagnostic::error("duplicate-declaration", "`u` is declared twice")
                .with_primary(Span::new(32, 33), "again"),
            Diagnostic::error("duplicate-declaration", "`v` is declared twice")
                .with_primary(Span::new(40, 41), "again"),
        ];
        let text = render(&ds, "m.som", src, RenderStyle::Plain);
        assert!(
            text.starts_with(
                "error[duplicate-declaration]: `u` is declared twice (and 1 more on this line)"
            ),
            "{text}"
        );
        assert!(text.contains("`v` is declared twice"), "{text}");
        assert_eq!(text.matches("\n1 │").count(), 1, "{text}");
        // Other lines and other codes stay apart.
        let src = "a\nb\n";
        let ds = vec![
            Diagnostic::error("x", "one").with_primary(Span::new(0, 1), ""),
            Diagnostic::error("x", "two").with_primary(Span::new(2, 3), ""),
            Diagnostic::error("y", "three").with_primary(Span::new(0, 1), ""),
        ];
        let text = render(&ds, "m.som", src, RenderStyle::Plain);
        assert_eq!(text.matches("error[").count(), 3, "{text}");
    }
}
