//! Parquet data files end to end: `leeway estimate --data run.parquet`
//! gives the estimate of the same values as CSV bit for bit (whatever the
//! column types, row groups and compression), and every problem is one
//! located error (file, row, row group, column), exit code 2, no panic.
//! Files are written here with the `parquet` crate's own writer.

use parquet::basic::{Compression, ZstdLevel};
use parquet::data_type::{
    ByteArray, ByteArrayType, DataType, DoubleType, FloatType, Int32Type, Int64Type,
};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::{SerializedColumnWriter, SerializedFileWriter};
use parquet::schema::parser::parse_message_type;
use std::sync::Arc;

use crate::common::*;

/// One column to write: values with `None` for a null.
#[derive(Clone, Debug)]
enum Data {
    Double(Vec<Option<f64>>),
    Float(Vec<Option<f32>>),
    Int32(Vec<Option<i32>>),
    Int64(Vec<Option<i64>>),
    /// INT64 TIMESTAMP(NANOS): what pandas writes for `datetime64[ns]`.
    Stamps(Vec<Option<i64>>),
    /// INT64 with a logical type written after the name (`(INTEGER(64,false))`).
    Int64As(&'static str, Vec<Option<i64>>),
    Text(Vec<Option<String>>),
}

impl Data {
    fn schema(&self, name: &str) -> String {
        let t = match self {
            Data::Double(_) => "double",
            Data::Float(_) => "float",
            Data::Int32(_) => "int32",
            Data::Int64(_) | Data::Stamps(_) | Data::Int64As(..) => "int64",
            Data::Text(_) => "binary",
        };
        let logical = match self {
            Data::Text(_) => " (UTF8)",
            Data::Stamps(_) => " (TIMESTAMP(NANOS,true))",
            Data::Int64As(logical, _) => logical,
            _ => "",
        };
        format!("optional {t} {name}{logical};")
    }
    fn len(&self) -> usize {
        match self {
            Data::Double(v) => v.len(),
            Data::Float(v) => v.len(),
            Data::Int32(v) => v.len(),
            Data::Int64(v) | Data::Stamps(v) | Data::Int64As(_, v) => v.len(),
            Data::Text(v) => v.len(),
        }
    }
}

/// Values present and definition levels (1 present, 0 null) of `v`.
fn split<T: Clone>(v: &[Option<T>]) -> (Vec<T>, Vec<i16>) {
    let values = v.iter().flatten().cloned().collect();
    let defs = v.iter().map(|x| i16::from(x.is_some())).collect();
    (values, defs)
}

/// Writes one column chunk (nulls as definition level 0).
fn put<T: DataType>(
    col: &mut SerializedColumnWriter<'_>,
    v: &[Option<T::T>],
) -> parquet::errors::Result<usize> {
    let (values, defs) = split(v);
    col.typed::<T>().write_batch(&values, Some(&defs), None)
}

/// Writes `columns` as a Parquet file, `group` rows per row group.
fn write_parquet(
    path: &std::path::Path,
    columns: &[(&str, Data)],
    group: usize,
    codec: Compression,
) {
    let fields: Vec<String> = columns.iter().map(|(n, d)| d.schema(n)).collect();
    let schema = Arc::new(
        parse_message_type(&format!("message log {{ {} }}", fields.join(" ")))
            .unwrap_or_else(|e| panic!("{e}")),
    );
    let props = Arc::new(WriterProperties::builder().set_compression(codec).build());
    let file = std::fs::File::create(path).unwrap_or_else(|e| panic!("{e}"));
    let mut writer =
        SerializedFileWriter::new(file, schema, props).unwrap_or_else(|e| panic!("{e}"));
    let rows = columns.first().map_or(0, |(_, d)| d.len());
    let mut start = 0;
    while start < rows {
        let end = (start + group).min(rows);
        let mut rg = writer.next_row_group().unwrap_or_else(|e| panic!("{e}"));
        for (_, data) in columns {
            let mut col = rg
                .next_column()
                .unwrap_or_else(|e| panic!("{e}"))
                .unwrap_or_else(|| panic!("a column"));
            let rows = start..end;
            let written = match data {
                Data::Double(v) => put::<DoubleType>(&mut col, &v[rows]),
                Data::Float(v) => put::<FloatType>(&mut col, &v[rows]),
                Data::Int32(v) => put::<Int32Type>(&mut col, &v[rows]),
                Data::Int64(v) | Data::Stamps(v) | Data::Int64As(_, v) => {
                    put::<Int64Type>(&mut col, &v[rows])
                }
                Data::Text(v) => {
                    let bytes: Vec<Option<ByteArray>> = v[rows]
                        .iter()
                        .map(|s| s.as_deref().map(ByteArray::from))
                        .collect();
                    put::<ByteArrayType>(&mut col, &bytes)
                }
            };
            written.unwrap_or_else(|e| panic!("{e}"));
            col.close().unwrap_or_else(|e| panic!("{e}"));
        }
        rg.close().unwrap_or_else(|e| panic!("{e}"));
        start = end;
    }
    writer.close().unwrap_or_else(|e| panic!("{e}"));
}

/// The columns of CSV text (every cell a number), as doubles.
fn columns_of(text: &str) -> Vec<(String, Vec<f64>)> {
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect();
    let mut cols: Vec<(String, Vec<f64>)> = header.into_iter().map(|h| (h, Vec::new())).collect();
    for line in lines {
        for (cell, (_, c)) in line.split(',').zip(cols.iter_mut()) {
            c.push(cell.parse().unwrap_or_else(|e| panic!("{cell}: {e}")));
        }
    }
    cols
}

fn doubles(v: &[f64]) -> Data {
    Data::Double(v.iter().copied().map(Some).collect())
}

#[test]
fn a_parquet_file_gives_the_estimate_of_the_same_values_as_csv_bit_for_bit() {
    let dir = Scratch::new("parquet-same");
    let text = estimation_csv(3000, 1.0, 7);
    let csv = dir.write("log.csv", &text);
    let cols = columns_of(&text);
    let time = cols
        .iter()
        .position(|(n, _)| n == "time")
        .unwrap_or_else(|| panic!("a time column"));
    // Doubles in several row groups; time as INT32, or as nanosecond
    // timestamps (read as seconds since the first), and the rest as doubles;
    // two codecs. Each must give the CSV's document, bit for bit.
    let expected = {
        let o = leeway(&["estimate", SHIP, "--data", &csv, "--json"]);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        stdout(&o)
    };
    for (variant, codec, group) in [
        ("snappy", Compression::SNAPPY, 700),
        ("zstd", Compression::ZSTD(ZstdLevel::default()), 3000),
        ("plain", Compression::UNCOMPRESSED, 1024),
        ("stamps", Compression::SNAPPY, 1000),
    ] {
        let sub = Scratch::new(&format!("parquet-same-{variant}"));
        let path = sub.path("log.parquet");
        let columns: Vec<(&str, Data)> = cols
            .iter()
            .enumerate()
            .map(|(i, (n, v))| {
                let data = if i == time && variant == "zstd" {
                    // Integral stamps stored as INT32 read as the same doubles.
                    Data::Int32(v.iter().map(|t| Some(*t as i32)).collect())
                } else if i == time && variant == "stamps" {
                    // 2026-11-23 plus the CSV's seconds, in nanoseconds.
                    let origin = 1_795_392_000_000_000_000i64;
                    assert_eq!(v.first(), Some(&0.0), "the CSV's time starts at 0");
                    Data::Stamps(
                        v.iter()
                            .map(|t| Some(origin + (t * 1e9).round() as i64))
                            .collect(),
                    )
                } else {
                    doubles(v)
                };
                (n.as_str(), data)
            })
            .collect();
        write_parquet(&path, &columns, group, codec);
        let data = path.display().to_string();
        let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
        assert_eq!(code(&o), 0, "{variant}: {}", stderr(&o));
        no_panic(&o);
        // The file's name is the only difference.
        assert_eq!(
            stdout(&o).replace(&data, &csv),
            expected,
            "{variant}: the Parquet estimate differs from the CSV one"
        );
        // validate reads it too.
        let params = sub.write("theta.json", &true_params());
        let v = leeway(&["validate", SHIP, "--data", &data, "--params", &params]);
        assert_eq!(code(&v), 0, "{variant}: {}", stderr(&v));
    }
}

#[test]
fn experiments_split_on_a_text_column_as_in_csv() {
    let dir = Scratch::new("parquet-experiments");
    let a = estimation_csv(1500, 1.0, 3);
    let b = estimation_csv(1500, -1.0, 4);
    let (ca, cb) = (columns_of(&a), columns_of(&b));
    let mut text = String::from("experiment,");
    text.push_str(a.lines().next().unwrap_or_default());
    text.push('\n');
    for (name, t) in [("east", &a), ("west", &b)] {
        for line in t.lines().skip(1) {
            text.push_str(&format!("{name},{line}\n"));
        }
    }
    let csv = dir.write("two.csv", &text);
    let labels: Vec<Option<String>> = std::iter::repeat_n(Some("east".to_string()), 1500)
        .chain(std::iter::repeat_n(Some("west".to_string()), 1500))
        .collect();
    let mut columns: Vec<(&str, Data)> = vec![("experiment", Data::Text(labels))];
    for ((n, x), (_, y)) in ca.iter().zip(&cb) {
        let v: Vec<f64> = x.iter().chain(y).copied().collect();
        columns.push((n.as_str(), doubles(&v)));
    }
    let path = dir.path("two.parquet");
    write_parquet(&path, &columns, 1000, Compression::SNAPPY);
    let data = path.display().to_string();
    let p = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
    let c = leeway(&["estimate", SHIP, "--data", &csv, "--json"]);
    assert_eq!(code(&p), 0, "{}", stderr(&p));
    assert_eq!(code(&c), 0, "{}", stderr(&c));
    let doc = json(&p);
    let names: Vec<&str> = doc["experiments"]
        .as_array()
        .map(|a| a.iter().filter_map(|e| e["name"].as_str()).collect())
        .unwrap_or_default();
    assert_eq!(names, ["east", "west"], "{doc}");
    assert_eq!(stdout(&p).replace(&data, &csv), stdout(&c));
}

/// A small valid log of the ship (`rows` rows) as doubles.
fn small_log(rows: usize) -> Vec<(String, Vec<f64>)> {
    columns_of(&estimation_csv(rows, 1.0, 11))
}

/// Runs `estimate` on `columns` written as Parquet (row groups of 100 rows)
/// and returns the one-line error, after checking exit code 2 and no panic.
fn error_of(name: &str, columns: &[(&str, Data)]) -> (String, String) {
    let dir = Scratch::new(&format!("parquet-error-{name}"));
    let path = dir.path(&format!("{name}.parquet"));
    write_parquet(&path, columns, 100, Compression::SNAPPY);
    let data = path.display().to_string();
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{name}: {}{}", stdout(&o), stderr(&o));
    (stderr(&o), data)
}

/// The log's columns with column `name` replaced by `data`.
fn with(cols: &[(String, Vec<f64>)], name: &str, data: Data) -> Vec<(String, Data)> {
    cols.iter()
        .map(|(n, v)| {
            let d = if n == name { data.clone() } else { doubles(v) };
            (n.clone(), d)
        })
        .collect()
}

fn borrowed(cols: &[(String, Data)]) -> Vec<(&str, Data)> {
    cols.iter().map(|(n, d)| (n.as_str(), d.clone())).collect()
}

#[test]
fn every_problem_is_located_by_file_row_group_row_and_column() {
    let cols = small_log(400);
    let col = |name: &str| {
        cols.iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("column {name}"))
    };
    let opt = |v: Vec<f64>| -> Vec<Option<f64>> { v.into_iter().map(Some).collect() };
    // Row 234 of the file is row 34 of row group 2 (groups of 100 rows).
    let at = |file: &str, column: &str| {
        format!("{file}: row 234 (row group 2, row 34), column `{column}`")
    };
    let mut v = opt(col("v"));
    v[234] = None;
    let (e, f) = error_of("null", &borrowed(&with(&cols, "v", Data::Double(v))));
    assert!(e.contains(&at(&f, "v")) && e.contains("null"), "{e}");

    let mut r = opt(col("r"));
    r[234] = Some(f64::NAN);
    let (e, f) = error_of("nan", &borrowed(&with(&cols, "r", Data::Double(r))));
    assert!(
        e.contains(&at(&f, "r")) && e.contains("`NaN` is not a finite number"),
        "{e}"
    );

    let mut u = opt(col("u"));
    u[234] = Some(f64::INFINITY);
    let (e, f) = error_of("inf", &borrowed(&with(&cols, "u", Data::Double(u))));
    assert!(
        e.contains(&at(&f, "u")) && e.contains("`inf` is not a finite number"),
        "{e}"
    );

    let mut t = opt(col("time"));
    t[234] = t[233];
    let (e, f) = error_of("time", &borrowed(&with(&cols, "time", Data::Double(t))));
    assert!(
        e.contains(&at(&f, "time")) && e.contains("time does not increase"),
        "{e}"
    );

    let mut big: Vec<Option<i64>> = col("time").iter().map(|t| Some(*t as i64)).collect();
    big[234] = Some((1 << 53) + 1);
    let (e, f) = error_of("int64", &borrowed(&with(&cols, "time", Data::Int64(big))));
    assert!(
        e.contains(&at(&f, "time")) && e.contains("9007199254740993"),
        "{e}"
    );
    assert!(e.contains("2⁵³"), "{e}");

    let text: Vec<Option<String>> = col("tau1").iter().map(|x| Some(format!("{x}"))).collect();
    let (e, f) = error_of("text", &borrowed(&with(&cols, "tau1", Data::Text(text))));
    assert!(
        e.contains(&format!("{f}: row 0 (row group 0, row 0), column `tau1`"))
            && e.contains("is not a number")
            && e.contains("BYTE_ARRAY"),
        "{e}"
    );

    let missing: Vec<(String, Data)> = with(&cols, "psi", doubles(&[]))
        .into_iter()
        .filter(|(n, _)| n != "psi")
        .collect();
    let (e, f) = error_of("missing", &borrowed(&missing));
    assert!(
        e.contains(&format!("{f}: schema")) && e.contains("missing column `psi`"),
        "{e}"
    );

    // Floats are read as doubles: a float32 outlier is still located.
    let mut w: Vec<Option<f32>> = col("wind_n").iter().map(|x| Some(*x as f32)).collect();
    w[234] = Some(1e30);
    let (e, f) = error_of("float", &borrowed(&with(&cols, "wind_n", Data::Float(w))));
    assert!(
        e.contains(&at(&f, "wind_n")) && e.contains("gross outlier"),
        "{e}"
    );
}

#[test]
fn a_damaged_or_empty_file_is_one_clear_error() {
    let dir = Scratch::new("parquet-damaged");
    let cols = small_log(300);
    let columns: Vec<(&str, Data)> = cols.iter().map(|(n, v)| (n.as_str(), doubles(v))).collect();
    let good = dir.path("good.parquet");
    write_parquet(&good, &columns, 100, Compression::SNAPPY);
    let bytes = std::fs::read(&good).unwrap_or_else(|e| panic!("{e}"));
    let cut = dir.path("cut.parquet");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap_or_else(|e| panic!("{e}"));
    let empty = dir.path("empty.parquet");
    std::fs::write(&empty, b"").unwrap_or_else(|e| panic!("{e}"));
    // The first page header of column `r` in row group 1 overwritten: the
    // footer is intact, the page cannot be decoded.
    let start = {
        use parquet::file::reader::{FileReader, SerializedFileReader};
        let reader =
            SerializedFileReader::new(std::fs::File::open(&good).unwrap_or_else(|e| panic!("{e}")))
                .unwrap_or_else(|e| panic!("{e}"));
        let r = cols
            .iter()
            .position(|(n, _)| n == "r")
            .unwrap_or_else(|| panic!("r"));
        reader.metadata().row_group(1).column(r).byte_range().0 as usize
    };
    let mut garbled = bytes.clone();
    for b in &mut garbled[start..start + 16] {
        *b = 0xFF;
    }
    let garbled_path = dir.path("garbled.parquet");
    std::fs::write(&garbled_path, &garbled).unwrap_or_else(|e| panic!("{e}"));
    // Renamed: the magic bytes, not the extension, say Parquet.
    let renamed = dir.path("log.dat");
    std::fs::write(&renamed, &bytes[..bytes.len() / 2]).unwrap_or_else(|e| panic!("{e}"));
    for (path, expect) in [
        (&cut, "not a Parquet file"),
        (&empty, "not a Parquet file: it is empty"),
        (
            &garbled_path,
            ": row 100 (row group 1, row 0), column `r`: cannot decode",
        ),
        (&renamed, "not a Parquet file"),
    ] {
        let data = path.display().to_string();
        let o = leeway(&["estimate", SHIP, "--data", &data]);
        no_panic(&o);
        assert_eq!(code(&o), 2, "{data}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(&data) && e.contains(expect), "{e}");
        assert_eq!(e.matches("error[").count(), 1, "one error for {data}: {e}");
        assert!(!e.contains("Parquet error"), "{e}");
    }
    // A valid file without rows.
    let none: Vec<(&str, Data)> = cols
        .iter()
        .map(|(n, _)| (n.as_str(), doubles(&[])))
        .collect();
    let zero = dir.path("zero.parquet");
    write_parquet(&zero, &none, 100, Compression::SNAPPY);
    let data = zero.display().to_string();
    let o = leeway(&["estimate", SHIP, "--data", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("{data}: row 0")) && stderr(&o).contains("no samples"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn simulate_reads_a_parquet_input_as_the_csv_of_the_same_values() {
    let dir = Scratch::new("parquet-simulate");
    let text = estimation_csv(200, 1.0, 5);
    let csv = dir.write("in.csv", &text);
    let cols = columns_of(&text);
    let columns: Vec<(&str, Data)> = cols.iter().map(|(n, v)| (n.as_str(), doubles(v))).collect();
    let path = dir.path("in.parquet");
    write_parquet(&path, &columns, 64, Compression::SNAPPY);
    let data = path.display().to_string();
    let params = dir.write("theta.json", &true_params());
    let p = leeway(&["simulate", SHIP, "--params", &params, "--input", &data]);
    let c = leeway(&["simulate", SHIP, "--params", &params, "--input", &csv]);
    assert_eq!(code(&p), 0, "{}", stderr(&p));
    assert_eq!(code(&c), 0, "{}", stderr(&c));
    assert!(stdout(&p).lines().count() > 200);
    assert_eq!(stdout(&p), stdout(&c));
    // A null input is located by row group and row.
    let mut tau: Vec<Option<f64>> = cols
        .iter()
        .find(|(n, _)| n == "tau2")
        .map(|(_, v)| v.iter().copied().map(Some).collect())
        .unwrap_or_default();
    tau[70] = None;
    let broken: Vec<(&str, Data)> = cols
        .iter()
        .map(|(n, v)| {
            let d = if n == "tau2" {
                Data::Double(tau.clone())
            } else {
                doubles(v)
            };
            (n.as_str(), d)
        })
        .collect();
    write_parquet(&path, &broken, 64, Compression::SNAPPY);
    let o = leeway(&["simulate", SHIP, "--params", &params, "--input", &data]);
    no_panic(&o);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!(
            "{data}: row 70 (row group 1, row 6), column `tau2`: null"
        )),
        "{}",
        stderr(&o)
    );
}

#[test]
fn logical_types_are_read_as_what_they_mean_or_refused() {
    // Regression: unsigned integers were read signed, decimals without their
    // scale, and a date or timestamp in a signal's column as a count.
    let dir = Scratch::new("parquet-logical");
    let text = estimation_csv(1500, 1.0, 7);
    let csv = dir.write("log.csv", &text);
    let cols = columns_of(&text);
    let expected = leeway(&["estimate", SHIP, "--data", &csv, "--json"]);
    assert_eq!(code(&expected), 0, "{}", stderr(&expected));
    // The time as UINT64 seconds and as DECIMAL(18, 3) seconds: the CSV's
    // estimate, bit for bit.
    for (name, logical, scale) in [
        ("uint", " (INTEGER(64,false))", 1.0),
        ("decimal", " (DECIMAL(18,3))", 1e3),
    ] {
        let columns: Vec<(&str, Data)> = cols
            .iter()
            .map(|(n, v)| {
                let d = if n == "time" {
                    Data::Int64As(
                        logical,
                        v.iter().map(|t| Some((t * scale) as i64)).collect(),
                    )
                } else {
                    doubles(v)
                };
                (n.as_str(), d)
            })
            .collect();
        // Named as the CSV file: the experiment is named after it.
        let sub = Scratch::new(&format!("parquet-logical-{name}"));
        let path = sub.path("log.parquet");
        write_parquet(&path, &columns, 500, Compression::SNAPPY);
        let data = path.display().to_string();
        let o = leeway(&["estimate", SHIP, "--data", &data, "--json"]);
        assert_eq!(code(&o), 0, "{name}: {}", stderr(&o));
        assert_eq!(stdout(&o).replace(&data, &csv), stdout(&expected), "{name}");
    }
    // A timestamp or a date in a signal's column is refused at the schema.
    let origin = 1_795_392_000_000_000_000i64;
    for (name, data) in [
        (
            "stamp",
            Data::Stamps((0..1500).map(|k| Some(origin + k)).collect()),
        ),
        (
            "date",
            Data::Int64As(" (TIMESTAMP(MILLIS,false))", vec![Some(0); 1500]),
        ),
    ] {
        let (e, f) = error_of(name, &borrowed(&with(&cols, "u", data)));
        assert!(
            e.contains(&format!("{f}: schema, column `u`")) && e.contains("dates or times"),
            "{e}"
        );
    }
    // An unsigned value beyond 2⁵³ is refused by row, never wrapped.
    let mut big: Vec<Option<i64>> = cols[0].1.iter().map(|t| Some(*t as i64)).collect();
    big[234] = Some(-40); // 2⁶⁴ − 40 as UINT64
    let (e, f) = error_of(
        "uint-big",
        &borrowed(&with(
            &cols,
            "time",
            Data::Int64As(" (INTEGER(64,false))", big),
        )),
    );
    assert!(
        e.contains(&format!(
            "{f}: row 234 (row group 2, row 34), column `time`"
        )) && e.contains("18446744073709551576"),
        "{e}"
    );
}

#[test]
fn a_log_source_in_parquet_is_stamped_by_its_timestamp_column() {
    // The ferry log's velocity topic as Parquet, its stamps a TIMESTAMP(NANOS)
    // column: the same joined samples, the same estimate, as from the CSV.
    let dir = Scratch::new("log-parquet");
    let spec = leeway_scenarios::ferry::FerryLog {
        seconds: 300.0,
        hole: (100.0, 105.8),
        ..Default::default()
    };
    leeway_scenarios::ferry::write_ferry_log(&dir.0, &spec).unwrap_or_else(|e| panic!("{e}"));
    let text = std::fs::read_to_string(dir.path("twist.csv")).unwrap_or_else(|e| panic!("{e}"));
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let stamp = |r: &Vec<&str>| {
        r[0].parse::<i64>().unwrap_or(0) * 1_000_000_000 + r[1].parse::<i64>().unwrap_or(0)
    };
    let column = |i: usize| Data::Double(rows.iter().map(|r| r[i].parse::<f64>().ok()).collect());
    write_parquet(
        &dir.path("twist.parquet"),
        &[
            (
                "stamp",
                Data::Stamps(rows.iter().map(|r| Some(stamp(r))).collect()),
            ),
            ("u", column(2)),
            ("v", column(3)),
            ("r", column(4)),
        ],
        500,
        Compression::SNAPPY,
    );
    let manifest = std::fs::read_to_string(dir.path("ferry.toml")).unwrap_or_default();
    dir.write(
        "parquet.toml",
        &manifest.replace(
            "file = \"twist.csv\"\ntime = [\"secs\", \"nsecs\"]",
            "file = \"twist.parquet\"\ntime = \"stamp\"",
        ),
    );
    let run = |m: &str| {
        let o = leeway(&[
            "estimate",
            "examples/models/ferry.som",
            "--data",
            &dir.path(m).display().to_string(),
            "--method",
            "ls",
            "--json",
        ]);
        assert_eq!(code(&o), 0, "{}", stdout(&o));
        json(&o)["parameters"].clone()
    };
    assert_eq!(run("parquet.toml"), run("ferry.toml"));
}
