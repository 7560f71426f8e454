use super::*;
use leeway_model::experiment::{Experiment, Source};
use leeway_structure::ir::Ir;

fn model(data: &str) -> Ir {
    let src =
        format!("model M {{ state u, r input delta der u = X*u + T*delta der r = N*r {data} }}");
    leeway_structure::compile(&src, &leeway_structure::CompileOptions::default())
        .ir
        .unwrap_or_else(|| panic!("the test model compiles"))
}

fn rows(from: usize, n: usize) -> String {
    (from..from + n)
        .map(|k| format!("{k}.0,1,0.5,35\n"))
        .collect()
}

#[test]
fn comment_lines_are_skipped_counted_and_rows_keep_their_line_numbers() {
    let ir = model("step 1.0");
    // Comments before the header, between rows (indented too), and a bad
    // cell on physical line 16.
    let mut text = String::from("# logger v2\n# ship: Test\ntime,u,r,delta\n");
    text.push_str(&rows(0, 5));
    text.push_str("  # pause\n");
    text.push_str(&rows(5, 5));
    text.push_str("10.0,1,x,35\n");
    let err = parse_csv("c.csv", text.as_bytes(), &ir, &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("the cell `x` is an error"));
    assert_eq!(err.location, "c.csv:15:3 (r)");
    let ok = text.replace("10.0,1,x,35\n", "");
    let loaded = parse_csv_noted("c.csv", ok.as_bytes(), &ir, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.notes.comment_lines, 3);
    assert_eq!(loaded.experiments[0].len(), 10);
    // A missing column is located on the header's physical line.
    let err = parse_csv(
        "c.csv",
        ok.replace("delta", "rudder").as_bytes(),
        &ir,
        &LoadOptions::default(),
    )
    .err()
    .unwrap_or_else(|| panic!("a missing column is an error"));
    assert_eq!(err.location, "c.csv:3");
}

#[test]
fn declared_units_are_converted_to_base_units() {
    let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
    let mut text = String::from("time,u,r,rudder\n");
    for k in 0..12 {
        text.push_str(&format!("{},1,{k}.5,35\n", 500 * k));
    }
    let e = parse_csv("u.csv", text.as_bytes(), &ir, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let e = &e[0];
    assert_eq!(e.h, 0.5);
    assert_eq!(e.inputs[0][0], 35.0f64.to_radians());
    assert_eq!(e.states[1][3], 3.5f64.to_radians());
    assert_eq!(e.states[0][3], 1.0);
}

#[test]
fn a_dropped_sample_is_located_and_names_the_options() {
    let ir = model("");
    let mut text = String::from("time,u,r,delta\n");
    for k in (0..20).filter(|k| *k != 7) {
        text.push_str(&format!("{},1,0,0\n", f64::from(k) * 0.5));
    }
    let err = parse_csv("d.csv", text.as_bytes(), &ir, &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("a dropped sample is an error"));
    // Rows 0..6 sit on lines 2..8; the row after the gap is on line 9.
    assert_eq!(err.location, "d.csv:9:1 (time)");
    assert!(err.hint.contains("--time-tolerance") && err.hint.contains("--resample"));
}

fn error_of(text: &str) -> DataError {
    parse_csv(
        "b.csv",
        text.as_bytes(),
        &model("step 1.0"),
        &LoadOptions::default(),
    )
    .err()
    .unwrap_or_else(|| panic!("an error expected in:\n{text}"))
}

#[test]
fn blank_lines_are_counted_and_rows_keep_their_physical_line() {
    let ir = model("step 1.0");
    // Blank lines (empty, spaces, CRLF) before the header and between rows.
    let mut text = String::from("\n  \ntime,u,r,delta\n");
    text.push_str(&rows(0, 5));
    text.push_str("\n \t \r\n");
    text.push_str(&rows(5, 5));
    let loaded = parse_csv_noted("b.csv", text.as_bytes(), &ir, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.notes.blank_lines, 4);
    assert_eq!(loaded.experiments[0].len(), 10);
    // Line 1, 2 blank, 3 header, 4..8 rows, 9 and 10 blank, 11.. rows.
    text.push_str("10.0,1,x,35\n");
    assert_eq!(error_of(&text).location, "b.csv:16:3 (r)");
}

#[test]
fn a_quoted_cell_holding_line_breaks_keeps_later_rows_on_their_line() {
    let mut text = String::from("time,u,r,delta,note\n");
    for k in 0..12 {
        let note = if k == 3 {
            "\"two\n# not a comment\n\nlines\""
        } else {
            "ok"
        };
        text.push_str(&format!("{k}.0,1,0.5,35,{note}\n"));
    }
    assert!(
        parse_csv(
            "q.csv",
            text.as_bytes(),
            &model("step 1.0"),
            &LoadOptions::default()
        )
        .is_ok()
    );
    text.push_str("12.0,1,0.5,bad,ok\n");
    // 1 header, rows 0..2 on 2..4, row 3 on 5..8, rows 4..11 on 9..16.
    assert_eq!(error_of(&text).location, "b.csv:17:4 (delta)");
}

#[test]
fn crlf_line_ends_read_like_lf() {
    let ir = model("step 1.0");
    let text = format!("time,u,r,delta\n{}", rows(0, 12)).replace('\n', "\r\n");
    let a = parse_csv("c.csv", text.as_bytes(), &ir, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let b = parse_csv(
        "c.csv",
        text.replace("\r\n", "\n").as_bytes(),
        &ir,
        &LoadOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a, b);
    // Rows keep their lines under CRLF (csv alone puts a record after a
    // CRLF on the line before).
    let bad = text.replacen("\r\n0.0,1,", "\r\n,1,", 1);
    assert_eq!(error_of(&bad).location, "b.csv:2:1 (time)");
    let bad = text.replace("5.0,1,0.5,35", "5.0,1,0.5,x");
    assert_eq!(error_of(&bad).location, "b.csv:7:4 (delta)");
}

#[test]
fn a_gross_outlier_is_located_by_row_and_a_zigzag_is_not_one() {
    // A zigzag: rudder ±35, switching every 7 samples; u varies a little.
    let zigzag = |spike: Option<(usize, f64)>| {
        let mut text = String::from("time,u,r,delta\n");
        for k in 0..200 {
            let delta = if (k / 7) % 2 == 0 { 35.0 } else { -35.0 };
            let mut u = 5.0 + 0.01 * (k % 13) as f64;
            if let Some((at, v)) = spike
                && at == k
            {
                u = v;
            }
            text.push_str(&format!("{k}.0,{u:e},{},{delta}\n", 0.01 * (k % 5) as f64));
        }
        text
    };
    let ir = model("step 1.0");
    assert!(
        parse_csv(
            "z.csv",
            zigzag(None).as_bytes(),
            &ir,
            &LoadOptions::default()
        )
        .is_ok()
    );
    for v in [1e6, -1e9, 1e300] {
        let err = parse_csv(
            "z.csv",
            zigzag(Some((57, v))).as_bytes(),
            &ir,
            &LoadOptions::default(),
        )
        .err()
        .unwrap_or_else(|| panic!("u = {v} is an outlier"));
        assert_eq!(err.location, "z.csv:59:2 (u)", "{err}");
        assert!(err.message.contains("gross outlier"), "{err}");
    }
    // Scale-free: the same data in other units give the same verdicts.
    let scaled = |text: &str, f: f64| -> String {
        text.lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    return format!("{l}\n");
                }
                let c: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(0.0)).collect();
                format!("{},{:e},{:e},{}\n", c[0], c[1] * f, c[2] * f, c[3])
            })
            .collect()
    };
    for f in [1e-8, 1e-4, 1e4, 1e8] {
        assert!(
            parse_csv(
                "z.csv",
                scaled(&zigzag(None), f).as_bytes(),
                &ir,
                &LoadOptions::default()
            )
            .is_ok()
        );
        let err = parse_csv(
            "z.csv",
            scaled(&zigzag(Some((57, 1e6))), f).as_bytes(),
            &ir,
            &LoadOptions::default(),
        )
        .err()
        .unwrap_or_else(|| panic!("the outlier at × {f}"));
        assert_eq!(err.location, "z.csv:59:2 (u)");
    }
}

#[test]
fn a_stuck_sensor_with_a_spike_is_an_outlier() {
    // Regression (the gap of the spread rule): a column constant apart from
    // a few samples has no spread; a spike far from the constant, or far
    // from 0 for a column of zeros, is still named by its row.
    let log = |u: &dyn Fn(usize) -> f64, delta: &dyn Fn(usize) -> f64| {
        let mut text = String::from("# a log\ntime,u,r,delta\n");
        for k in 0..200 {
            text.push_str(&format!(
                "{k}.0,{:e},{},{:e}\n",
                u(k),
                0.01 * (k % 5) as f64,
                delta(k)
            ));
        }
        text
    };
    let ir = model("step 1.0");
    let check = |text: String| parse_csv("s.csv", text.as_bytes(), &ir, &LoadOptions::default());
    let varying = |k: usize| 35.0 * ((k / 7) % 2) as f64;
    for (c, spike) in [
        (5.0, 1e300),
        (5.0, -1e6),
        (5e-8, 5e-3),
        (0.0, 1e300),
        (0.0, -2e6),
    ] {
        let err = check(log(&|k| if k == 57 { spike } else { c }, &varying))
            .err()
            .unwrap_or_else(|| panic!("{c} with {spike} at row 57"));
        assert_eq!(err.location, "s.csv:60:2 (u)", "{err}");
        assert!(err.message.contains("is a gross outlier"), "{err}");
        assert!(err.message.contains("the column is constant"), "{err}");
    }
    // Within the bound: a stuck sensor with small deviations, a pulse.
    for (c, spike) in [(5.0, 20.0), (5.0, -4e4), (0.0, 35.0), (0.0, 9e5)] {
        assert!(
            check(log(
                &|k| if (57..60).contains(&k) { spike } else { c },
                &varying
            ))
            .is_ok(),
            "{c} with {spike}"
        );
    }
    // Inputs are in the user's units: a thruster kick of 16 samples on a
    // zero column is data; only beyond 1e12 is a zero column's sample a glitch.
    let kick = |k: usize| if (100..116).contains(&k) { 2e6 } else { 0.0 };
    assert!(check(log(&|k| 5.0 + 0.01 * (k % 3) as f64, &kick)).is_ok());
    let glitch = |k: usize| if k == 120 { 1e13 } else { 0.0 };
    let err = check(log(&|k| 5.0 + 0.01 * (k % 3) as f64, &glitch))
        .err()
        .unwrap_or_else(|| panic!("1e13 on a zero input"));
    assert_eq!(err.location, "s.csv:123:4 (delta)", "{err}");
    assert!(err.message.contains("exceeds 1e12 in magnitude"), "{err}");
}

#[test]
fn streaming_visits_give_the_values_of_loading_bit_for_bit() {
    let ir = model("step 1.0");
    let mut text = String::from("# head\ntime,u,r,delta,experiment\n");
    for k in 0..40 {
        let e = if k < 25 { "a" } else { "b" };
        text.push_str(&format!(
            "{k}.0,{},{},{},{e}\n",
            1.0 / (k + 1) as f64,
            0.1 * k as f64,
            (k as f64).sin()
        ));
        if k % 9 == 0 {
            text.push_str("\n# pause\n");
        }
    }
    let path = std::env::temp_dir().join(format!("leeway-stream-{}.csv", std::process::id()));
    std::fs::write(&path, &text).unwrap_or_else(|e| panic!("{e}"));
    let held = load_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let streamed = open_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(held.len(), 2);
    assert_eq!(streamed.sources.len(), 2);
    for (h, s) in held.iter().zip(&streamed.sources) {
        assert_eq!((h.name(), h.len(), h.step()), (s.name(), s.len(), s.step()));
        let mut a: Vec<u64> = Vec::new();
        let mut b: Vec<u64> = Vec::new();
        h.visit(&mut |r| a.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
        // Twice: every visit reads the spill again.
        for _ in 0..2 {
            b.clear();
            s.visit(&mut |r| b.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
            assert_eq!(a, b);
        }
        // A head (the refinement on a subsample): its first rows only,
        // streamed or held.
        let width = a.len() / h.len();
        for n in [0, 1, 7, h.len(), h.len() + 3] {
            let first = &a[..width * n.min(h.len())];
            for source in [h as &dyn Source, s as &dyn Source] {
                b.clear();
                source.visit_head(n, &mut |r| {
                    b.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits()));
                });
                assert_eq!(first, &b[..], "head of {n}");
            }
        }
        assert!(s.failure().is_none());
    }
    // Sample 3 of `b` (row k = 28) sits on line 36: 2 before the header,
    // 28 rows, and 2 dropped lines after rows 0, 9, 18 and 27.
    assert_eq!(
        streamed.sources[1].locate(3),
        format!("{}:{}", path.display(), 2 + 29 + 2 * 4)
    );
    let _ = std::fs::remove_file(&path);
}

#[test]
fn resampling_far_finer_than_the_log_is_refused_before_it_allocates() {
    let ir = model("");
    let text = format!("time,u,r,delta\n{}", rows(0, 12));
    let options = LoadOptions {
        resample: Some(1e-3),
        ..LoadOptions::default()
    };
    let err = parse_csv("r.csv", text.as_bytes(), &ir, &options)
        .err()
        .unwrap_or_else(|| panic!("11001 samples from 12 rows is refused"));
    assert_eq!(err.location, "r.csv:2");
    assert!(err.message.contains("at most 100 per row"), "{err}");
}

#[test]
fn later_passes_read_the_validated_samples_and_the_spill_is_removed() {
    // Passes read the binary copy the validating pass wrote: a file
    // rewritten after validation changes nothing (it used to stop the
    // visit with "the file changed while it was being read").
    let ir = model("step 1.0");
    let path = std::env::temp_dir().join(format!("leeway-changed-{}.csv", std::process::id()));
    let text = format!("time,u,r,delta\n{}", rows(0, 20));
    std::fs::write(&path, &text).unwrap_or_else(|e| panic!("{e}"));
    let held = load_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let streamed = open_csv(&path, &ir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(&path, format!("time,u,r,delta\n{}", rows(0, 5)))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut a: Vec<u64> = Vec::new();
    let mut b: Vec<u64> = Vec::new();
    held[0].visit(&mut |r| a.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
    streamed.sources[0]
        .visit(&mut |r| b.extend(r.states.iter().chain(r.inputs).map(|v| v.to_bits())));
    assert_eq!(a.len(), 20 * 3);
    assert_eq!(a, b);
    assert!(streamed.sources[0].failure().is_none());
    assert_eq!(
        streamed.sources[0].locate(19),
        format!("{}:21", path.display())
    );
    assert_eq!(
        streamed.sources[0].locate(20),
        format!(
            "{}: experiment `{}`, sample 21",
            path.display(),
            streamed.sources[0].name()
        )
    );
    // The spill file is removed with the sources.
    let spill = streamed.sources[0].spill_path();
    assert!(spill.exists());
    drop(streamed);
    assert!(!spill.exists(), "{}", spill.display());
    let _ = std::fs::remove_file(&path);
}

/// The columns of CSV text (all but `experiment` parsed as numbers; the
/// parse of a cell is the CSV loader's own, so values agree bit for bit).
type Frame = (Vec<(String, Vec<f64>)>, Option<Vec<String>>);

fn columns_of(text: &str) -> Frame {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let mut cols: Vec<(String, Vec<f64>)> = Vec::new();
    let mut labels: Option<Vec<String>> = None;
    for h in &header {
        if *h == "experiment" {
            labels = Some(Vec::new());
        } else {
            cols.push((h.to_string(), Vec::new()));
        }
    }
    for line in lines {
        let mut c = cols.iter_mut();
        for (h, cell) in header.iter().zip(line.split(',')) {
            if *h == "experiment" {
                if let Some(l) = labels.as_mut() {
                    l.push(cell.to_string());
                }
            } else if let Some((_, v)) = c.next() {
                v.push(cell.parse().unwrap_or(f64::NAN));
            }
        }
    }
    (cols, labels)
}

fn load_columns_of(text: &str, ir: &Ir, options: &LoadOptions) -> Result<LoadedFile, DataError> {
    let (cols, labels) = columns_of(text);
    let borrowed: Vec<(&str, &[f64])> = cols.iter().map(|(n, v)| (n.as_str(), &v[..])).collect();
    load_columns(
        "run",
        &borrowed,
        labels.as_deref().map(Labels::PerRow),
        ir,
        options,
    )
}

fn bits(e: &Experiment) -> Vec<u64> {
    source_bits(e)
}

/// Every value a visit gives, as bits, after the step.
fn source_bits(e: &dyn Source) -> Vec<u64> {
    let mut out = vec![e.step().to_bits()];
    e.visit(&mut |r| {
        out.extend(
            r.states
                .iter()
                .chain(r.inputs)
                .chain(r.rotation)
                .chain(r.disturbances)
                .chain([&r.heading])
                .map(|v| v.to_bits()),
        );
    });
    out
}

/// A log with units, two experiments, values whose bits matter (-0.0,
/// thirds, subnormal-ish small numbers) and jittered time stamps.
fn log_text() -> String {
    let mut text = String::from("time,u,r,rudder,experiment,note\n");
    for k in 0..60 {
        let e = if k < 25 { "east" } else { "west" };
        let jitter = if k % 3 == 0 { 1.0 } else { 0.0 };
        let u = if k == 4 { -0.0 } else { 1.0 / (k + 3) as f64 };
        text.push_str(&format!(
            "{:?},{u:?},{:?},{:?},{e},x\n",
            500.0 * k as f64 + jitter,
            (k as f64 * 0.7).sin() * 1e-300,
            (k % 7) as f64 / 3.0
        ));
    }
    text
}

#[test]
fn columns_load_bit_for_bit_as_the_csv_of_the_same_values() {
    let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
    let text = log_text();
    for options in [
        LoadOptions::default(),
        LoadOptions {
            resample: Some(0.5),
            ..LoadOptions::default()
        },
    ] {
        let csv = parse_csv_noted("run", text.as_bytes(), &ir, &options)
            .unwrap_or_else(|e| panic!("{e}"));
        let cols = load_columns_of(&text, &ir, &options).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(csv.experiments.len(), 2);
        assert_eq!(csv.notes, cols.notes);
        for (a, b) in csv.experiments.iter().zip(&cols.experiments) {
            assert_eq!((&a.name, a.len()), (&b.name, b.len()));
            assert_eq!(bits(a), bits(b), "{}", a.name);
        }
        assert!(csv.notes.experiments[0].max_step_deviation > Some(0.0));
    }
    // Without labels the frame is one experiment named after it.
    let one = format!("time,u,r,rudder\n{}", rows(0, 12)).replace(",35\n", ",35\n");
    let csv = parse_csv_noted(
        "run",
        one.as_bytes(),
        &model("step 1.0 data { delta = \"rudder\" }"),
        &LoadOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let cols = load_columns_of(
        &one,
        &model("step 1.0 data { delta = \"rudder\" }"),
        &LoadOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(csv.experiments, cols.experiments);
    assert_eq!(cols.experiments[0].name, "run");
}

#[test]
fn columns_fail_as_csv_does_located_by_positional_row() {
    // Each broken log fails with the CSV loader's message and hint; the
    // place is the same row, counted from 0 below the header (line 1).
    let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
    let good = log_text();
    let edit = |row: usize, f: &dyn Fn(&str) -> String| -> String {
        good.lines()
            .enumerate()
            .map(|(i, l)| if i == row + 1 { f(l) } else { l.to_string() } + "\n")
            .collect()
    };
    let cell = |row: usize, col: usize, v: &str| {
        edit(row, &|l: &str| {
            let mut c: Vec<&str> = l.split(',').collect();
            c[col] = v;
            c.join(",")
        })
    };
    let cases = [
        (cell(17, 1, "NaN"), "run: row 17, column `u`"),
        (cell(18, 2, "-inf"), "run: row 18, column `r`"),
        (cell(30, 0, "1000"), "run: row 30, column `time`"),
        (cell(40, 3, "1e30"), "run: row 40, column `rudder`"),
        (cell(50, 4, "east"), "run: row 50, column `experiment`"),
        (cell(20, 0, "30000"), "run: row 21, column `time`"),
        (good.replace("rudder", "delta"), "run: header"),
        (
            good.lines().take(5).map(|l| format!("{l}\n")).collect(),
            "run: row 0",
        ),
    ];
    for (text, place) in cases {
        let csv = parse_csv("run", text.as_bytes(), &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("an error expected at {place}"));
        let cols = load_columns_of(&text, &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("an error expected at {place}"));
        assert_eq!(cols.location, place, "{cols}");
        assert_eq!(cols.message, csv.message, "{place}");
        // The header's list differs only in order (labels come last).
        if place != "run: header" {
            assert_eq!(cols.hint, csv.hint, "{place}");
        }
    }
    // Columns of unequal length and a name given twice.
    let a = [1.0, 2.0];
    let b = [1.0];
    let err = load_columns(
        "f",
        &[("u", &a), ("r", &b)],
        None,
        &ir,
        &LoadOptions::default(),
    )
    .err()
    .unwrap_or_else(|| panic!("unequal lengths"));
    assert_eq!(
        (err.location.as_str(), err.message.as_str()),
        ("f", "column `r` has 1 rows, the others 2")
    );
    let err = load_columns(
        "f",
        &[("u", &a), ("u", &a)],
        None,
        &ir,
        &LoadOptions::default(),
    )
    .err()
    .unwrap_or_else(|| panic!("a repeated name"));
    assert_eq!(err.location, "f: header, column `u`");
}

#[test]
fn streamed_columns_visit_bit_for_bit_as_loaded_ones() {
    // Regression: frames from Python are streamed through the spill like a
    // file, so an estimate holds no copy of a large frame: the samples each
    // visit gives are the loaded ones, bit for bit, with the same notes.
    let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
    let (cols, labels) = columns_of(&log_text());
    let borrowed: Vec<(&str, &[f64])> = cols.iter().map(|(n, v)| (n.as_str(), &v[..])).collect();
    let options = LoadOptions::default();
    let labels = labels.unwrap_or_default();
    // Labels handed over coded, as pandas.factorize gives them.
    let names: Vec<String> = vec!["east".into(), "west".into()];
    let codes: Vec<i64> = labels.iter().map(|l| i64::from(l == "west")).collect();
    let coded = Labels::Coded {
        codes: &codes,
        names: &names,
    };
    let held = load_columns(
        "run",
        &borrowed,
        Some(Labels::PerRow(&labels)),
        &ir,
        &options,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let streamed = crate::columns::open_columns("run", &borrowed, Some(coded), &ir, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(held.notes, streamed.notes);
    assert_eq!(held.experiments.len(), streamed.sources.len());
    for (e, s) in held.experiments.iter().zip(&streamed.sources) {
        let held_source: &dyn Source = e;
        assert_eq!((s.name(), s.len()), (held_source.name(), held_source.len()));
        assert_eq!(source_bits(s), bits(e), "{}", e.name);
        // Rows in a frame are positions one after another: the spill does
        // not store them, and each experiment's are counted from its first.
        assert_eq!(s.locate(3), format!("run: row {}", s.block().first + 3));
    }
}

#[test]
fn a_code_without_a_label_is_a_located_error() {
    let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
    let (cols, _) = columns_of(&log_text());
    let borrowed: Vec<(&str, &[f64])> = cols.iter().map(|(n, v)| (n.as_str(), &v[..])).collect();
    let names = vec!["east".to_string()];
    let mut codes = vec![0i64; cols[0].1.len()];
    codes[7] = -1; // pandas.factorize's code of a missing label
    let coded = Labels::Coded {
        codes: &codes,
        names: &names,
    };
    let e = load_columns("run", &borrowed, Some(coded), &ir, &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("a code without a label accepted"));
    assert!(e.location.starts_with("run: row 7"), "{e}");
    assert!(e.message.contains("missing experiment label"), "{e}");
}

#[test]
fn reading_a_frame_stops_when_its_interrupt_says_so() {
    // Regression: Ctrl-C while a large frame is validated.
    let ir = model("data { delta = \"rudder\" in deg, r in deg/s, time in ms }");
    let (cols, labels) = columns_of(&log_text());
    let borrowed: Vec<(&str, &[f64])> = cols.iter().map(|(n, v)| (n.as_str(), &v[..])).collect();
    let labels = labels.as_deref().map(Labels::PerRow);
    let stop = leeway_model::interrupt::Interrupt::new(|| true);
    let mut table = super::columns::frame("run", &borrowed, labels, &ir)
        .unwrap_or_else(|e| panic!("{e}"))
        .interruptible(Some(stop));
    let e = load_table(&mut table, &ir, &LoadOptions::default())
        .err()
        .unwrap_or_else(|| panic!("read to the end"));
    assert_eq!(e.message, super::columns::INTERRUPTED);
    // Never asked to stop: read as without an interrupt.
    let mut table = super::columns::frame("run", &borrowed, labels, &ir)
        .unwrap_or_else(|e| panic!("{e}"))
        .interruptible(Some(leeway_model::interrupt::Interrupt::new(|| false)));
    assert!(load_table(&mut table, &ir, &LoadOptions::default()).is_ok());
}

#[test]
fn a_header_of_a_hundred_thousand_names_is_checked_at_once() {
    // Each name against every one before it was 5·10⁹ comparisons.
    let mut header: String = (0..100_000).map(|k| format!("c{k},")).collect();
    header.push_str("c17\n1\n");
    let started = std::time::Instant::now();
    let e = Records::new("wide.csv", header.as_bytes(), "--data")
        .err()
        .unwrap_or_else(|| panic!("c17 is given twice"));
    assert_eq!(e.location, "wide.csv:1:100001");
    assert!(e.message.contains("(columns 18 and 100001)"), "{e:?}");
    assert!(started.elapsed().as_secs() < 2, "{:?}", started.elapsed());
}
