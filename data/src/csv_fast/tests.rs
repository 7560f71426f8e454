//! The fast path against the exact reader: the same rows, values (bits),
//! lines, bytes, counts and errors, whatever the batches and threads.

use super::*;
use crate::csv_chunk::plain_number;
use leeway_model::experiment::Source;
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
            // A cell parsed ahead is what `number` gives, bit for bit.
            let ahead = table.parsed_row().and_then(|p| p.get(i));
            match table.number(i, &format!("c{i}")) {
                Ok(v) => {
                    assert!(
                        ahead.is_none_or(|a| a.to_bits() == v.to_bits()),
                        "{row} {i}"
                    );
                    row.push_str(&format!(" {:x}", v.to_bits()));
                }
                Err(e) => {
                    assert!(ahead.is_none(), "{row} {i}: parsed ahead, yet {e:?}");
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
    let scale = [1e-8, 1e-5, 1e-3, 0.1, 1.0, 10.0, 1e3, 1e7][rng.random_range(0..8)];
    let v: f64 = rng.random_range(-1e3..1e3) * scale;
    match rng.random_range(0..8) {
        0 => format!("{v:e}"),
        1 => format!("{v:E}"),
        2 => format!("{v:.3}"),
        3 => format!("+{}", v.abs()),
        4 => format!("{}", rng.random_range(-50i32..50)),
        5 => format!("{v:.17e}"),
        6 => format!("{:.1}", v.abs())
            .trim_start_matches('0')
            .to_string(),
        _ => format!("{v:?}"),
    }
}

/// Something the fast path leaves to the exact reader, or a bad cell.
const ODD: &[&str] = &[
    "\"1.5\"",
    " \"1.5\"",
    "\" 2.5 \" \t",
    "\"2.5\"x",
    "\"\"",
    "\"a\"\"b\"",
    "\"a,b\"",
    "x\"y",
    "\"run 1\"",
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
    if rng.random_bool(0.3) {
        text.push_str(&format!("\"time\",\" u \",r,delta,\"experiment\"{end}"));
    } else {
        text.push_str(&format!("time, u ,r,delta,experiment{end}"));
    }
    // As R's write.csv and some loggers write text.
    let quote_labels = rng.random_bool(0.3);
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
        let label = if k < rows / 2 { "a" } else { "b b" };
        cells.push(if quote_labels {
            format!("\"{label}\"")
        } else {
            label.to_string()
        });
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
        let odd = if case % 3 == 0 {
            0
        } else {
            rng.random_range(0..3)
        };
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
        b"\"time\", \"u\" \r\n1,\"2\"\r\n3,4\r\n",
        b"\"time\" x,u\n1,2\n",
        b"a\"b,\"c\n\"1,2\n3,4\n",
        b"time,u\n1,\"2\"\"\"\n3,4\n",
        b"time,u\n1,\"2\n# not a comment\n\"\n3,4\n",
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
    // What the fast parser would take were it not for the cell's whole text
    // or finiteness: words it reads, other notations, separators, spaces.
    let wide = b"0123456789+-.eEinfatyINFATYxXp_, \t\r";
    let words = [
        "inf",
        "-inf",
        "+Infinity",
        "NaN",
        "nan",
        "infinity",
        "infinit",
        "0x1p3",
        "1_000",
        "1e",
        "1e+",
        ".e1",
        "+.5",
        "5.",
        ".",
        "-",
        "+",
        "--1",
        "1..2",
        "1e5.5",
        " 1",
        "1 ",
        "1e400",
        "-1e400",
        "4.9e-324",
        "2.4e-324",
        "1,5",
        "\u{661}",
    ];
    for w in words {
        let std = w.parse::<f64>().ok().filter(|v| v.is_finite());
        assert_eq!(
            plain_number(w.as_bytes()).map(f64::to_bits),
            std.map(f64::to_bits),
            "{w:?}"
        );
    }
    let mut taken = 0;
    for k in 0..300_000 {
        let s: String = if k % 3 == 2 {
            let n = rng.random_range(1..12);
            (0..n)
                .map(|_| wide[rng.random_range(0..wide.len())] as char)
                .collect()
        } else if k % 2 == 0 {
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

/// The test model: time, two states, one input, an experiment column.
fn model() -> leeway_structure::ir::Ir {
    let src = "model M { state u, r input delta der u = X*u + T*delta der r = N*r step 1.0 }";
    leeway_structure::compile(src, &leeway_structure::CompileOptions::default())
        .ir
        .unwrap_or_else(|| panic!("the test model compiles"))
}

/// `n` rows of a valid log, `odd(k)` replacing row k's text when it gives one.
fn big_log(n: usize, odd: &dyn Fn(usize) -> Option<String>) -> Vec<u8> {
    let mut text = String::from("# logger\ntime,u,r,delta\n");
    for k in 0..n {
        if k % 100_000 == 50_000 {
            text.push_str("# pause\r\n\n");
        }
        match odd(k) {
            Some(row) => text.push_str(&row),
            None => text.push_str(&format!(
                "{k},{},{:e},35\n",
                1.0 + 1e-3 * (k % 7) as f64,
                ((k % 1000) as f64 * 1e-3).sin()
            )),
        }
    }
    text.into_bytes()
}

/// Every value of the loaded experiments, as bits.
fn bits(loaded: &crate::notes::LoadedFile) -> Vec<u64> {
    let mut out = Vec::new();
    for e in &loaded.experiments {
        e.visit(&mut |r| {
            out.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits()));
        });
    }
    out
}

#[test]
fn a_quoted_cell_in_a_large_file_and_the_rows_after_it_read_as_today() {
    let ir = model();
    let options = crate::options::LoadOptions::default();
    // A simply quoted cell (the fast path's), then one holding a line end
    // (the exact reader's from there on).
    let text = big_log(300_000, &|k| match k {
        100_001 => Some(format!("{k},\"1.5\",0.5,35\n")),
        150_001 => Some(format!("{k},\" 1.25\n\",0.5,35\n")),
        _ => None,
    });
    let f = file_of(&text);
    let exact = load_table(
        &mut Records::open(f.path(), "--data").unwrap_or_else(|e| panic!("{e}")),
        &ir,
        &options,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut table = CsvFile::open_with(
        f.path(),
        "--data",
        Batching {
            chunk: 1 << 16,
            threads: 3,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let fast = load_table(&mut table, &ir, &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !table.is_fast(),
        "the quoted cell is read by the exact reader"
    );
    assert_eq!(fast.notes, exact.notes);
    assert_eq!(bits(&fast), bits(&exact));
    assert_eq!(fast.experiments[0].len(), 300_000);
    let mut u = Vec::new();
    fast.experiments[0].visit(&mut |r| u.push(r.states[0]));
    assert_eq!((u[100_001], u[150_001]), (1.5, 1.25));
    assert_eq!((fast.notes.comment_lines, fast.notes.blank_lines), (4, 3));
}

#[test]
fn a_bad_cell_deep_in_a_large_file_is_located_as_today_whatever_the_threads() {
    let ir = model();
    let options = crate::options::LoadOptions::default();
    let text = big_log(720_000, &|k| {
        (k == 700_000).then(|| format!("{k},1,0.5x,35\n"))
    });
    let f = file_of(&text);
    let mut errors = Vec::new();
    for threads in [1, 2, 5] {
        let mut table = CsvFile::open_with(
            f.path(),
            "--data",
            Batching {
                chunk: 1 << 18,
                threads,
            },
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let err = load_table(&mut table, &ir, &options)
            .err()
            .unwrap_or_else(|| panic!("`0.5x` is not a number"));
        assert!(table.is_fast(), "a bad cell needs no hand-over");
        errors.push(err);
    }
    // Row k sits on line k + 3 (a comment, the header) plus two dropped
    // lines before rows 50 000, 150 000, … (7 of them before row 700 000).
    let at = format!("{}:{}:3 (r)", f.path().display(), 700_000 + 3 + 2 * 7);
    assert_eq!(errors[0].location, at);
    assert_eq!(errors[0].message, "`0.5x` is not a number");
    assert!(errors.iter().all(|e| *e == errors[0]));
    let exact = load_table(
        &mut Records::open(f.path(), "--data").unwrap_or_else(|e| panic!("{e}")),
        &ir,
        &options,
    )
    .err()
    .unwrap_or_else(|| panic!("`0.5x` is not a number"));
    assert_eq!(errors[0], exact);
}

#[test]
fn the_loaded_file_does_not_depend_on_batches_or_threads() {
    let ir = model();
    let options = crate::options::LoadOptions::default();
    let text = big_log(20_000, &|k| match k {
        7_000 => Some(format!("{k}, 1.0 ,\t2e-3,+35\r\n")),
        9_000 => Some(format!("{k},1,0.5,35,\n")),
        _ => None,
    });
    let f = file_of(&text);
    let want = load_table(
        &mut Records::open(f.path(), "--data").unwrap_or_else(|e| panic!("{e}")),
        &ir,
        &options,
    );
    for (chunk, threads) in [(1, 1), (97, 2), (4096, 3), (1 << 20, 8)] {
        let mut table = CsvFile::open_with(f.path(), "--data", Batching { chunk, threads })
            .unwrap_or_else(|e| panic!("{e}"));
        let got = load_table(&mut table, &ir, &options);
        assert_eq!(got.as_ref().map(bits), want.as_ref().map(bits));
        assert_eq!(
            got.map(|l| l.notes),
            want.as_ref().map(|l| l.notes.clone()).map_err(Clone::clone)
        );
    }
}

#[test]
fn the_fast_path_hands_its_parsed_cells_over_and_leaves_the_others() {
    let f = file_of(b"a,b,c\n1.5,x,-2e3\n\"4\",5,inf\n");
    let mut r = CsvFile::open_with(
        f.path(),
        "--data",
        Batching {
            chunk: 1000,
            threads: 1,
        },
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    // Columns chosen out of order, one twice: each keeps its own slot.
    r.select(&[2, 0, 2]);
    let mut rows = Vec::new();
    while r.next_row().unwrap_or_else(|e| panic!("{e:?}")) {
        let p = r
            .parsed_row()
            .unwrap_or_else(|| panic!("the fast path parsed the row"));
        rows.push([p.get(0), p.get(1), p.get(2)]);
    }
    assert!(r.is_fast());
    // `x` and `5` are not read (column 1 is not chosen), a simply quoted
    // `"4"` is, and `inf` is left to `number` (not finite: its error).
    assert_eq!(
        rows,
        [[Some(1.5), None, Some(-2e3)], [Some(4.0), None, None]],
    );
}

/// The exact reader's transcript of `text` and the fast reader's for a few
/// batchings, all alike; the exact one returned.
fn read_alike(text: &[u8], columns: &[usize]) -> Vec<String> {
    let f = file_of(text);
    let want = exact(f.path(), columns, None);
    for (chunk, threads) in [(1 << 20, 2), (1 << 16, 3), (100, 1)] {
        let (got, _) = fast(f.path(), Batching { chunk, threads }, columns, None);
        assert_eq!(got, want, "chunk {chunk}, threads {threads}");
    }
    want
}

/// The last entry of a transcript: its end or its error.
fn last(transcript: &[String]) -> &str {
    transcript.last().map_or("", String::as_str)
}

#[test]
fn a_line_longer_than_a_mib_is_an_error_at_its_line_and_byte_by_either_reader() {
    let head = b"time,u\n1,2\n".to_vec();
    let long = |end: &[u8]| {
        let mut text = head.clone();
        text.extend(std::iter::repeat_n(b'7', 2 << 20));
        text.extend_from_slice(end);
        text
    };
    // Without a line end, with one and rows after, a comment line: the
    // error is at line 3, from byte 11, never the line read whole.
    for text in [long(b""), long(b"\n3,4\n"), {
        let mut t = head.clone();
        t.push(b'#');
        t.extend(long(b"\n")[head.len()..].iter());
        t
    }] {
        let started = std::time::Instant::now();
        let t = read_alike(&text, &[0, 1]);
        assert!(
            last(&t).contains("location: \"") && last(&t).contains(":3\""),
            "{t:?}"
        );
        assert!(
            last(&t).contains(
                "a line longer than 1 MiB: no line end within 1048576 bytes from byte 11"
            ),
            "{t:?}"
        );
        assert!(started.elapsed().as_secs() < 20);
    }
    // A line of exactly the limit, its line end included, is read.
    let mut text = head.clone();
    text.push(b'#');
    text.extend(std::iter::repeat_n(b' ', MAX_LINE_BYTES - 2));
    text.extend_from_slice(b"\n3,4\n");
    let t = read_alike(&text, &[0, 1]);
    assert!(last(&t).starts_with("end (1, 0)"), "{t:?}");
    // One byte more is refused.
    text.insert(head.len() + 1, b' ');
    let t = read_alike(&text, &[0, 1]);
    assert!(last(&t).contains("a line longer than 1 MiB"), "{t:?}");
}

#[test]
fn a_quoted_cell_left_open_over_a_mib_of_lines_is_an_error_at_its_first_line() {
    let mut text = b"time,u\n1,2\n3,\"4\n".to_vec();
    for _ in 0..(600 << 10) {
        text.extend_from_slice(b"5,6\n");
    }
    let t = read_alike(&text, &[0, 1]);
    assert!(last(&t).contains(":3\""), "{t:?}");
    assert!(
        last(&t)
            .contains("a record longer than 1 MiB: the quoted cell opened in it (from byte 11)"),
        "{t:?}"
    );
    // A quote inside an unquoted cell is a character like any (the csv
    // reader's rule), not an open quoted cell: the rows after it read.
    let mut text = b"time,u,note\n1,2,Joe\"s boat\n".to_vec();
    for k in 0..(300 << 10) {
        text.extend_from_slice(format!("{k},6,x\n").as_bytes());
    }
    let t = read_alike(&text, &[0, 1]);
    assert!(last(&t).starts_with("end"), "{}", last(&t));
    assert_eq!(t.len(), 2 + 1 + (300 << 10));
}

#[test]
fn text_without_line_ends_costs_a_mib_not_all_memory() {
    // An endless stream of zeros (as `/dev/zero`): one located error.
    let zeros = std::io::BufReader::new(std::io::repeat(0));
    let e = Records::new("zeros", zeros, "--data")
        .err()
        .unwrap_or_else(|| panic!("zeros are refused"));
    assert_eq!(e.location, "zeros:1");
    assert!(e.message.contains("from byte 0"), "{e:?}");
    // The device itself, by path, as the CLI opens it.
    if Path::new("/dev/zero").exists() {
        let e = crate::file::with_table(Path::new("/dev/zero"), "--data", |_| Ok(()))
            .err()
            .unwrap_or_else(|| panic!("/dev/zero is refused"));
        assert_eq!(e.location, "/dev/zero:1", "{e:?}");
    }
}

#[test]
fn a_pipe_is_read_as_a_stream_and_never_peeked_at() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let fifo = dir.path().join("log.csv");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("no mkfifo here: skipped");
        return;
    }
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            // Opening waits for the reader; one reader, one stream.
            let mut w = std::fs::OpenOptions::new()
                .write(true)
                .open(&fifo)
                .unwrap_or_else(|e| panic!("{e}"));
            std::io::Write::write_all(&mut w, b"time,u\n1,2\n3,4\n").is_ok()
        })
    };
    let (done, outcome) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let read = crate::file::with_table(&fifo, "--data", |t| {
            let mut rows = Vec::new();
            while t.next_row()? {
                rows.push((t.number(0, "time")?, t.number(1, "u")?));
            }
            Ok((t.headers().to_vec(), rows))
        });
        let _ = done.send(read);
    });
    let read = outcome
        .recv_timeout(std::time::Duration::from_secs(20))
        .unwrap_or_else(|_| panic!("reading the pipe hangs"));
    let (headers, rows) = read.unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(headers, ["time", "u"]);
    assert_eq!(rows, [(1.0, 2.0), (3.0, 4.0)]);
    assert!(writer.join().unwrap_or(false), "the writer wrote it all");
}
