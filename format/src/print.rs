//! Lines of code and the comments of the source → the formatted text.

use crate::comments::Comment;
use crate::layout::Line;

/// One output line: code (or a comment on its own), and the comments that
/// trail it, aligned afterwards.
struct Out {
    code: String,
    trailing: Vec<String>,
}

fn newlines(source: &str, from: usize, to: usize) -> usize {
    if from >= to {
        return 0;
    }
    source
        .get(from..to)
        .map_or(0, |gap| gap.matches('\n').count())
}

/// Each comment goes to the end of the line of code it was written on
/// (the line whose code began before it, when no newline parts them), or
/// else before the next line of code.
fn place<'c>(
    source: &str,
    lines: &[Line],
    comments: &'c [Comment],
) -> (Vec<Vec<&'c Comment>>, Vec<Vec<&'c Comment>>) {
    let mut leading = vec![Vec::new(); lines.len() + 1];
    let mut trailing = vec![Vec::new(); lines.len()];
    for c in comments {
        let on = lines.partition_point(|l| l.start <= c.span.start);
        match on.checked_sub(1) {
            Some(i)
                if c.span.start < lines[i].end
                    || newlines(source, lines[i].end, c.span.start) == 0 =>
            {
                trailing[i].push(c)
            }
            Some(i) => leading[i + 1].push(c),
            None => leading[0].push(c),
        }
    }
    (leading, trailing)
}

/// The formatted text.
pub(crate) fn print(source: &str, lines: &[Line], comments: &[Comment]) -> String {
    let (leading, trailing) = place(source, lines, comments);
    let mut out: Vec<Out> = Vec::new();
    // Where the last thing printed ended in the source.
    let mut prev_end = 0;
    // A blank line may not follow `model Name {` nor precede the first line.
    let mut blank_allowed = false;
    let last = lines.len().saturating_sub(1);
    for i in 0..=lines.len() {
        let indent = lines.get(i).map_or(0, |l| l.indent);
        for c in &leading[i] {
            if blank_allowed && newlines(source, prev_end, c.span.start) >= 2 {
                out.push(Out {
                    code: String::new(),
                    trailing: Vec::new(),
                });
            }
            out.push(Out {
                code: format!("{}{}", " ".repeat(indent), c.text),
                trailing: Vec::new(),
            });
            prev_end = c.span.end;
            blank_allowed = true;
        }
        let Some(line) = lines.get(i) else { break };
        if line.item_start
            && blank_allowed
            && i != last
            && newlines(source, prev_end, line.start) >= 2
        {
            out.push(Out {
                code: String::new(),
                trailing: Vec::new(),
            });
        }
        out.push(Out {
            code: format!("{}{}", " ".repeat(line.indent), line.text),
            trailing: trailing[i].iter().map(|c| c.text.clone()).collect(),
        });
        prev_end = trailing[i]
            .last()
            .map_or(line.end, |c| c.span.end.max(line.end));
        // Nothing blank right after the header.
        blank_allowed = i != 0;
    }
    render(&mut out)
}

/// Joins the lines, the trailing comments of consecutive lines aligned two
/// columns after the longest code among them.
fn render(out: &mut [Out]) -> String {
    let mut text = String::new();
    let mut i = 0;
    while i < out.len() {
        if out[i].trailing.is_empty() {
            text.push_str(&out[i].code);
            text.push('\n');
            i += 1;
            continue;
        }
        let run_end = (i..out.len())
            .find(|&j| out[j].trailing.is_empty())
            .unwrap_or(out.len());
        let column = out[i..run_end]
            .iter()
            .map(|o| o.code.chars().count())
            .max()
            .unwrap_or(0)
            + 2;
        for o in &out[i..run_end] {
            let pad = column - o.code.chars().count();
            text.push_str(&o.code);
            text.push_str(&" ".repeat(pad));
            text.push_str(&o.trailing.join(" "));
            text.push('\n');
        }
        i = run_end;
    }
    text
}
