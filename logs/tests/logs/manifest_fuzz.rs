//! Mutated log manifests — keys dropped, given twice, unknown or of another
//! type, numbers at their extremes, sources swapped for other files, missing
//! ones, a folder, a pipe or a device, time columns and units, signals,
//! interpolations, frames and windows changed, deep nesting, bytes cut,
//! flipped or inserted — and damaged sources are joined into a log from
//! small CSV files, or refused with an error at the manifest's line and
//! column or the source's row and column; never a panic. A manifest whose
//! change means nothing (layout: sections, inline or dotted tables, inline
//! arrays of windows, comments, CRLF; spelling: `0.1`, `1e-1`, `+0.10`,
//! `1_0.5`, integers for reals, quoted keys, literal strings; key order; a
//! default said out loud) loads the same numbers, bit for bit. Seeded:
//! `LEEWAY_FUZZ_MANIFEST=N` runs N manifests (CI's short budget by default;
//! 10 000 for a campaign, in release).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use leeway_data::{DataError, LoadOptions, LoadedFile};
use leeway_logs::load_log;
use leeway_structure::ir::Ir;

use crate::common::Seeded;

/// 2023-11-14 22:13:20 UTC, in s.
const T0: i64 = 1_700_000_000;

/// The test model: two states, an input, a heading.
fn model() -> Ir {
    let src = "model M { step 0.1 state u, r input n heading psi integrates r
         der u = X*u + T*n der r = N*r + M*n
         nominal { X = -0.1, T = 1, N = -0.2, M = 0.5 } }";
    leeway_structure::compile(src, &leeway_structure::CompileOptions::default())
        .ir
        .unwrap_or_else(|| panic!("the test model compiles"))
}

/// The log's sources over 20 s: `motion.csv` (10 Hz, secs/nsecs, a mode
/// switching at 10 s), `heading.csv` (1 Hz, a heading and its ENU
/// quaternion), `stamped.csv` (5 Hz, stamps in ms), `iso.csv` (10 Hz,
/// ISO-8601 stamps); a folder and, where `mkfifo` is, a pipe.
fn write_sources(dir: &Path) -> Vec<(String, String)> {
    let mut motion = String::from("secs,nsecs,u,r,n,mode\n");
    for k in 0..=200i64 {
        let t = k as f64 / 10.0;
        let _ = writeln!(
            motion,
            "{},{},{},{},{},{}",
            T0 + k / 10,
            (k % 10) * 100_000_000,
            1.0 + 0.01 * t,
            0.05 * (0.4 * t).sin(),
            (t * 0.7).sin(),
            i32::from(k >= 100)
        );
    }
    let mut heading = String::from("secs,nsecs,psi,q.x,q.y,q.z,q.w\n");
    for k in 0..=20i64 {
        let psi = 0.05 * k as f64 - 0.3;
        let yaw = std::f64::consts::FRAC_PI_2 - psi;
        let (s, c) = (yaw / 2.0).sin_cos();
        let _ = writeln!(heading, "{},0,{psi},0,0,{s},{c}", T0 + k);
    }
    let mut stamped = String::from("stamp,n,tau\n");
    for k in 0..=100i64 {
        let t = k as f64 / 5.0;
        let _ = writeln!(
            stamped,
            "{},{},{}",
            T0 * 1000 + k * 200,
            (t * 0.7).sin(),
            (0.3 * t).sin()
        );
    }
    let mut iso = String::from("time,u\n");
    for k in 0..=200i64 {
        let _ = writeln!(
            iso,
            "2023-11-14T22:13:{:02}.{}Z,{}",
            20 + k / 10,
            k % 10,
            1.0 + 0.001 * k as f64
        );
    }
    let files = vec![
        ("motion.csv".to_string(), motion),
        ("heading.csv".to_string(), heading),
        ("stamped.csv".to_string(), stamped),
        ("iso.csv".to_string(), iso),
    ];
    for (name, text) in &files {
        std::fs::write(dir.join(name), text).unwrap_or_else(|e| panic!("{e}"));
    }
    std::fs::create_dir_all(dir.join("folder.csv")).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::process::Command::new("mkfifo")
        .arg(dir.join("pipe.csv"))
        .status();
    files
}

/// The manifests the mutations start from: each loads.
const BASES: &[&str] = &[
    r#"[sources.m]
file = "motion.csv"
time = ["secs", "nsecs"]
[sources.h]
file = "heading.csv"
time = ["secs", "nsecs"]
[signals]
u = "m:u"
r = "m:r"
n = "m:n"
psi = "h:psi"
"#,
    r#"experiment = "run3"
step = 0.1
max_gap = 2.5
[sources.m]
file = "motion.csv"
time = ["secs", "nsecs"]
[sources.h]
file = "heading.csv"
time = ["secs", "nsecs"]
[signals]
u = { from = "m:u", interpolate = "linear" }
r = "m:r"
n = { from = "m:n", interpolate = "hold" }
psi = { from = "h:q", as = "yaw", frame = "enu" }
[[keep]]
from = 1.5
to = 8
[[keep]]
when = "m:mode"
equals = 1
from = 12
"#,
    r#"max_gap_steps = 4
[sources.s]
file = "stamped.csv"
time = "stamp"
time_unit = "ms"
[sources.i]
file = "iso.csv"
time = "time"
[sources.m]
file = "motion.csv"
time = ["secs", "nsecs"]
[sources.h]
file = "heading.csv"
time = ["secs", "nsecs"]
[signals]
u = "i:u"
r = { from = "m:r", on_grid = "instant" }
n = "s:n"
psi = { from = "h:psi", interpolate = "linear" }
[[keep]]
when = "s:tau"
min = -0.5
max = 0.5
[[keep]]
from = "2023-11-14T22:13:36Z"
"#,
];

/// A manifest as a tree, its tables' entries in order (a key may be given
/// twice, as a mutation).
#[derive(Clone, Debug, PartialEq)]
enum V {
    Int(i64),
    Float(f64),
    Str(String),
    Bool(bool),
    Array(Vec<V>),
    Table(Vec<(String, V)>),
    /// A number in arrays this deep, written as text (no recursion here).
    Deep(usize),
    /// Written as it is: a TOML date-time.
    Raw(String),
}

impl V {
    fn of(value: &toml::Value) -> V {
        match value {
            toml::Value::Integer(i) => V::Int(*i),
            toml::Value::Float(x) => V::Float(*x),
            toml::Value::String(s) => V::Str(s.clone()),
            toml::Value::Boolean(b) => V::Bool(*b),
            toml::Value::Datetime(d) => V::Str(d.to_string()),
            toml::Value::Array(a) => V::Array(a.iter().map(V::of).collect()),
            toml::Value::Table(t) => {
                V::Table(t.iter().map(|(k, v)| (k.clone(), V::of(v))).collect())
            }
        }
    }
    /// Every node's path from the root (indices of array items and table
    /// entries).
    fn paths(&self, here: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        out.push(here.clone());
        let children: Vec<&V> = match self {
            V::Array(items) => items.iter().collect(),
            V::Table(entries) => entries.iter().map(|(_, v)| v).collect(),
            _ => Vec::new(),
        };
        for (i, v) in children.into_iter().enumerate() {
            here.push(i);
            v.paths(here, out);
            here.pop();
        }
    }
    fn at(&mut self, path: &[usize]) -> Option<&mut V> {
        let Some((&i, rest)) = path.split_first() else {
            return Some(self);
        };
        match self {
            V::Array(items) => items.get_mut(i)?.at(rest),
            V::Table(entries) => entries.get_mut(i)?.1.at(rest),
            _ => None,
        }
    }
    /// The entry `key` of a table.
    fn get(&mut self, key: &str) -> Option<&mut V> {
        match self {
            V::Table(entries) => entries.iter_mut().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }
}

/// Numbers at the edges of what a manifest may say.
fn extreme(rng: &mut Seeded) -> V {
    match rng.range(0, 20) {
        0 => V::Float(0.0),
        1 => V::Float(-0.0),
        2 => V::Float(1e-300),
        3 => V::Float(5e-324),
        4 => V::Float(1e308),
        5 => V::Float(-1e308),
        6 => V::Float(f64::NAN),
        7 => V::Float(f64::INFINITY),
        8 => V::Float(f64::NEG_INFINITY),
        9 => V::Float(-1.0),
        10 => V::Int(i64::MAX),
        11 => V::Int(i64::MIN),
        12 => V::Int(0),
        13 => V::Float(1.5),
        14 => V::Float(1.4999999999999998),
        15 => V::Float(0.1),
        16 => V::Float(9.2e9),
        17 => V::Int(20),
        18 => V::Float(1e-9),
        _ => V::Float(f64::from_bits(rng.next())),
    }
}

/// Numbers a manifest may well say: times within the log and about it,
/// steps and gaps near the grid's, bounds about the columns' values.
fn plausible(rng: &mut Seeded) -> V {
    match rng.range(0, 6) {
        0 => V::Float(rng.range(0, 300) as f64 / 10.0 - 5.0),
        1 => V::Float(rng.range(0, 31) as f64 / 10.0 - 1.5),
        2 => V::Int(rng.range(0, 25) as i64 - 2),
        3 => V::Float(*rng.pick(&[0.1, 0.05, 0.2, 0.1000001, 0.0999999, 1.5, 1.49, 2.0, 0.5])),
        4 => V::Float(rng.range(1, 1000) as f64 / 100.0),
        _ => V::Int(rng.range(0, 2) as i64),
    }
}

/// A window at random: a time range, a condition, or both.
fn window(rng: &mut Seeded) -> V {
    let mut entries = Vec::new();
    if rng.one_in(2) {
        entries.push(("from".to_string(), plausible(rng)));
    }
    if rng.one_in(2) {
        entries.push(("to".to_string(), plausible(rng)));
    }
    if rng.one_in(2) {
        let column = *rng.pick(&["m:mode", "m:u", "s:tau", "h:psi", "m:r", "i:u"]);
        entries.push(("when".to_string(), V::Str(column.into())));
        for bound in ["equals", "min", "max"] {
            if rng.one_in(3) {
                entries.push((bound.to_string(), plausible(rng)));
            }
        }
    }
    V::Table(entries)
}

/// Texts a manifest's strings may be changed to.
const TEXTS: &[&str] = &[
    "motion.csv",
    "heading.csv",
    "stamped.csv",
    "iso.csv",
    "missing.csv",
    "folder.csv",
    "pipe.csv",
    "/dev/zero",
    "",
    ".",
    "motion.mcap",
    "m:u",
    "m:nope",
    "x:u",
    "u",
    "m:",
    ":u",
    "h:q",
    "h:psi",
    "m:mode",
    "s:tau",
    "secs",
    "stamp",
    "time",
    "s",
    "ms",
    "us",
    "ns",
    "h",
    "S",
    "hold",
    "linear",
    "cubic",
    "yaw",
    "enu",
    "ned",
    "NED",
    "instant",
    "2023-11-14T22:13:25Z",
    "2023-11-14T22:13:25",
    "2023-11-14T22:13:25.5+01:00",
    "10:00",
    "2023-13-40T00:00:00Z",
    "99999-01-01T00:00:00Z",
];

/// Keys a mutation may add: the manifest's own and unknown ones.
const KEYS: &[&str] = &[
    "file",
    "time",
    "time_unit",
    "from",
    "to",
    "when",
    "equals",
    "min",
    "max",
    "interpolate",
    "as",
    "frame",
    "on_grid",
    "step",
    "max_gap",
    "max_gap_steps",
    "experiment",
    "colour",
    "u",
    "psi",
];

/// A value of a kind picked at random (a type swapped in).
fn other(rng: &mut Seeded) -> V {
    match rng.range(0, 8) {
        0 => V::Str(rng.pick(TEXTS).to_string()),
        1 => V::Bool(rng.one_in(2)),
        2 => V::Array(Vec::new()),
        3 => V::Array(vec![
            V::Str("secs".into()),
            V::Str("nsecs".into()),
            V::Int(3),
        ]),
        4 => V::Array(vec![V::Str("secs".into())]),
        5 => V::Table(Vec::new()),
        6 => V::Table(vec![("from".into(), V::Str("m:u".into()))]),
        _ => V::Int(7),
    }
}

/// Nested arrays `depth` deep around a number.
fn nested(depth: usize) -> V {
    V::Deep(depth)
}

/// One change that may change what the manifest says.
fn mutate(tree: &mut V, rng: &mut Seeded) {
    let mut paths = Vec::new();
    tree.paths(&mut Vec::new(), &mut paths);
    let path = rng.pick(&paths).clone();
    let (parent, last) = match path.split_last() {
        Some((last, parent)) => (parent.to_vec(), Some(*last)),
        None => (Vec::new(), None),
    };
    let kind = rng.range(0, 12);
    let Some(node) = tree.at(&path) else {
        return;
    };
    match kind {
        0..=2 => {
            *node = match node {
                V::Str(_) => V::Str(rng.pick(TEXTS).to_string()),
                _ if rng.one_in(2) => plausible(rng),
                _ => extreme(rng),
            }
        }
        3 | 4 => *node = V::Str(rng.pick(TEXTS).to_string()),
        5 => *node = other(rng),
        6 => *node = extreme(rng),
        7 => match node {
            V::Array(items) if !items.is_empty() && rng.one_in(2) => {
                items.pop();
            }
            V::Array(items) => items.push(V::Str("nsecs".into())),
            V::Table(entries) => {
                let value = if rng.one_in(2) {
                    V::Str(rng.pick(TEXTS).to_string())
                } else {
                    extreme(rng)
                };
                entries.push((rng.pick(KEYS).to_string(), value));
            }
            _ => *node = nested(rng.range(2, 6)),
        },
        8 if rng.one_in(2) => {
            // Another window.
            let Some(V::Array(windows)) = tree.get("keep") else {
                if let V::Table(entries) = tree {
                    entries.push(("keep".into(), V::Array(vec![window(rng)])));
                }
                return;
            };
            windows.push(window(rng));
        }
        8 => {
            *node = nested(match rng.range(0, 3) {
                0 => rng.range(2, 40),
                1 => rng.range(100, 300),
                _ => rng.range(1000, 5000),
            });
        }
        _ => {
            // A key renamed, dropped or given twice.
            let Some(i) = last else { return };
            let Some(V::Table(entries)) = tree.at(&parent) else {
                return;
            };
            match kind {
                9 => entries[i].0 = rng.pick(KEYS).to_string(),
                10 => {
                    entries.remove(i);
                }
                _ => {
                    let twice = entries[i].clone();
                    entries.push(twice);
                }
            }
        }
    }
}

/// The same manifest, said differently: entries reordered, an integral
/// real written as an integer (or the reverse), a signal's short form
/// written in full, defaults said out loud.
fn neutral(tree: &mut V, rng: &mut Seeded) {
    match tree {
        V::Table(entries) => {
            if rng.one_in(2) {
                entries.reverse();
            }
            for (_, v) in entries.iter_mut() {
                neutral(v, rng);
            }
        }
        V::Array(items) => items.iter_mut().for_each(|v| neutral(v, rng)),
        V::Float(x) => {
            let x = *x;
            if x.fract() == 0.0
                && x.abs() < 1e15
                && !(x == 0.0 && x.is_sign_negative())
                && rng.one_in(2)
            {
                *tree = V::Int(x as i64);
            }
        }
        V::Int(i) => {
            if i.unsigned_abs() < 1 << 53 && rng.one_in(2) {
                *tree = V::Float(*i as f64);
            }
        }
        V::Str(_) | V::Bool(_) | V::Deep(_) | V::Raw(_) => {}
    }
}

/// Defaults said out loud and instants spelled otherwise: the experiment's
/// name (the manifest's stem), a one-column clock's `time_unit = "s"`
/// where it reads ISO text, a window's stamp at another offset or as a
/// TOML date-time, a signal in full (`{ from = ... }`), its interpolation
/// as the role has it (an input held, a state or heading linear).
fn defaults(tree: &mut V, rng: &mut Seeded) {
    if tree.get("experiment").is_none()
        && rng.one_in(2)
        && let V::Table(entries) = &mut *tree
    {
        entries.push(("experiment".into(), V::Str("log".into())));
    }
    if let Some(V::Table(sources)) = tree.get("sources") {
        for (_, source) in sources.iter_mut() {
            let one_column = matches!(source.get("time"), Some(V::Str(_)));
            if one_column
                && source.get("time_unit").is_none()
                && rng.one_in(2)
                && let V::Table(fields) = source
            {
                // A unit reads numbers; ISO text ignores it.
                let iso = fields
                    .iter()
                    .any(|(k, v)| k == "file" && *v == V::Str("iso.csv".into()));
                if iso {
                    fields.push(("time_unit".into(), V::Str("s".into())));
                }
            }
        }
    }
    // A window's stamp as the same instant at another offset, or as a
    // TOML date-time.
    if let Some(V::Array(windows)) = tree.get("keep") {
        for window in windows {
            if let Some(from) = window.get("from")
                && *from == V::Str("2023-11-14T22:13:36Z".into())
            {
                *from = match rng.range(0, 4) {
                    0 => V::Str("2023-11-14T23:43:36+01:30".into()),
                    1 => V::Raw("2023-11-14T22:13:36Z".into()),
                    2 => V::Raw("2023-11-14 21:13:36.000-01:00".into()),
                    _ => from.clone(),
                };
            }
        }
    }
    if let Some(V::Table(signals)) = tree.get("signals") {
        for (name, entry) in signals.iter_mut() {
            if let V::Str(from) = entry
                && rng.one_in(2)
            {
                let mut full = vec![("from".to_string(), V::Str(from.clone()))];
                if rng.one_in(2) {
                    let how = if name == "n" { "hold" } else { "linear" };
                    full.push(("interpolate".into(), V::Str(how.into())));
                }
                *entry = V::Table(full);
            }
        }
    }
}

/// A manifest written out as TOML, laid out and spelled at random, each
/// number written so that it reads to its bits.
struct Writer<'a> {
    rng: &'a mut Seeded,
    out: String,
    crlf: bool,
    comments: bool,
}

impl Writer<'_> {
    fn end(&mut self) {
        if self.comments && self.rng.one_in(4) {
            self.out.push_str(" # u = \"m:v\" [[keep]]");
        }
        self.out.push_str(if self.crlf { "\r\n" } else { "\n" });
        if self.comments && self.rng.one_in(6) {
            self.out.push_str(if self.rng.one_in(2) {
                "# [sources.x] file = \"y.csv\"\n"
            } else {
                "\n"
            });
        }
    }
    fn space(&mut self) -> &'static str {
        const SPACES: [&str; 4] = ["", " ", "  ", "\t"];
        SPACES[self.rng.range(0, SPACES.len())]
    }
    fn key(&mut self, k: &str) -> String {
        let bare = !k.is_empty()
            && k.bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-');
        match self.rng.range(0, 6) {
            _ if !bare => quoted(k),
            0 => quoted(k),
            1 => format!("'{k}'"),
            _ => k.to_string(),
        }
    }
    fn string(&mut self, s: &str) -> String {
        let plain = s.chars().all(|c| c.is_ascii_graphic() || c == ' ');
        match self.rng.range(0, 4) {
            0 if plain && !s.contains('\'') => format!("'{s}'"),
            1 if plain && !s.is_empty() => {
                let mut chars = s.chars();
                let first = chars.next().map_or(0, u32::from);
                let rest: String = chars.collect();
                format!("\"\\u{first:04x}{}", &quoted(&rest)[1..])
            }
            _ => quoted(s),
        }
    }
    fn int(&mut self, i: i64) -> String {
        match self.rng.range(0, 6) {
            0 if i >= 0 => format!("+{i}"),
            1 if i >= 0 => format!("0x{i:x}"),
            2 if i >= 0 => format!("0b{i:b}"),
            3 => underscored(&i.to_string(), self.rng),
            _ => i.to_string(),
        }
    }
    fn float(&mut self, x: f64) -> String {
        if x.is_nan() {
            return self.rng.pick(&["nan", "+nan", "-nan"]).to_string();
        }
        if x.is_infinite() {
            return if x > 0.0 {
                self.rng.pick(&["inf", "+inf"])
            } else {
                &"-inf"
            }
            .to_string();
        }
        let mut text = match self.rng.range(0, 4) {
            0 => format!("{x:e}"),
            1 => format!("{x:E}"),
            _ => format!("{x:?}"),
        };
        if self.rng.one_in(3) {
            let (mantissa, exponent) = match text.find(['e', 'E']) {
                Some(at) => text.split_at(at),
                None => (text.as_str(), ""),
            };
            text = if mantissa.contains('.') {
                format!("{mantissa}{}{exponent}", "0".repeat(self.rng.range(1, 4)))
            } else {
                format!("{mantissa}.0{exponent}")
            };
        }
        if self.rng.one_in(4) {
            text = text.replacen("e", "e+", 1).replace("e+-", "e-");
        }
        if x.is_sign_positive() && self.rng.one_in(4) {
            text.insert(0, '+');
        }
        if self.rng.one_in(4) {
            text = underscored(&text, self.rng);
        }
        text
    }
    fn value(&mut self, v: &V) -> String {
        match v {
            V::Int(i) => self.int(*i),
            V::Float(x) => self.float(*x),
            V::Str(s) => self.string(s),
            V::Bool(b) => b.to_string(),
            V::Deep(depth) => format!("{}1{}", "[".repeat(*depth), "]".repeat(*depth)),
            V::Raw(text) => text.clone(),
            V::Array(items) => {
                let parts: Vec<String> = items.iter().map(|v| self.value(v)).collect();
                let comma = if !items.is_empty() && self.rng.one_in(4) {
                    ","
                } else {
                    ""
                };
                let sep = if self.rng.one_in(5) {
                    ",\n  ".to_string()
                } else {
                    format!(",{}", self.space())
                };
                format!("[{}{}{comma}]", self.space(), parts.join(&sep))
            }
            V::Table(entries) => {
                let parts: Vec<String> = entries
                    .iter()
                    .map(|(k, v)| format!("{} = {}", self.key(k), self.value(v)))
                    .collect();
                format!("{{ {} }}", parts.join(", "))
            }
        }
    }
    /// A table's entries under the header path `path`: the values and the
    /// tables written in line (inline or dotted) first, then the tables
    /// and arrays of tables written as sections (`sections`: whether this
    /// table may have sections below it).
    fn table(&mut self, path: &[String], entries: &[(String, V)], sections: bool) {
        let mut below: Vec<(String, &V)> = Vec::new();
        for (k, v) in entries {
            let key = self.key(k);
            let tables = matches!(v, V::Array(items) if !items.is_empty() && items.iter().all(|i| matches!(i, V::Table(_))));
            match v {
                V::Table(inner) if sections && !inner.is_empty() && self.rng.range(0, 4) < 2 => {
                    below.push((k.clone(), v));
                }
                V::Array(_) if sections && tables && self.rng.range(0, 4) < 3 => {
                    below.push((k.clone(), v));
                }
                V::Table(inner)
                    if !inner.is_empty()
                        && self.rng.one_in(2)
                        && inner.iter().all(|(_, v)| !matches!(v, V::Table(_))) =>
                {
                    // Dotted keys.
                    for (k2, v2) in inner {
                        let (k2, s, v2) = (self.key(k2), self.space(), self.value(v2));
                        let _ = write!(self.out, "{key}.{k2}{s}={s}{v2}");
                        self.end();
                    }
                }
                _ => {
                    let (indent, s, value) = (self.space(), self.space(), self.value(v));
                    let _ = write!(self.out, "{indent}{key}{s}={s}{value}");
                    self.end();
                }
            }
        }
        for (k, v) in below {
            let mut here = path.to_vec();
            here.push(k);
            let header: Vec<String> = here.iter().map(|k| self.key(k)).collect();
            let header = header.join(".");
            match v {
                V::Table(inner) => {
                    let indent = self.space();
                    let _ = write!(self.out, "{indent}[{header}]");
                    self.end();
                    self.table(&here, inner, true);
                }
                V::Array(items) => {
                    for item in items {
                        let V::Table(inner) = item else { continue };
                        let _ = write!(self.out, "[[{header}]]");
                        self.end();
                        self.table(&here, inner, false);
                    }
                }
                _ => {}
            }
        }
    }
}

/// `s` in a basic string.
fn quoted(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 || c as u32 == 0x7f => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `text` with an underscore between two of its digits, where TOML allows
/// one (not in hexadecimal, octal or binary).
fn underscored(text: &str, rng: &mut Seeded) -> String {
    if text.contains(['x', 'o', 'b']) {
        return text.to_string();
    }
    let bytes = text.as_bytes();
    let places: Vec<usize> = (1..bytes.len())
        .filter(|&i| bytes[i - 1].is_ascii_digit() && bytes[i].is_ascii_digit())
        .collect();
    if places.is_empty() {
        return text.to_string();
    }
    let at = *rng.pick(&places);
    format!("{}_{}", &text[..at], &text[at..])
}

/// The manifest written out.
fn write(tree: &V, rng: &mut Seeded) -> String {
    let crlf = rng.one_in(5);
    let comments = rng.one_in(2);
    let mut w = Writer {
        rng,
        out: String::new(),
        crlf,
        comments,
    };
    match tree {
        V::Table(entries) => w.table(&[], entries, true),
        v => w.out = w.value(v),
    }
    w.out
}

/// Bytes changed at random: cut, flipped, inserted, removed, a line doubled.
fn damage(bytes: &[u8], rng: &mut Seeded) -> Vec<u8> {
    let mut bytes = bytes.to_vec();
    if bytes.is_empty() {
        return bytes;
    }
    match rng.range(0, 5) {
        0 => bytes.truncate(rng.range(0, bytes.len())),
        1 => {
            let at = rng.range(0, bytes.len());
            bytes[at] ^= 1 << rng.range(0, 8);
        }
        2 => {
            let at = rng.range(0, bytes.len());
            bytes.insert(at, *rng.pick(b"[]{}=\",.#\n'0-e_+\\:"));
        }
        3 => {
            bytes.remove(rng.range(0, bytes.len()));
        }
        _ => {
            let lines: Vec<&[u8]> = bytes.split_inclusive(|b| *b == b'\n').collect();
            let k = rng.range(0, lines.len());
            let mut out = lines.clone();
            out.insert(k, lines[k]);
            bytes = out.concat();
        }
    }
    bytes
}

/// Every loaded number, bit for bit, with its experiment's name and step.
type Numbers = Vec<(String, u64, Vec<u64>)>;

fn numbers(loaded: &LoadedFile) -> Numbers {
    loaded
        .experiments
        .iter()
        .map(|e| {
            let values = e
                .states
                .iter()
                .chain(&e.inputs)
                .chain(std::iter::once(&e.heading))
                .flatten()
                .map(|v| v.to_bits())
                .collect();
            (e.name.clone(), e.h.to_bits(), values)
        })
        .collect()
}

/// What a case is: the same manifest said differently (it must load, to
/// the base's numbers), a changed one or damaged bytes (loaded or refused
/// where), a source damaged under a base manifest.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Same,
    Changed,
    Damaged,
    Source,
}

/// What the cases found.
#[derive(Debug, Default)]
struct Outcomes {
    /// Cases of each kind: the same manifest said differently, changed,
    /// damaged bytes, a damaged source.
    kinds: [usize; 4],
    loaded: usize,
    refused: usize,
    panics: usize,
    changed: usize,
    unlocated: usize,
    /// The slowest case, s.
    slowest: f64,
}

/// What a manifest lacks, or the log as a whole: errors at the manifest,
/// with no line to show.
const WHOLE: &[&str] = &[
    "the manifest maps no signals",
    "is not mapped to a source",
    "differs from the model's sample time",
    "the log has no grid step",
    "the log leaves no experiment",
];

/// Whether an error says where: the manifest's line and column (or the
/// manifest itself for what it lacks), a source's row (and column), the
/// joined log's row and column; and always how to fix it.
fn located(e: &DataError, manifest: &str, text: &str, dir: &str) -> bool {
    if e.hint.is_empty() || e.message.is_empty() {
        return false;
    }
    if let Some(rest) = e.location.strip_prefix(manifest) {
        if rest.is_empty() {
            return WHOLE.iter().any(|w| e.message.contains(w));
        }
        if rest.starts_with(" (joined): row ") {
            return true;
        }
        let lines = text.split('\n').count();
        let mut parts = rest.trim_start_matches(':').split(':');
        let line: Option<usize> = parts.next().and_then(|l| l.parse().ok());
        let column: Option<usize> = parts.next().and_then(|c| c.parse().ok());
        return line.is_some_and(|l| (1..=lines).contains(&l)) && column.is_some_and(|c| c >= 1);
    }
    // A source: `file:row`, `file:row:column (name)`, or the file itself
    // when it cannot be read at all; a window given on the command line.
    e.location.starts_with(dir) || e.location.starts_with("--keep (window ")
}

/// One case: the manifest at `path` loaded; counted.
fn check(
    ir: &Ir,
    (path, options): (&Path, &LoadOptions),
    text: &str,
    said: Option<&Numbers>,
    kind: Kind,
    outcomes: &mut Outcomes,
) -> Result<(), String> {
    let started = std::time::Instant::now();
    let run =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| load_log(path, ir, options)));
    outcomes.slowest = outcomes.slowest.max(started.elapsed().as_secs_f64());
    let Ok(loaded) = run else {
        outcomes.panics += 1;
        return Err("a panic".into());
    };
    match loaded {
        Ok(loaded) => {
            outcomes.loaded += 1;
            let got = numbers(&loaded);
            match said {
                Some(said) if got != *said => {
                    outcomes.changed += 1;
                    Err("the same manifest said differently loads other numbers".into())
                }
                _ => Ok(()),
            }
        }
        Err(e) if kind == Kind::Same => {
            outcomes.changed += 1;
            Err(format!(
                "the same manifest said differently is refused: {e:?}"
            ))
        }
        Err(e) => {
            let manifest = path.display().to_string();
            let dir = path
                .parent()
                .map_or(String::new(), |d| d.display().to_string());
            if located(&e, &manifest, text, &dir) {
                outcomes.refused += 1;
                Ok(())
            } else {
                outcomes.unlocated += 1;
                Err(format!("unlocated: {e:?}"))
            }
        }
    }
}

/// A source's text damaged: a cell made bad, a row doubled or cut, a stamp
/// moved back.
fn damage_source(text: &str, rng: &mut Seeded) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let k = rng.range(1, lines.len());
    match rng.range(0, 5) {
        0 => {
            let mut cells: Vec<String> = lines[k].split(',').map(str::to_string).collect();
            let c = rng.range(0, cells.len());
            cells[c] = rng
                .pick(&["", "x", "nan", "inf", "1e999", "--1", "1,2", "\"1\""])
                .to_string();
            lines[k] = cells.join(",");
        }
        1 => {
            let row = lines[k].clone();
            lines.insert(k, row);
        }
        2 => {
            let cut = rng.range(0, lines[k].len().max(1));
            lines[k].truncate(cut);
        }
        3 => {
            let row = lines[k].clone();
            lines.insert(rng.range(1, k + 1), row);
        }
        _ => {
            lines.remove(k);
        }
    }
    lines.join("\n") + "\n"
}

/// The command line's options that meet a manifest's (valid ones, as the
/// CLI bounds them): windows, a gap limit, a grid step.
fn options(rng: &mut Seeded) -> LoadOptions {
    let mut o = LoadOptions::default();
    match rng.range(0, 3) {
        0 => {
            let from = rng.range(0, 250) as f64 / 10.0;
            o.keep = vec![(Some(from), Some(from + rng.range(1, 100) as f64 / 10.0))];
            if rng.one_in(2) {
                o.keep.push((Some(from + 12.0), None));
            }
        }
        1 => o.max_gap = leeway_data::gaps::GapLimit::Seconds(rng.range(1, 300) as f64 / 10.0),
        _ => o.resample = Some(*rng.pick(&[0.1, 0.2, 0.05])),
    }
    o
}

#[test]
fn mutated_manifests_load_as_they_say_or_are_refused_where_never_a_panic() {
    let cases: usize = std::env::var("LEEWAY_FUZZ_MANIFEST")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000);
    let started = std::time::Instant::now();
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let sources = write_sources(dir.path());
    let ir = model();
    let path: PathBuf = dir.path().join("log.toml");
    let bases: Vec<(V, Numbers)> = BASES
        .iter()
        .map(|text| {
            std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
            let loaded = load_log(&path, &ir, &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{text}: {e}"));
            let table: toml::Table = toml::from_str(text).unwrap_or_else(|e| panic!("{e}"));
            (V::of(&toml::Value::Table(table)), numbers(&loaded))
        })
        .collect();
    let mut rng = Seeded(0x5eed_3a71);
    let mut outcomes = Outcomes::default();
    let mut failures = Vec::new();
    for case in 0..cases {
        let (base, base_numbers) = &bases[case % bases.len()];
        let mut tree = base.clone();
        let kind = match rng.range(0, 8) {
            0 | 1 => Kind::Same,
            2..=4 => Kind::Changed,
            5 | 6 => Kind::Damaged,
            _ => Kind::Source,
        };
        outcomes.kinds[kind as usize] += 1;
        let mut damaged = None;
        let bytes = match kind {
            Kind::Same => {
                neutral(&mut tree, &mut rng);
                defaults(&mut tree, &mut rng);
                write(&tree, &mut rng).into_bytes()
            }
            Kind::Changed => {
                for _ in 0..rng.range(1, 4) {
                    mutate(&mut tree, &mut rng);
                }
                write(&tree, &mut rng).into_bytes()
            }
            Kind::Damaged => damage(write(&tree, &mut rng).as_bytes(), &mut rng),
            Kind::Source => {
                let (name, text) = rng.pick(&sources);
                std::fs::write(dir.path().join(name), damage_source(text, &mut rng))
                    .unwrap_or_else(|e| panic!("{e}"));
                damaged = Some((name, text));
                write(&tree, &mut rng).into_bytes()
            }
        };
        std::fs::write(&path, &bytes).unwrap_or_else(|e| panic!("{e}"));
        let text = String::from_utf8_lossy(&bytes);
        let said = (kind == Kind::Same).then_some(base_numbers);
        let options = if kind == Kind::Changed && rng.one_in(4) {
            options(&mut rng)
        } else {
            LoadOptions::default()
        };
        if let Err(why) = check(&ir, (&path, &options), &text, said, kind, &mut outcomes)
            && failures.len() < 20
        {
            failures.push(format!("case {case} ({kind:?}): {why}\n{text}"));
        }
        if let Some((name, text)) = damaged {
            std::fs::write(dir.path().join(name), text).unwrap_or_else(|e| panic!("{e}"));
        }
    }
    for f in &failures {
        eprintln!("{f}\n");
    }
    eprintln!("{cases} manifests in {:?}: {outcomes:?}", started.elapsed());
    assert_eq!(outcomes.panics, 0, "{outcomes:?}");
    assert_eq!(outcomes.changed, 0, "{outcomes:?}");
    assert_eq!(outcomes.unlocated, 0, "{outcomes:?}");
    // No case hangs (a pipe named as a source is refused, never waited on).
    assert!(outcomes.slowest < 5.0, "{outcomes:?}");
}
