//! The fast path against the exact reader: the same rows, values (bits),
//! lines, bytes, counts and errors, whatever the batches and threads.

use super::*;
use crate::csv_chunk::plain_number;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A file holding `text`, removed when dropped.
fn file_of(text: &[u8]) -> tempfile::NamedTempFile {
    let mut f = tempfile::Builder::new()
        .suffix(".csv")
        .tempfile()
        .unwrap_or_else(|e| panic!("{e}"));
    std::io::Write::write_all(&mut f, text).unwrap_or_else(|e| panic!("{e}"));
    f
}

/// Everything a table tells the validating pass, row by row, until its end
/// or its first error: a transcript to compare.
fn transcript(table: &mut dyn Table, columns: &[usize], label: Option<usize>) -> Vec<String> {
    let mut out = vec![format!(
        "{:?} {} {} {:?}",
        table.headers(),
        table.header_at(Some(1)),
        table.first_position(),
        table.dropped()
    )];
    table.select(columns);
    loop {
        match table.next_row() {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => {
                out.push(format!("row error {e:?}"));
                return out;
            }
        }
        let mut row = format!(
            "{} {} {:?}",
            table.position(),
            table.offset(),
            table.dropped()
        );
        for &i in columns {
            match table.number(i, &format!("c{i}")) {
                Ok(v) => row.push_str(&format!(" {:x}", v.to_bits())),
                Err(e) => {
                    out.push(format!("{row} cell error {e:?}"));
                    return out;
                }
            }
        }
        if let Some(i) = label {
            let l = table.label(i).map(|l| l.into_owned());
            row.push_str(&format!(" {l:?}"));
        }
        out.push(row);
    }
    out.push(format!("end {:?}", table.dropped()));
    out
}

/// The exact reader's transcript of a file.
fn exact(path: &Path, columns: &[usize], label: Option<usize>) -> Vec<String> {
    match Records::open(path, "--data") {
        Ok(mut r) => transcript(&mut r, columns, label),
        Err(e) => vec![format!("open error {e:?}")],
    }
}

/// The fast reader's transcript of a file, and whether it stayed fast.
fn fast(
    path: &Path,
    batching: Batching,
    columns: &[usize],
    label: Option<usize>,
) -> (Vec<String>, bool) {
    match CsvFile::open_with(path, "--data", batching) {
        Ok(mut r) => {
            let t = transcript(&mut r, columns, label);
            (t, r.is_fast())
        }
        Err(e) => (vec![format!("open error {e:?}")], false),
    }
}

/// A number as a logger might write it.
fn number_text(rng: &mut ChaCha8Rng) -> String {
    let v: f64 = rng.random_range(-1e3..1e3) * 10f64.powi(rng.random_range(-8..8));
    match rng.random_range(0..8) {
        0 => format!("{v:e}"),
        1 => format!("{v:E}"),
        2 => format!("{v:.3}"),
        3 => format!("+{}", v.abs()),
        4 => format!("{}", rng.random_range(-50i32..50)),
        5 => format!("{v:.17e}"),
        6 => format!("{:.1}", v.abs()).trim_start_matches('0').to_string(),
        _ => format!("{v:?}"),
    }
}

/// Something the fast path leaves to the exact reader, or a bad cell.
const ODD: &[&str] = &[
    "\"1.5\"",
    "\"a\nb\"",
    "\"x,\n\n# y\"",
    "NaN",
    "inf",
    "-infinity",
    "",
    "abc",
    "1.2.3",
    "--1",
    "0x10",
    "1e400",
    "1e",
    ".",
    "1_0",
    "\u{feff}2",
    "\u{a0}3",
];

/// A CSV text of `rows` rows of `time,u,r,delta,experiment` with comments,
/// blank lines, CRLF, spaces, signs, exponents and `odd` odd cells.
fn layout(rng: &mut ChaCha8Rng, rows: usize, odd: usize) -> Vec<u8> {
    let crlf = rng.random_bool(0.3);
    let end = if crlf { "\r\n" } else { "\n" };
    let mut text = String::new();
    if rng.random_bool(0.2) {
        text.push_str("# logger\n\n");
    }
    text.push_str(&format!("time, u ,r,delta,experiment{end}"));
    let odd_rows: Vec<usize> = (0..odd).map(|_| rng.random_range(0..rows.max(1))).collect();
    for k in 0..rows {
        match rng.random_range(0..30) {
            0 => text.push_str(&format!("# pause {k}{end}")),
            1 => text.push_str(&format!("  \t{end}")),
            2 => text.push_str(&format!("   # \"quoted\" note{end}")),
            3 => text.push_str(end),
            _ => {}
        }
        let mut cells: Vec<String> = (0..4).map(|_| number_text(rng)).collect();
        cells.push(if k < rows / 2 { "a" } else { "b b" }.to_string());
        if odd_rows.contains(&k) {
            match rng.random_range(0..4) {
                0 => cells.push("9".to_string()),
                1 => {
                    cells.pop();
                }
                _ => {
                    let c = rng.random_range(0..5);
                    cells[c] = ODD[rng.random_range(0..ODD.len())].to_string();
                }
            }
        }
        for c in &mut cells {
            if rng.random_bool(0.1) {
                *c = format!(" {c}\t");
            }
        }
        text.push_str(&cells.join(","));
        if k + 1 < rows || rng.random_bool(0.7) {
            text.push_str(end);
        }
    }
    if rng.random_bool(0.3) {
        text.push_str(&format!("# end{end}{end}"));
    }
    text.into_bytes()
}

#[test]
fn fast_reading_is_the_exact_reading_for_any_layout_batches_and_threads() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut stayed_fast = 0;
    for case in 0..300 {
        let rows = rng.random_range(0..60);
        let odd = if case % 3 == 0 { 0 } else { rng.random_range(0..3) };
        let text = layout(&mut rng, rows, odd);
        let f = file_of(&text);
        let columns: Vec<usize> = match case % 3 {
            0 => vec![0, 1, 2, 3],
            1 => vec![3, 0],
            _ => vec![2],
        };
        let want = exact(f.path(), &columns, Some(4));
        for threads in [1, 3] {
            let chunk = rng.random_range(1..200);
            let (got, on_fast) = fast(f.path(), Batching { chunk, threads }, &columns, Some(4));
            assert_eq!(
                got,
                want,
                "case {case}, chunk {chunk}, threads {threads}:\n{}",
                String::from_utf8_lossy(&text)
            );
            stayed_fast += usize::from(on_fast);
        }
    }
    // Most files without odd cells are read on the fast path to their end.
    assert!(stayed_fast > 150, "{stayed_fast}");
}

#[test]
fn files_the_fast_path_does_not_start_on_are_read_exactly() {
    let texts: &[&[u8]] = &[
        b"",
        b"# only a comment\n\n",
        b"time,u\r1,2\r3,4\r",
        b"\"time\",u\n1,2\n",
        b"\"ti\nme\",u\n1,2\n",
        b"time,u\n",
        b"time,u",
        b"time,time\n1,2\n",
        b"\xef\xbb\xbftime,u\n1,2\n",
        b"time,u\n1,2",
        b"time,u\n1,2\n\"3\",4\n5,6\n",
        b"time,u\n1,2\n3,4,5\n5,6\n",
        b"time,u\n1,2\n\xef\xbb\xbf\"3\",4\n5,6\n",
        b"time,u\n1,2\n\xef\xbb\xbf3,4\n5,6\n",
        b"x\n1\n\"2\"\n3\n",
    ];
    for text in texts {
        let f = file_of(text);
        let want = exact(f.path(), &[0, 1], None);
        for chunk in [1, 2, 5, 1000] {
            for threads in [1, 2] {
                let (got, _) = fast(f.path(), Batching { chunk, threads }, &[0, 1], None);
                assert_eq!(got, want, "{:?}", String::from_utf8_lossy(text));
            }
        }
    }
}

#[test]
fn plain_numbers_are_parsed_to_the_bits_of_str_parse() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let alphabet = b"0123456789+-.eE";
    let mut taken = 0;
    for k in 0..200_000 {
        let s: String = if k % 2 == 0 {
            let n = rng.random_range(1..28);
            (0..n)
                .map(|_| alphabet[rng.random_range(0..alphabet.len())] as char)
                .collect()
        } else {
            let bits: u64 = rng.random();
            match k % 6 {
                1 => format!("{:?}", f64::from_bits(bits)),
                3 => format!("{:.25e}", f64::from_bits(bits)),
                _ => number_text(&mut rng),
            }
        };
        let std = s.parse::<f64>().ok().filter(|v| v.is_finite());
        match plain_number(s.as_bytes()) {
            Some(v) => {
                taken += 1;
                assert_eq!(std.map(f64::to_bits), Some(v.to_bits()), "{s:?}");
            }
            // Left to the exact reading: fine whatever std says, but a plain
            // finite decimal is expected to be taken.
            None => assert!(
                std.is_none() || !s.starts_with(|c: char| c.is_ascii_digit() || c == '-'),
                "{s:?} not taken"
            ),
        }
    }
    assert!(taken > 100_000, "{taken}");
}
