//! Mutated plans — numbers at their extremes, keys dropped, given twice,
//! unknown or of another type, arrays of the wrong length, deep nesting,
//! bytes cut, flipped or inserted, in TOML and in JSON — are read and sized
//! (the conditions against the model, the samples a budget buys), or
//! refused with an error at the plan's line and column; never a panic. A
//! plan that reads holds the numbers its text says, bit for bit, however
//! they are spelled (`0.1`, `1e-1`, `+0.100`, `1_0.0`, an integer for a
//! real, TOML or JSON) and laid out (sections, inline or dotted tables,
//! comments, key order). Seeded: `LEEWAY_FUZZ_PLAN=N` runs N plans (CI's
//! short budget by default; 10 000 for a campaign, in release).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use leeway_design::bounds::SAMPLES;
use leeway_design::error::DesignError;
use leeway_design::plan::{PerComponent, PlanFile, locate, parse};
use leeway_model::Interpreter;
use leeway_model::model::Model;

use crate::common::model;

/// The plans of the repository, with their models.
const PLANS: &[(&str, &str)] = &[
    ("examples/models/rov.som", "examples/plans/rov.toml"),
    ("examples/models/blimp.som", "examples/plans/blimp.toml"),
    (
        "examples/models/hovercraft.som",
        "examples/plans/hovercraft.toml",
    ),
    ("examples/models/tanker.som", "examples/plans/tanker.toml"),
    (
        "examples/models/ship.som",
        "examples/plans/ship-high-wind.toml",
    ),
    (
        "examples/models/ship_iv2.som",
        "examples/plans/ship-iv2.toml",
    ),
    ("tests/models/catamaran.som", "tests/plans/catamaran.toml"),
];

/// splitmix64: a seeded stream, enough to pick mutations.
struct Seeded(u64);

impl Seeded {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// In `from..to` (`to > from`).
    fn range(&mut self, from: usize, to: usize) -> usize {
        from + (self.next() % (to - from) as u64) as usize
    }
    /// True once in `n` times.
    fn one_in(&mut self, n: usize) -> bool {
        self.range(0, n) == 0
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.range(0, items.len())]
    }
}

/// A plan as a tree, its tables' entries in order (a key may be given
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
            toml::Value::Table(t) => V::table(t),
        }
    }
    fn table(t: &toml::Table) -> V {
        V::Table(t.iter().map(|(k, v)| (k.clone(), V::of(v))).collect())
    }
    /// Every node's path from the root (indices for array items).
    fn paths(&self, here: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
        out.push(here.clone());
        match self {
            V::Array(items) => {
                for (i, v) in items.iter().enumerate() {
                    here.push(Step::Item(i));
                    v.paths(here, out);
                    here.pop();
                }
            }
            V::Table(entries) => {
                for (i, (_, v)) in entries.iter().enumerate() {
                    here.push(Step::Entry(i));
                    v.paths(here, out);
                    here.pop();
                }
            }
            _ => {}
        }
    }
    fn at(&mut self, path: &[Step]) -> Option<&mut V> {
        let Some((first, rest)) = path.split_first() else {
            return Some(self);
        };
        match (self, first) {
            (V::Array(items), Step::Item(i)) => items.get_mut(*i)?.at(rest),
            (V::Table(entries), Step::Entry(i)) => entries.get_mut(*i)?.1.at(rest),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Step {
    Item(usize),
    Entry(usize),
}

/// Numbers at the edges of what a plan may say.
fn extreme(rng: &mut Seeded) -> V {
    match rng.range(0, 24) {
        0 => V::Float(0.0),
        1 => V::Float(-0.0),
        2 => V::Float(1e-300),
        3 => V::Float(5e-324),
        4 => V::Float(1e308),
        5 => V::Float(f64::MAX),
        6 => V::Float(-1e308),
        7 => V::Float(f64::NAN),
        8 => V::Float(f64::INFINITY),
        9 => V::Float(f64::NEG_INFINITY),
        10 => V::Float(-1.0),
        11 => V::Int(i64::MAX),
        12 => V::Int(i64::MIN),
        13 => V::Int(0),
        14 => V::Int(-1),
        15 => V::Int((1 << 53) + 1),
        16 => V::Float(3600.0),
        17 => V::Float(3_600.000_000_000_5),
        18 => V::Int(49),
        19 => V::Int(10_000_001),
        20 => V::Float(1e-9),
        21 => V::Float(0.1 + 0.2),
        22 => V::Int(50),
        _ => V::Float(f64::from_bits(rng.next())),
    }
}

/// A value of a kind picked at random (a type swapped in).
fn other(rng: &mut Seeded) -> V {
    match rng.range(0, 8) {
        0 => V::Str(rng.pick(&["1.5", "", "auto", "nan", "prbs"]).to_string()),
        1 => V::Bool(rng.one_in(2)),
        2 => V::Array(Vec::new()),
        3 => V::Array(vec![V::Float(1.0), V::Str("x".into())]),
        4 => V::Table(Vec::new()),
        5 => V::Table(vec![("range".into(), V::Array(vec![V::Int(0), V::Int(1)]))]),
        6 => V::Int(7),
        _ => V::Float(0.25),
    }
}

/// Nested arrays `depth` deep around a number.
fn nested(depth: usize) -> V {
    V::Deep(depth)
}

/// One change that may change what the plan says (the tree is the truth
/// of what it says afterwards); false when the tree had no place for it.
fn mutate(tree: &mut V, rng: &mut Seeded, names: &[String]) -> bool {
    let mut paths = Vec::new();
    tree.paths(&mut Vec::new(), &mut paths);
    let path = rng.pick(&paths).clone();
    let kind = rng.range(0, 10);
    let (parent, last) = match path.split_last() {
        Some((last, parent)) => (parent.to_vec(), Some(*last)),
        None => (Vec::new(), None),
    };
    let Some(node) = tree.at(&path) else {
        return false;
    };
    match kind {
        // A number at an extreme (any node: a table becomes a number too).
        0..=2 => *node = extreme(rng),
        3 => *node = other(rng),
        4 => match node {
            V::Array(items) if rng.one_in(2) && !items.is_empty() => {
                items.pop();
            }
            V::Array(items) => items.push(V::Float(2.5)),
            V::Table(entries) => entries.push((
                rng.pick(&["colour", "range", "rate", "time", "samples", "std", "Step"])
                    .to_string(),
                V::Float(1.0),
            )),
            _ => return false,
        },
        5 => {
            *node = match rng.range(0, 3) {
                0 => nested(rng.range(2, 40)),
                1 => nested(rng.range(100, 300)),
                _ => nested(rng.range(1000, 5000)),
            }
        }
        6 => {
            // A key renamed: to another name of the model, or one it lacks.
            let Some(Step::Entry(i)) = last else {
                return false;
            };
            let Some(V::Table(entries)) = tree.at(&parent) else {
                return false;
            };
            entries[i].0 = match rng.range(0, 3) {
                0 if !names.is_empty() => rng.pick(names).clone(),
                1 => String::new(),
                _ => format!("{}_x", entries[i].0),
            };
        }
        7 | 8 => {
            // A key dropped, or given twice.
            let Some(Step::Entry(i)) = last else {
                return false;
            };
            let Some(V::Table(entries)) = tree.at(&parent) else {
                return false;
            };
            if kind == 7 {
                entries.remove(i);
            } else {
                let twice = entries[i].clone();
                entries.push(twice);
            }
        }
        _ => match node {
            V::Str(s) => {
                *s = rng
                    .pick(&[
                        "auto",
                        "pulses",
                        "prbs",
                        "multisine",
                        "zigzag",
                        "",
                        "PRBS",
                        "chirp",
                    ])
                    .to_string();
            }
            V::Table(entries) => {
                // The budget both ways, the excitation named.
                entries.push(("budget".into(), {
                    V::Table(vec![
                        ("time".into(), V::Int(1200)),
                        ("samples".into(), V::Int(5000)),
                    ])
                }));
            }
            _ => *node = extreme(rng),
        },
    }
    true
}

/// A plan written out: TOML or JSON, laid out and spelled at random, each
/// number written so that it reads to its bits.
struct Writer<'a> {
    rng: &'a mut Seeded,
    out: String,
    /// Line ends (`\n` or `\r\n`), comments, spacing.
    crlf: bool,
    comments: bool,
}

impl Writer<'_> {
    fn end(&mut self) {
        if self.comments && self.rng.one_in(4) {
            self.out.push_str(" # note = 1 [x]");
        }
        self.out.push_str(if self.crlf { "\r\n" } else { "\n" });
        if self.comments && self.rng.one_in(6) {
            self.out.push_str(if self.rng.one_in(2) {
                "# [inputs.x] range = [0, 1]\n"
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
    fn string(&mut self, s: &str, json: bool) -> String {
        let plain = s.chars().all(|c| c.is_ascii_graphic() || c == ' ');
        match self.rng.range(0, 4) {
            0 if plain && !json && !s.contains('\'') => format!("'{s}'"),
            1 if plain && !s.is_empty() => {
                // The first character as a \u escape.
                let mut chars = s.chars();
                let first = chars.next().map_or(0, u32::from);
                let rest: String = chars.collect();
                format!("\"\\u{first:04x}{}", &quoted(&rest)[1..])
            }
            _ => quoted(s),
        }
    }
    /// An integer, spelled as TOML (or JSON) allows.
    fn int(&mut self, i: i64, json: bool) -> String {
        if json {
            return i.to_string();
        }
        match self.rng.range(0, 6) {
            0 if i >= 0 => format!("+{i}"),
            1 if i >= 0 => format!("0x{i:x}"),
            2 if i >= 0 => format!("0o{i:o}"),
            3 => underscored(&i.to_string(), self.rng),
            _ => i.to_string(),
        }
    }
    /// A float, spelled as TOML (or JSON) allows, reading to `x`'s bits.
    fn float(&mut self, x: f64, json: bool) -> String {
        if x.is_nan() {
            // JSON has no NaN: a text that is no JSON.
            return if json {
                "NaN"
            } else {
                *self.rng.pick(&["nan", "+nan", "-nan"])
            }
            .into();
        }
        if x.is_infinite() {
            return match (json, x > 0.0) {
                (true, true) => "1e999".into(),
                (true, false) => "-1e999".into(),
                (false, true) => self.rng.pick(&["inf", "+inf"]).to_string(),
                (false, false) => "-inf".into(),
            };
        }
        let mut text = match self.rng.range(0, 4) {
            0 => format!("{x:e}"),
            1 => format!("{x:E}"),
            _ => format!("{x:?}"),
        };
        // A mantissa without a point: as TOML and JSON both allow.
        if self.rng.one_in(3) {
            let (mantissa, exponent) = match text.find(['e', 'E']) {
                Some(at) => text.split_at(at),
                None => (text.as_str(), ""),
            };
            if mantissa.contains('.') {
                text = format!("{mantissa}{}{exponent}", "0".repeat(self.rng.range(1, 4)));
            } else {
                text = format!("{mantissa}.0{exponent}");
            }
        }
        if self.rng.one_in(4) {
            text = text.replacen("e", "e+", 1).replace("e+-", "e-");
        }
        if !json && x.is_sign_positive() && self.rng.one_in(4) {
            text.insert(0, '+');
        }
        if !json && self.rng.one_in(4) {
            text = underscored(&text, self.rng);
        }
        text
    }
    fn scalar(&mut self, v: &V, json: bool) -> String {
        match v {
            V::Int(i) => self.int(*i, json),
            V::Float(x) => self.float(*x, json),
            V::Str(s) => self.string(s, json),
            V::Bool(b) => b.to_string(),
            V::Deep(depth) => format!("{}1{}", "[".repeat(*depth), "]".repeat(*depth)),
            V::Array(items) => {
                let parts: Vec<String> = items.iter().map(|v| self.scalar(v, json)).collect();
                let comma = if !json && !items.is_empty() && self.rng.one_in(4) {
                    ","
                } else {
                    ""
                };
                let sep = format!(",{}", self.space());
                format!("[{}{}{comma}]", self.space(), parts.join(&sep))
            }
            V::Table(entries) if json => self.json_object(entries),
            V::Table(entries) => {
                let parts: Vec<String> = entries
                    .iter()
                    .map(|(k, v)| format!("{} = {}", self.key(k), self.scalar(v, false)))
                    .collect();
                format!("{{ {} }}", parts.join(", "))
            }
        }
    }
    fn json_object(&mut self, entries: &[(String, V)]) -> String {
        let mut parts = Vec::new();
        for (k, v) in entries {
            let key = quoted(k);
            let nl = if self.rng.one_in(3) { "\n  " } else { "" };
            parts.push(format!(
                "{nl}{key}{}:{}{}",
                self.space(),
                self.space(),
                self.scalar(v, true)
            ));
        }
        format!("{{{}}}", parts.join(","))
    }
    /// A table's entries in TOML under the header path `path`: the values
    /// and the tables written in line (inline or dotted) first, then the
    /// tables written as sections.
    fn toml_table(&mut self, path: &[String], entries: &[(String, V)]) {
        let mut sections = Vec::new();
        for (k, v) in entries {
            let key = self.key(k);
            match v {
                V::Table(inner) if !inner.is_empty() && self.rng.range(0, 4) < 2 => {
                    sections.push((k.clone(), inner.clone()));
                }
                V::Table(inner) if !inner.is_empty() && self.rng.one_in(2) => {
                    // Dotted keys, when every value below is not a table.
                    if inner.iter().all(|(_, v)| !matches!(v, V::Table(_))) {
                        for (k2, v2) in inner {
                            let (k2, s, v2) = (self.key(k2), self.space(), self.scalar(v2, false));
                            let _ = write!(self.out, "{key}.{k2}{s}={s}{v2}");
                            self.end();
                        }
                    } else {
                        sections.push((k.clone(), inner.clone()));
                    }
                }
                _ => {
                    let (indent, s, value) = (self.space(), self.space(), self.scalar(v, false));
                    let _ = write!(self.out, "{indent}{key}{s}={s}{value}");
                    self.end();
                }
            }
        }
        for (k, inner) in sections {
            let mut here = path.to_vec();
            here.push(k);
            let header: Vec<String> = here.iter().map(|k| self.key(k)).collect();
            let indent = self.space();
            let _ = write!(self.out, "{indent}[{}]", header.join("."));
            self.end();
            self.toml_table(&here, &inner);
        }
    }
}

/// `s` in a basic string, as TOML and JSON both read it.
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
/// one (not in hexadecimal, octal or binary, never at an edge).
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

/// The plan written out.
fn write(tree: &V, json: bool, rng: &mut Seeded) -> String {
    let crlf = rng.one_in(5);
    let comments = rng.one_in(2);
    let mut w = Writer {
        rng,
        out: String::new(),
        crlf,
        comments,
    };
    let V::Table(entries) = tree else {
        return w.scalar(tree, json);
    };
    if json {
        w.json_object(entries)
    } else {
        w.toml_table(&[], entries);
        w.out
    }
}

/// A real's bits, every NaN alike (its sign and payload say nothing).
fn bits(x: f64) -> u64 {
    if x.is_nan() {
        f64::NAN.to_bits()
    } else {
        x.to_bits()
    }
}

/// Every number a plan holds, by path (`inputs.f.range[0]`): a real's
/// bits, a count as itself.
type Numbers = BTreeMap<String, u64>;

fn read_numbers(p: &PlanFile) -> Numbers {
    let mut out = Numbers::new();
    let mut real = |key: String, x: f64| {
        out.insert(key, bits(x));
    };
    if let Some(h) = p.step {
        real("step".into(), h);
    }
    for (k, x) in &p.nominal {
        real(format!("nominal.{k}"), *x);
    }
    for (k, x) in &p.noise {
        real(format!("noise.{k}"), *x);
    }
    for (k, l) in &p.inputs {
        real(format!("inputs.{k}.range[0]"), l.range[0]);
        real(format!("inputs.{k}.range[1]"), l.range[1]);
        if let Some(r) = l.rate {
            real(format!("inputs.{k}.rate"), r);
        }
    }
    for (k, d) in &p.disturbances {
        for (field, v) in [
            ("mean", &d.mean),
            ("std", &d.std),
            ("sensor_noise", &d.sensor_noise),
        ] {
            match v {
                Some(PerComponent::One(x)) => real(format!("disturbances.{k}.{field}"), *x),
                Some(PerComponent::Each(xs)) => {
                    for (i, x) in xs.iter().enumerate() {
                        real(format!("disturbances.{k}.{field}[{i}]"), *x);
                    }
                }
                None => {}
            }
        }
        for (field, v) in [
            ("correlation_time", d.correlation_time),
            ("mean_uncertainty", d.mean_uncertainty),
        ] {
            if let Some(x) = v {
                real(format!("disturbances.{k}.{field}"), x);
            }
        }
    }
    if let Some(b) = &p.budget {
        if let Some(t) = b.time {
            real("budget.time".into(), t);
        }
        if let Some(n) = b.samples {
            out.insert("budget.samples".into(), n as u64);
        }
    }
    out
}

/// The numbers a tree says, as [`read_numbers`] keys them (integers read
/// as the nearest real, except the budget's samples, a count).
fn said_numbers(v: &V, key: &str, out: &mut Numbers) {
    match v {
        V::Int(i) if key == "budget.samples" => {
            out.insert(key.to_string(), *i as u64);
        }
        V::Int(i) => {
            out.insert(key.to_string(), bits(*i as f64));
        }
        V::Float(x) => {
            out.insert(key.to_string(), bits(*x));
        }
        V::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                said_numbers(v, &format!("{key}[{i}]"), out);
            }
        }
        V::Table(entries) => {
            for (k, v) in entries {
                let key = if key.is_empty() {
                    k.clone()
                } else {
                    format!("{key}.{k}")
                };
                said_numbers(v, &key, out);
            }
        }
        V::Str(_) | V::Bool(_) | V::Deep(_) => {}
    }
}

/// The same plan, said differently: entries reordered, an integral real
/// written as an integer (or the reverse), the stated defaults given.
fn neutral(tree: &mut V, rng: &mut Seeded) {
    if let V::Table(entries) = tree {
        if rng.one_in(2) {
            entries.reverse();
        }
        for (k, v) in entries.iter_mut() {
            if k != "samples" {
                neutral(v, rng);
            }
        }
    } else if let V::Array(items) = tree {
        for v in items {
            neutral(v, rng);
        }
    } else if let V::Float(x) = *tree {
        if x.fract() == 0.0
            && x.abs() < 1e15
            && !(x == 0.0 && x.is_sign_negative())
            && rng.one_in(2)
        {
            *tree = V::Int(x as i64);
        }
    } else if let V::Int(i) = *tree
        && i.unsigned_abs() < 1 << 53
        && rng.one_in(2)
    {
        *tree = V::Float(i as f64);
    }
}

/// [`neutral`], and the excitation's default said out loud.
fn same_plan(tree: &mut V, rng: &mut Seeded) {
    neutral(tree, rng);
    if let V::Table(entries) = tree
        && !entries.iter().any(|(k, _)| k == "excitation")
        && rng.one_in(3)
    {
        entries.push(("excitation".into(), V::Str("auto".into())));
    }
}

/// Bytes changed at random: cut, flipped, inserted, a line doubled.
fn damage(text: &str, rng: &mut Seeded) -> String {
    let mut bytes = text.as_bytes().to_vec();
    if bytes.is_empty() {
        return String::new();
    }
    match rng.range(0, 5) {
        0 => bytes.truncate(rng.range(0, bytes.len())),
        1 => {
            let at = rng.range(0, bytes.len());
            bytes[at] ^= 1 << rng.range(0, 8);
        }
        2 => {
            let at = rng.range(0, bytes.len());
            let b = *rng.pick(b"[]{}=\",.#\n'0-e_+\\");
            bytes.insert(at, b);
        }
        3 => {
            let at = rng.range(0, bytes.len());
            bytes.remove(at);
        }
        _ => {
            let lines: Vec<&str> = text.split_inclusive('\n').collect();
            let k = rng.range(0, lines.len());
            let mut out: Vec<&str> = lines.clone();
            out.insert(k, lines[k]);
            bytes = out.concat().into_bytes();
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

/// What the cases found.
#[derive(Debug, Default)]
struct Outcomes {
    /// Cases of each kind: the same plan said differently, changed, damaged.
    kinds: [usize; 3],
    read: usize,
    sized: usize,
    refused: usize,
    panics: usize,
    changed: usize,
    unlocated: usize,
    /// The slowest case, s.
    slowest: f64,
}

/// Whether a plan error says where: a line and column inside the text, or
/// a value the plan leaves out (then there is no place to show).
fn located(e: &DesignError, text: &str) -> bool {
    let lines = text.split('\n').count();
    match (e.line, e.column) {
        (Some(l), Some(c)) => (1..=lines).contains(&l) && c >= 1,
        _ => {
            e.key.is_none()
                && (e.message.contains("the plan gives no range for the input")
                    || e.message
                        .contains("declares no `step` and the plan gives none"))
        }
    }
}

/// The conditions read from `plan` against the model, then sized (the
/// samples the budget buys at a few experiment counts): whether the
/// conditions hold the plan's numbers (θ, step, ranges) and each count is
/// within its bounds.
fn size(m: &Interpreter, plan: &PlanFile) -> Result<bool, DesignError> {
    let ir = m.ir();
    let c = plan.conditions(ir)?;
    let mut same = plan.step.is_none_or(|h| c.h.to_bits() == h.to_bits());
    for (name, x) in &plan.nominal {
        let i = ir.parameters.iter().position(|p| &p.name == name);
        same &= i.map(|i| c.theta[i].to_bits()) == Some(x.to_bits());
    }
    for (name, l) in ir.inputs.iter().zip(&c.limits) {
        let r = plan.inputs.get(name).map(|i| i.range);
        same &= r.map(|r| r.map(f64::to_bits)) == Some([l.low.to_bits(), l.high.to_bits()]);
    }
    for experiments in [1, 2, 3, 5, 8] {
        let n = c.budget.samples(experiments, c.h)?;
        same &= (SAMPLES.0..=SAMPLES.1).contains(&n);
    }
    Ok(same)
}

/// What a case is: the same plan said differently (it must read, to the
/// base's numbers), a changed one (it reads to the numbers it says, or is
/// refused where), bytes damaged (read or refused where).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Same,
    Changed,
    Damaged,
}

/// One case: read, checked against what it says, sized; counted.
fn check(
    m: &Interpreter,
    (text, json): (&str, bool),
    said: Option<&Numbers>,
    kind: Kind,
    outcomes: &mut Outcomes,
) -> Result<(), String> {
    let started = std::time::Instant::now();
    let run = std::panic::catch_unwind(|| match parse(text, json) {
        Ok(plan) => {
            let sized = size(m, &plan);
            (Some(read_numbers(&plan)), sized)
        }
        Err(e) => (None, Err(e)),
    });
    outcomes.slowest = outcomes.slowest.max(started.elapsed().as_secs_f64());
    let Ok((read, sized)) = run else {
        outcomes.panics += 1;
        return Err("a panic".into());
    };
    if let Some(got) = &read {
        outcomes.read += 1;
        if let Some(said) = said
            && got != said
        {
            outcomes.changed += 1;
            return Err(format!("read {got:?}\nsaid {said:?}"));
        }
    }
    match sized {
        Ok(true) => {
            outcomes.sized += 1;
            Ok(())
        }
        Ok(false) => {
            outcomes.changed += 1;
            Err("the conditions do not hold the plan's numbers".into())
        }
        Err(e) => {
            let e = locate(e, text, json);
            if kind == Kind::Same {
                outcomes.changed += 1;
                Err(format!("the same plan said differently is refused: {e:?}"))
            } else if e.code == "plan" && !located(&e, text) {
                outcomes.unlocated += 1;
                Err(format!("unlocated: {e:?}"))
            } else {
                outcomes.refused += 1;
                Ok(())
            }
        }
    }
}

/// The names a mutation may rename a key to: the model's parameters,
/// inputs, states and disturbances.
fn names(m: &Interpreter) -> Vec<String> {
    let ir = m.ir();
    ir.parameters
        .iter()
        .map(|p| p.name.clone())
        .chain(ir.inputs.iter().cloned())
        .chain(ir.states.iter().cloned())
        .chain(ir.disturbances.iter().map(|d| d.name.clone()))
        .collect()
}

#[test]
fn mutated_plans_read_as_they_say_or_are_refused_where_never_a_panic() {
    let cases: usize = std::env::var("LEEWAY_FUZZ_PLAN")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000);
    let started = std::time::Instant::now();
    let bases: Vec<(Interpreter, V, Numbers, Vec<String>)> = PLANS
        .iter()
        .map(|(m, plan)| {
            let m = model(m);
            let file = format!("{}/../{plan}", env!("CARGO_MANIFEST_DIR"));
            let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{file}: {e}"));
            let table: toml::Table =
                toml::from_str(&text).unwrap_or_else(|e| panic!("{file}: {e}"));
            let tree = V::table(&table);
            let mut said = Numbers::new();
            said_numbers(&tree, "", &mut said);
            let names = names(&m);
            (m, tree, said, names)
        })
        .collect();
    let mut rng = Seeded(0x5eed_91a4);
    let mut outcomes = Outcomes::default();
    let mut failures = Vec::new();
    for case in 0..cases {
        let (m, base, base_said, names) = &bases[case % bases.len()];
        let json = rng.one_in(3);
        let mut tree = base.clone();
        let kind = match rng.range(0, 4) {
            0 => Kind::Same,
            1 | 2 => Kind::Changed,
            _ => Kind::Damaged,
        };
        outcomes.kinds[kind as usize] += 1;
        let (text, said) = match kind {
            Kind::Same => {
                same_plan(&mut tree, &mut rng);
                (write(&tree, json, &mut rng), Some(base_said.clone()))
            }
            Kind::Changed => {
                for _ in 0..rng.range(1, 4) {
                    mutate(&mut tree, &mut rng, names);
                }
                let mut said = Numbers::new();
                said_numbers(&tree, "", &mut said);
                (write(&tree, json, &mut rng), Some(said))
            }
            Kind::Damaged => (damage(&write(&tree, json, &mut rng), &mut rng), None),
        };
        if let Err(why) = check(m, (&text, json), said.as_ref(), kind, &mut outcomes)
            && failures.len() < 20
        {
            failures.push(format!(
                "case {case} ({kind:?}, json {json}): {why}\n{text}"
            ));
        }
    }
    for f in &failures {
        eprintln!("{f}\n");
    }
    eprintln!("{cases} plans in {:?}: {outcomes:?}", started.elapsed());
    assert_eq!(outcomes.panics, 0, "{outcomes:?}");
    assert_eq!(outcomes.changed, 0, "{outcomes:?}");
    assert_eq!(outcomes.unlocated, 0, "{outcomes:?}");
    // No case hangs: the slowest reads and sizes in well under a second.
    assert!(outcomes.slowest < 2.0, "{outcomes:?}");
}
