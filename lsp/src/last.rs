//! The last version of a document that parsed, kept so that hover,
//! definition and references still answer while the text does not parse.
//!
//! Its answers are mapped onto the current text through the bytes the two
//! versions share at their start and at their end: a name there is the
//! same name at a shifted place. A name in the edited middle, or touching
//! it (the edit may have lengthened it), maps to nothing, and an answer
//! about it is not given.

use crate::analysis::Analysis;
use leeway_grammar::Span;

/// The analysis of the last version that parsed, with its text.
pub struct LastParsed {
    /// The text of that version.
    pub text: String,
    /// Its analysis (its syntax tree is `Some`).
    pub analysis: Analysis,
}

/// How a span of the old text maps onto the new: the lengths of the common
/// start and end.
#[derive(Clone, Copy, Debug)]
pub struct Unchanged {
    prefix: usize,
    suffix: usize,
    old_len: usize,
    new_len: usize,
}

impl Unchanged {
    /// The longest common start and end of `old` and `new` (not overlapping).
    pub fn of(old: &str, new: &str) -> Unchanged {
        let (a, b) = (old.as_bytes(), new.as_bytes());
        let prefix = a.iter().zip(b).take_while(|(x, y)| x == y).count();
        let room = a.len().min(b.len()) - prefix;
        let suffix = a
            .iter()
            .rev()
            .zip(b.iter().rev())
            .take(room)
            .take_while(|(x, y)| x == y)
            .count();
        Unchanged {
            prefix,
            suffix,
            old_len: a.len(),
            new_len: b.len(),
        }
    }

    /// The old offset of a new one outside the edited middle.
    pub fn to_old(&self, at: usize) -> Option<usize> {
        if at < self.prefix {
            Some(at)
        } else if at >= self.new_len - self.suffix && at <= self.new_len {
            Some(at + self.old_len - self.new_len)
        } else {
            None
        }
    }

    /// The new place of an old span, when the span and the bytes on either
    /// side of it are unchanged.
    pub fn to_new(&self, span: Span) -> Option<Span> {
        let old_tail = self.old_len - self.suffix;
        let identical = self.prefix == self.old_len && self.old_len == self.new_len;
        if identical || span.end < self.prefix {
            Some(span)
        } else if span.start > old_tail {
            let shift = |x: usize| x + self.new_len - self.old_len;
            Some(Span::new(shift(span.start), shift(span.end)))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_before_and_after_an_edit_map_and_names_touching_it_do_not() {
        let old = "der v = Y_v*water.v\nder r = N_r*r\n";
        let new = "der v = Y_v*water.v +\nder r = N_r*r\n";
        let u = Unchanged::of(old, new);
        let y_v = Span::new(8, 11);
        assert_eq!(u.to_new(y_v), Some(y_v));
        let n_r = Span::new(
            old.find("N_r").unwrap_or(0),
            old.find("N_r").unwrap_or(0) + 3,
        );
        assert_eq!(u.to_new(n_r), Some(Span::new(n_r.start + 2, n_r.end + 2)));
        assert_eq!(u.to_old(new.find("N_r").unwrap_or(0)), Some(n_r.start));
        // `v` of `water.v` ends where the edit starts: it may have grown.
        assert_eq!(u.to_new(Span::new(18, 19)), None);
        assert_eq!(u.to_old(19), None);
    }

    #[test]
    fn edits_at_either_end_and_no_edit() {
        let same = Unchanged::of("ab cd", "ab cd");
        assert_eq!(same.to_new(Span::new(3, 5)), Some(Span::new(3, 5)));
        let front = Unchanged::of("ab cd", "x ab cd");
        assert_eq!(front.to_new(Span::new(0, 2)), None);
        assert_eq!(front.to_new(Span::new(3, 5)), Some(Span::new(5, 7)));
        let back = Unchanged::of("ab cd", "ab c");
        assert_eq!(back.to_new(Span::new(0, 2)), Some(Span::new(0, 2)));
        assert_eq!(back.to_new(Span::new(3, 5)), None);
        let emptied = Unchanged::of("ab", "");
        assert_eq!(emptied.to_new(Span::new(0, 2)), None);
        assert_eq!(emptied.to_old(0), Some(2));
    }
}
