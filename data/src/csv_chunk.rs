//! One chunk of a CSV file's lines parsed into columns, on the fast path of
//! [`CsvFile`](crate::csv_fast::CsvFile): what one thread does.
//!
//! The chunk only takes what it can prove the exact reader
//! ([`Records`](crate::csv::Records)) reads the same way: comment and blank
//! lines dropped and counted as its line filter does, and rows that are
//! plain lines (as many cells as the header, each without quotes or quoted
//! simply: `"run 1"`) split at commas and trimmed as the csv crate's
//! `Trim::All` does. It stops at the first line it does not take (a line
//! longer than [`MAX_LINE_BYTES`] among them: the exact reader refuses
//! it), for the exact reader to go on from there. A cell is parsed here
//! only when the fast parser reads all of it to a finite number, which
//! `str::parse::<f64>` (both correctly rounded) reads to the same bits; any
//! other cell is left for [`cell`](crate::csv::cell) to read (or refuse)
//! from the line's text.

use crate::csv::MAX_LINE_BYTES;

/// The rows of a chunk: the selected columns' values and where each row is.
#[derive(Debug, Default)]
pub(crate) struct Chunk {
    /// The selected columns' values, row by row; NaN where the cell was
    /// left for the exact reading (never a value taken: those are finite).
    pub(crate) values: Vec<f64>,
    /// Per row: the physical lines of the chunk before its line.
    pub(crate) lines: Vec<u64>,
    /// Per row: where its line starts and ends (without the line end) in
    /// the chunk.
    pub(crate) spans: Vec<(usize, usize)>,
    /// `(row, comments, blanks)` for each row after dropped lines: the
    /// comment and blank lines of the chunk before it.
    pub(crate) drops: Vec<(usize, usize, usize)>,
    /// Physical, comment and blank lines of the chunk (before `stop` if any).
    pub(crate) physical: u64,
    pub(crate) comments: usize,
    pub(crate) blanks: usize,
    /// Where the first line the chunk does not take starts.
    pub(crate) stop: Option<usize>,
}

impl Chunk {
    /// Empty, its buffers kept.
    fn clear(&mut self) {
        self.values.clear();
        self.lines.clear();
        self.spans.clear();
        self.drops.clear();
        (self.physical, self.comments, self.blanks) = (0, 0, 0);
        self.stop = None;
    }
    /// The rows taken.
    pub(crate) fn rows(&self) -> usize {
        self.lines.len()
    }
    /// The comment and blank lines of the chunk before row `row`.
    pub(crate) fn dropped_before(&self, row: usize) -> (usize, usize) {
        let i = self.drops.partition_point(|(r, ..)| *r <= row);
        match i {
            0 => (0, 0),
            _ => (self.drops[i - 1].1, self.drops[i - 1].2),
        }
    }
}

/// The columns a chunk parses: `slots[c]` is the place of column `c` among
/// a row's values; the header has `cells` cells.
#[derive(Clone, Debug)]
pub(crate) struct Selection {
    pub(crate) cells: usize,
    pub(crate) slots: Vec<Option<usize>>,
    /// Values per row.
    pub(crate) width: usize,
}

impl Selection {
    /// Columns `columns` of a header of `cells` cells (each once, in order
    /// of first mention).
    pub(crate) fn new(cells: usize, columns: &[usize]) -> Selection {
        let mut slots = vec![None; cells];
        let mut width = 0;
        for &c in columns {
            if let Some(slot @ None) = slots.get_mut(c) {
                *slot = Some(width);
                width += 1;
            }
        }
        Selection {
            cells,
            slots,
            width,
        }
    }
}

/// Parses whole lines (`text` ends at a line end or the file's end) into
/// `chunk`, whose buffers are reused from batch to batch (memory stays
/// that of one batch, allocated once).
pub(crate) fn parse_chunk(text: &[u8], selection: &Selection, chunk: &mut Chunk) {
    chunk.clear();
    let mut pos = 0;
    let mut dropped = false;
    while pos < text.len() {
        // A line longer than the filter holds (its line end included) is
        // the exact reader's to refuse, at its line and byte.
        let end = line_end(text, pos);
        if (end + 1).min(text.len()) - pos > MAX_LINE_BYTES {
            chunk.stop = Some(pos);
            return;
        }
        // As the filter: a line of whitespace is blank, one whose first
        // other byte is `#` a comment.
        let first = text[pos..]
            .iter()
            .position(|b| *b == b'\n' || !b.is_ascii_whitespace())
            .map_or(text.len(), |k| pos + k);
        match text.get(first) {
            None | Some(b'\n') => {
                chunk.blanks += 1;
                dropped = true;
            }
            Some(b'#') => {
                chunk.comments += 1;
                dropped = true;
            }
            Some(_) => {
                if !take_row(&mut chunk.values, &text[pos..end], selection) {
                    chunk.stop = Some(pos);
                    return;
                }
                if dropped {
                    chunk
                        .drops
                        .push((chunk.rows(), chunk.comments, chunk.blanks));
                    dropped = false;
                }
                chunk.lines.push(chunk.physical);
                chunk.spans.push((pos, end));
            }
        }
        chunk.physical += 1;
        pos = end + 1;
    }
}

/// Where the line holding `from` ends (its LF, or the text's end): found by
/// `memchr`'s vectorised search.
fn line_end(text: &[u8], from: usize) -> usize {
    memchr::memchr(b'\n', &text[from..]).map_or(text.len(), |k| from + k)
}

/// Appends the selected values of the row `line` (without its line end);
/// false (nothing appended) for a line with a quote other than a simply
/// quoted cell's (see [`cell_text`]) or a cell count other than the
/// header's. The line's quotes and its commas are found by `memchr`'s
/// vectorised searches.
fn take_row(values: &mut Vec<f64>, line: &[u8], selection: &Selection) -> bool {
    if memchr::memchr(b'"', line).is_some() {
        take_quoted(values, line, selection)
    } else {
        take_plain(values, line, selection)
    }
}

/// [`take_row`] for a line without quotes.
fn take_plain(values: &mut Vec<f64>, line: &[u8], selection: &Selection) -> bool {
    let base = values.len();
    values.resize(base + selection.width, f64::NAN);
    let mut cell = |cells: usize, piece: &[u8]| {
        if let Some(Some(slot)) = selection.slots.get(cells)
            && let Some(v) = plain_number(piece.trim_ascii())
        {
            values[base + slot] = v;
        }
    };
    let (mut cells, mut from) = (0, 0);
    for comma in memchr::memchr_iter(b',', line) {
        cell(cells, &line[from..comma]);
        cells += 1;
        from = comma + 1;
    }
    cell(cells, &line[from..]);
    if cells + 1 != selection.cells {
        values.truncate(base);
        return false;
    }
    true
}

/// [`take_row`] for a line holding quotes.
fn take_quoted(values: &mut Vec<f64>, line: &[u8], selection: &Selection) -> bool {
    let base = values.len();
    values.resize(base + selection.width, f64::NAN);
    let mut cells = 0;
    for piece in line.split(|b| *b == b',') {
        let Some(text) = cell_text(piece) else {
            values.truncate(base);
            return false;
        };
        if let Some(Some(slot)) = selection.slots.get(cells)
            && let Some(v) = plain_number(text)
        {
            values[base + slot] = v;
        }
        cells += 1;
    }
    if cells != selection.cells {
        values.truncate(base);
        return false;
    }
    true
}

/// Whether every cell of a line is plain or simply quoted (see
/// [`cell_text`]): the csv reader then ends the record at the line's end
/// and the line filter, seeing an even number of quotes, stays outside
/// quoted cells.
pub(crate) fn plain_line(line: &[u8]) -> bool {
    !line.contains(&b'"') || line.split(|b| *b == b',').all(|p| cell_text(p).is_some())
}

/// Cell `i` of a line the chunk took, as the csv reader gives it (empty if
/// absent).
pub(crate) fn field(line: &[u8], i: usize) -> &[u8] {
    line.split(|b| *b == b',')
        .nth(i)
        .and_then(cell_text)
        .unwrap_or(b"")
}

/// A cell's text (the piece of a line between commas) as the csv reader
/// with `Trim::All` gives it, where the fast path can tell: a piece without
/// quotes, trimmed of ASCII whitespace; or one quoted simply — a quote as
/// its first byte, the closing quote, then only whitespace — whose text is
/// what is between the quotes, trimmed (the reader appends the whitespace
/// after the closing quote to it, and trims). `None` for any other quote.
fn cell_text(piece: &[u8]) -> Option<&[u8]> {
    match piece.split_first() {
        Some((b'"', rest)) => {
            let close = rest.iter().position(|b| *b == b'"')?;
            rest[close + 1..]
                .iter()
                .all(u8::is_ascii_whitespace)
                .then(|| rest[..close].trim_ascii())
        }
        _ if piece.contains(&b'"') => None,
        _ => Some(piece.trim_ascii()),
    }
}

/// A cell the fast parser reads to the bits `str::parse::<f64>` gives: a
/// decimal read whole to a finite value. `None` leaves the cell to the
/// exact reading. The fast parser reads whole only an optional sign, digits
/// with at most one point, and an exponent, or else `inf`, `infinity` and
/// `nan` (not finite): the cells `str::parse` reads, correctly rounded by
/// both (`csv_fast::tests::plain_numbers_are_parsed_to_the_bits_of_str_parse`
/// tries random texts over digits, signs, points, exponents and letters).
pub(crate) fn plain_number(cell: &[u8]) -> Option<f64> {
    match fast_float2::parse::<f64, _>(cell) {
        Ok(v) if v.is_finite() => Some(v),
        _ => None,
    }
}
