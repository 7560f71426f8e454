//! The log manifest: a small TOML file, written once per log, that says
//! which file (or bag) each of the model's signals comes from and how each
//! file's clock is written. Documented in docs/logs.md.
//!
//! ```toml
//! experiment = "run3"          # default: the manifest's file name
//! step = 0.1                   # the grid; default: the model's step
//! max_gap = 2.0                # seconds; default: 5 of each signal's median steps
//!
//! [sources.twist]
//! file = "twist.csv"
//! time = ["secs", "nsecs"]     # seconds + nanoseconds columns
//! [sources.tau]
//! file = "tau.csv"
//! time = "stamp"               # one column: numbers (time_unit) or ISO-8601 text
//! time_unit = "ns"
//! [sources.bag]
//! file = "ferry.mcap"          # a ROS 2 bag: header stamps
//!
//! [signals]
//! u = "twist:u"
//! tau_x = { from = "tau:Fx", interpolate = "linear" }
//! psi = { from = "bag:/imu.orientation", as = "yaw", frame = "enu" }
//!
//! [[keep]]                     # windows: only these stretches are joined
//! from = 0                     # seconds from the log's first stamp,
//! to = 700                     # or ISO-8601 text with a UTC offset
//! [[keep]]
//! when = "mode:dp"             # where a source's column ...
//! equals = 0                   # ... equals a value (or min = / max =)
//! ```

use crate::stamps::TimeUnit;
use leeway_data::DataError;
use leeway_data::gaps::GapLimit;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The hint every manifest error carries.
const SEE_DOCS: &str = "docs/logs.md describes the manifest";

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    experiment: Option<String>,
    step: Option<Spanned<f64>>,
    max_gap: Option<Spanned<f64>>,
    max_gap_steps: Option<Spanned<f64>>,
    #[serde(default)]
    sources: BTreeMap<String, Spanned<SourceFile>>,
    #[serde(default)]
    signals: BTreeMap<String, Spanned<SignalEntry>>,
    #[serde(default)]
    keep: Vec<Spanned<KeepFile>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct KeepFile {
    from: Option<Spanned<TimeValue>>,
    to: Option<Spanned<TimeValue>>,
    when: Option<Spanned<String>>,
    equals: Option<f64>,
    min: Option<f64>,
    max: Option<f64>,
}

#[derive(serde::Deserialize)]
#[serde(untagged)]
enum TimeValue {
    Seconds(f64),
    Text(String),
    /// A TOML date-time, written without quotes: read as its text.
    Stamp(toml::value::Datetime),
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SourceFile {
    file: String,
    time: Option<TimeColumns>,
    time_unit: Option<Spanned<String>>,
}

#[derive(serde::Deserialize)]
#[serde(untagged)]
enum TimeColumns {
    One(String),
    Pair([String; 2]),
}

#[derive(serde::Deserialize)]
#[serde(untagged)]
enum SignalEntry {
    Path(String),
    Full(FullEntry),
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FullEntry {
    from: String,
    interpolate: Option<String>,
    #[serde(rename = "as")]
    kind: Option<String>,
    frame: Option<String>,
    on_grid: Option<String>,
}

/// A source's kind and clock.
#[derive(Clone, Debug, PartialEq)]
pub enum Clock {
    /// One column: decimal numbers in a unit, or ISO-8601 text.
    Column {
        /// The column.
        name: String,
        /// The unit of numbers.
        unit: TimeUnit,
    },
    /// Seconds and nanoseconds in two integer columns.
    Pair {
        /// Seconds.
        secs: String,
        /// Nanoseconds.
        nanos: String,
    },
    /// A ROS 2 bag: each message's header stamp (else its log time).
    Bag,
}

/// One file of the log.
#[derive(Clone, Debug)]
pub struct SourceSpec {
    /// Its key in `[sources]`.
    pub key: String,
    /// The file, relative to the manifest's folder.
    pub file: PathBuf,
    /// Its clock.
    pub clock: Clock,
    /// Where it is declared (`manifest:line:col`).
    pub at: String,
}

/// How a signal is put on the grid between its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolate {
    /// The last sample holds until the next (a command, an actuator set point).
    Hold,
    /// Straight lines between samples (a measurement).
    Linear,
}

/// One model signal and where it is read.
#[derive(Clone, Debug)]
pub struct SignalSpec {
    /// The model's signal.
    pub signal: String,
    /// Index into [`Manifest::sources`].
    pub source: usize,
    /// The column, or the bag's `topic.field.path`.
    pub field: String,
    /// As declared (`None`: the role's default).
    pub interpolate: Option<Interpolate>,
    /// A quaternion read as its heading (yaw): a bag's orientation, or a
    /// CSV's four columns `field.x`, `.y`, `.z`, `.w`.
    pub yaw: bool,
    /// The frame a heading is logged in (`None`: as the model's, NED).
    pub frame: Option<Frame>,
    /// Read at the grid time even when faster than the grid
    /// (`on_grid = "instant"`), not by its mean over the step.
    pub instant: bool,
    /// Where it is declared.
    pub at: String,
}

/// The world frame a heading is logged in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// North-east-down: the heading from north, clockwise (the model's ψ).
    Ned,
    /// East-north-up (ROS, REP 103): the yaw from east, counter-clockwise;
    /// ψ = 90° − yaw.
    Enu,
}

/// A time of a window: seconds from the log's first stamp, or a stamp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeRef {
    /// Seconds from the earliest stamp of any signal (the notes' times).
    FromStart(f64),
    /// An absolute stamp.
    At(crate::stamps::Nanos),
}

/// A condition on a source's column: it holds from a sample that meets it
/// until the next sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Condition {
    /// Index into [`Manifest::sources`].
    pub source: usize,
    /// The column (or the bag's field path).
    pub field: String,
    /// The value the column must equal.
    pub equals: Option<f64>,
    /// The least value it may have.
    pub min: Option<f64>,
    /// The largest value it may have.
    pub max: Option<f64>,
}

impl Condition {
    /// Whether `x` meets the condition.
    pub fn holds(&self, x: f64) -> bool {
        self.equals.is_none_or(|e| x == e)
            && self.min.is_none_or(|m| x >= m)
            && self.max.is_none_or(|m| x <= m)
    }
}

/// A window of the log that is kept: a time range, a condition, or both
/// (their intersection).
#[derive(Clone, Debug, PartialEq)]
pub struct Keep {
    /// Its start (`None`: the log's).
    pub from: Option<TimeRef>,
    /// Its end (`None`: the log's).
    pub to: Option<TimeRef>,
    /// Where a source's column meets a condition.
    pub when: Option<Condition>,
    /// Where it is declared.
    pub at: String,
}

/// A log manifest, read and checked against itself (the model's names are
/// checked when the log is joined).
#[derive(Clone, Debug)]
pub struct Manifest {
    /// The manifest file as named in messages.
    pub file: String,
    /// The experiment's name.
    pub experiment: String,
    /// The grid's step, when the manifest gives one.
    pub step: Option<f64>,
    /// Where the manifest gives its step (`manifest:line:col`).
    pub step_at: Option<String>,
    /// The gap limit, when the manifest gives one.
    pub max_gap: Option<GapLimit>,
    /// Where the manifest gives its gap limit.
    pub max_gap_at: Option<String>,
    /// The files, in key order.
    pub sources: Vec<SourceSpec>,
    /// The signals, in name order.
    pub signals: Vec<SignalSpec>,
    /// The windows kept (empty: the whole log).
    pub keep: Vec<Keep>,
}

/// `file:line:col` of byte `at` in `text`.
fn place(file: &str, text: &str, at: usize) -> String {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    format!("{file}:{line}:{col}")
}

/// The most bytes of a manifest: 1 MiB, some ten thousand lines. A larger
/// file (or one without end, `/dev/zero`) is refused, never read whole.
pub const MAX_MANIFEST_BYTES: u64 = 1 << 20;

/// Reads the manifest at `path`: at most [`MAX_MANIFEST_BYTES`], told by
/// its size and, for a pipe or a device whose size says nothing, by the
/// bytes read.
pub fn read(path: &Path) -> Result<Manifest, DataError> {
    let file = path.display().to_string();
    let too_large = |size: String| {
        DataError::new(
            &file,
            format!("the log manifest is larger than 1 MiB ({size}): it is not a manifest"),
            "a manifest is a small TOML file naming the log's sources (docs/logs.md); check the path given to --data",
        )
    };
    let bytes = read_bounded(path, MAX_MANIFEST_BYTES).map_err(|e| match e {
        Bounded::Io(e) => DataError::new(
            &file,
            format!("cannot read the log manifest: {e}"),
            "check the path given to --data",
        ),
        Bounded::Larger(Some(size)) => too_large(format!("{size} bytes")),
        Bounded::Larger(None) => too_large("it goes on past that".to_string()),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let before = String::from_utf8_lossy(&e.as_bytes()[..valid]);
        DataError::new(
            place(&file, &before, valid),
            "the log manifest is not UTF-8 text",
            "save the manifest as UTF-8 (TOML is UTF-8); check the path given to --data",
        )
    })?;
    let stem = path
        .file_stem()
        .map_or("log".to_string(), |s| s.to_string_lossy().into_owned());
    let folder = path.parent().unwrap_or(Path::new(""));
    parse(&file, &text, &stem, folder)
}

/// Why a file read whole with a bound was not read.
enum Bounded {
    /// It could not be opened or read.
    Io(std::io::Error),
    /// It is larger than the bound: its size when its metadata tells it.
    Larger(Option<u64>),
}

/// The bytes of `path`, at most `limit` of them: a larger regular file is
/// refused by its size before it is read, and no more than `limit + 1`
/// bytes are read from anything (a pipe, a device).
fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, Bounded> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(Bounded::Io)?;
    let size = file.metadata().map_err(Bounded::Io)?.len();
    if size > limit {
        return Err(Bounded::Larger(Some(size)));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(Bounded::Io)?;
    if bytes.len() as u64 > limit {
        return Err(Bounded::Larger(None));
    }
    Ok(bytes)
}

/// Parses a manifest's `text` (`file` names it in messages; `stem` is the
/// default experiment name; files are relative to `folder`).
pub fn parse(file: &str, text: &str, stem: &str, folder: &Path) -> Result<Manifest, DataError> {
    let raw: ManifestFile = toml::from_str(text).map_err(|e| {
        let at = e
            .span()
            .map_or(file.to_string(), |s| place(file, text, s.start));
        DataError::new(at, e.message().trim().to_string(), SEE_DOCS)
    })?;
    let at = |s: &std::ops::Range<usize>| place(file, text, s.start);
    let positive = |v: &Option<Spanned<f64>>, what: &str| -> Result<Option<f64>, DataError> {
        match v {
            Some(v) if !(v.get_ref().is_finite() && *v.get_ref() > 0.0) => Err(DataError::new(
                at(&v.span()),
                format!(
                    "`{what}` must be a positive number of seconds (steps for max_gap_steps), not {}",
                    v.get_ref()
                ),
                SEE_DOCS,
            )),
            v => Ok(v.as_ref().map(|v| *v.get_ref())),
        }
    };
    let step = positive(&raw.step, "step")?;
    let max_gap = match (positive(&raw.max_gap, "max_gap")?, &raw.max_gap_steps) {
        (Some(_), Some(s)) => {
            return Err(DataError::new(
                at(&s.span()),
                "both `max_gap` and `max_gap_steps` are given",
                "give one: seconds (max_gap) or median steps (max_gap_steps)",
            ));
        }
        (Some(s), None) => Some(GapLimit::Seconds(s)),
        (None, Some(n)) if !GapLimit::Steps(*n.get_ref()).is_valid() => {
            return Err(DataError::new(
                at(&n.span()),
                format!("`max_gap_steps = {}` must be at least 1.5", n.get_ref()),
                "a hole shorter than one and a half steps is jitter, not a gap",
            ));
        }
        (None, Some(n)) => Some(GapLimit::Steps(*n.get_ref())),
        (None, None) => None,
    };
    let mut sources = Vec::new();
    for (key, spec) in &raw.sources {
        sources.push(source(key, spec, folder, &at)?);
    }
    let mut signals = Vec::new();
    for (signal, entry) in &raw.signals {
        signals.push(signal_spec(signal, entry, &sources, &at)?);
    }
    if signals.is_empty() {
        return Err(DataError::new(
            file,
            "the manifest maps no signals",
            "add a [signals] table: each model signal = \"source:column\"",
        ));
    }
    let keep = raw
        .keep
        .iter()
        .map(|k| keep_spec(k, &sources, &at))
        .collect::<Result<_, _>>()?;
    let step_at = raw.step.as_ref().map(|v| at(&v.span()));
    let max_gap_at = raw
        .max_gap
        .as_ref()
        .or(raw.max_gap_steps.as_ref())
        .map(|v| at(&v.span()));
    Ok(Manifest {
        file: file.to_string(),
        experiment: raw.experiment.unwrap_or_else(|| stem.to_string()),
        step,
        step_at,
        max_gap,
        max_gap_at,
        sources,
        signals,
        keep,
    })
}

/// A `[[keep]]` window, checked.
fn keep_spec(
    k: &Spanned<KeepFile>,
    sources: &[SourceSpec],
    at: &dyn Fn(&std::ops::Range<usize>) -> String,
) -> Result<Keep, DataError> {
    let here = at(&k.span());
    let raw = k.get_ref();
    let time = |v: &Option<Spanned<TimeValue>>| -> Result<Option<TimeRef>, DataError> {
        let Some(v) = v else { return Ok(None) };
        let text = match v.get_ref() {
            TimeValue::Seconds(s) if s.is_finite() => return Ok(Some(TimeRef::FromStart(*s))),
            TimeValue::Seconds(s) => {
                return Err(DataError::new(
                    at(&v.span()),
                    format!("a window's time must be finite, not {s}"),
                    SEE_DOCS,
                ));
            }
            TimeValue::Text(t) => t.clone(),
            TimeValue::Stamp(d) => d.to_string(),
        };
        crate::stamps::iso_nanos(&text)
            .map(|ns| Some(TimeRef::At(ns)))
            .map_err(|why| {
                DataError::new(
                    at(&v.span()),
                    why,
                    "a window's time is seconds from the log's first stamp (a number), or ISO-8601 text with a UTC offset",
                )
            })
    };
    let (from, to) = (time(&raw.from)?, time(&raw.to)?);
    if let (Some(TimeRef::FromStart(a)), Some(TimeRef::FromStart(b))) = (from, to)
        && b <= a
    {
        return Err(DataError::new(
            here,
            format!("the window from {a} s to {b} s is empty"),
            "`to` must come after `from`",
        ));
    }
    let bounds = raw.equals.is_some() || raw.min.is_some() || raw.max.is_some();
    let when = match &raw.when {
        None if bounds => {
            return Err(DataError::new(
                here,
                "`equals`, `min` and `max` bound a column, and this window names none",
                "add when = \"source:column\"",
            ));
        }
        None if from.is_none() && to.is_none() => {
            return Err(DataError::new(
                here,
                "this window keeps everything: it has no `from`, `to` or `when`",
                "give a time range (from, to: seconds from the log's first stamp) or a condition (when = \"source:column\" with equals, min or max)",
            ));
        }
        None => None,
        Some(w) => Some(condition(w, raw, sources, bounds, at)?),
    };
    Ok(Keep {
        from,
        to,
        when,
        at: here,
    })
}

/// A window's `when = "source:column"` with its bounds.
fn condition(
    w: &Spanned<String>,
    raw: &KeepFile,
    sources: &[SourceSpec],
    bounds: bool,
    at: &dyn Fn(&std::ops::Range<usize>) -> String,
) -> Result<Condition, DataError> {
    let here = at(&w.span());
    if !bounds {
        return Err(DataError::new(
            here,
            format!("`when = \"{}\"` has no bound", w.get_ref()),
            "add equals = VALUE, or min = / max = (inclusive)",
        ));
    }
    if raw.equals.is_some() && (raw.min.is_some() || raw.max.is_some()) {
        return Err(DataError::new(
            here,
            "a window's condition has both `equals` and `min`/`max`",
            "give equals alone, or a range with min and max",
        ));
    }
    if let (Some(a), Some(b)) = (raw.min, raw.max)
        && b < a
    {
        return Err(DataError::new(
            here,
            format!("min = {a} is above max = {b}: the condition never holds"),
            "swap them",
        ));
    }
    let (source, field) = source_field(w.get_ref(), "when", &here, sources)?;
    Ok(Condition {
        source,
        field,
        equals: raw.equals,
        min: raw.min,
        max: raw.max,
    })
}

/// `"source:column"`: the source's index and the column.
fn source_field(
    from: &str,
    what: &str,
    here: &str,
    sources: &[SourceSpec],
) -> Result<(usize, String), DataError> {
    let keys = || {
        sources
            .iter()
            .map(|s| s.key.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some((key, field)) = from.split_once(':') else {
        return Err(DataError::new(
            here,
            format!("`{what} = \"{from}\"` names no source"),
            format!(
                "write \"source:column\" with a source of [sources] ({})",
                keys()
            ),
        ));
    };
    let Some(source) = sources.iter().position(|s| s.key == key) else {
        return Err(DataError::new(
            here,
            format!("`{what}` reads from source `{key}`, which [sources] does not declare"),
            format!("the sources are: {}", keys()),
        ));
    };
    Ok((source, field.to_string()))
}

fn source(
    key: &str,
    spec: &Spanned<SourceFile>,
    folder: &Path,
    at: &dyn Fn(&std::ops::Range<usize>) -> String,
) -> Result<SourceSpec, DataError> {
    let here = at(&spec.span());
    let s = spec.get_ref();
    let is_bag = Path::new(&s.file)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"));
    let unit = match &s.time_unit {
        None => TimeUnit::Seconds,
        Some(u) => TimeUnit::parse(u.get_ref()).ok_or_else(|| {
            DataError::new(
                at(&u.span()),
                format!("unknown time unit `{}`", u.get_ref()),
                "one of s, ms, us, ns",
            )
        })?,
    };
    if let Some(u) = &s.time_unit
        && (is_bag || matches!(s.time, Some(TimeColumns::Pair(_))))
    {
        return Err(DataError::new(
            at(&u.span()),
            format!("`time_unit` does not apply to source `{key}`"),
            "a unit reads one numeric time column; a bag's header stamps and a secs/nsecs pair carry their own",
        ));
    }
    let clock = match (&s.time, is_bag) {
        (None, true) => Clock::Bag,
        (Some(_), true) => {
            return Err(DataError::new(
                here,
                format!("source `{key}` is a bag, whose stamps are its messages' headers"),
                "drop `time` from a bag source",
            ));
        }
        (None, false) => Clock::Column {
            name: "time".into(),
            unit,
        },
        (Some(TimeColumns::One(name)), false) => Clock::Column {
            name: name.clone(),
            unit,
        },
        (Some(TimeColumns::Pair([secs, nanos])), false) => Clock::Pair {
            secs: secs.clone(),
            nanos: nanos.clone(),
        },
    };
    Ok(SourceSpec {
        key: key.to_string(),
        file: folder.join(&s.file),
        clock,
        at: here,
    })
}

fn signal_spec(
    signal: &str,
    entry: &Spanned<SignalEntry>,
    sources: &[SourceSpec],
    at: &dyn Fn(&std::ops::Range<usize>) -> String,
) -> Result<SignalSpec, DataError> {
    let here = at(&entry.span());
    let (from, interpolate, kind, frame, on_grid) = match entry.get_ref() {
        SignalEntry::Path(p) => (p.as_str(), None, None, None, None),
        SignalEntry::Full(f) => (
            f.from.as_str(),
            f.interpolate.as_deref(),
            f.kind.as_deref(),
            f.frame.as_deref(),
            f.on_grid.as_deref(),
        ),
    };
    let instant = match on_grid {
        None => false,
        Some("instant") => true,
        Some(other) => {
            return Err(DataError::new(
                here,
                format!("unknown `on_grid = \"{other}\"` for `{signal}`"),
                "\"instant\" reads the signal at the grid time even when it is faster than the grid; without it, a fast signal is its mean over the step",
            ));
        }
    };
    let (source, field) = source_field(from, signal, &here, sources)?;
    let interpolate = match interpolate {
        None => None,
        Some("hold") => Some(Interpolate::Hold),
        Some("linear") => Some(Interpolate::Linear),
        Some(other) => {
            return Err(DataError::new(
                here,
                format!("unknown interpolation `{other}` for `{signal}`"),
                "\"hold\" (the last sample until the next) or \"linear\"",
            ));
        }
    };
    let yaw = match kind {
        None => false,
        Some("yaw") => true,
        Some(other) => {
            return Err(DataError::new(
                here,
                format!("unknown conversion `as = \"{other}\"` for `{signal}`"),
                "\"yaw\" reads a quaternion (a bag's orientation) as its heading",
            ));
        }
    };
    let frame = match frame {
        None if yaw => {
            return Err(DataError::new(
                here,
                format!("`{signal}` reads a quaternion's yaw without its frame"),
                "say which world frame the orientation is in: frame = \"enu\" (ROS, REP 103: yaw from east, counter-clockwise; ψ = 90° − yaw) or frame = \"ned\" (the yaw is the heading from north, clockwise)",
            ));
        }
        None => None,
        Some("ned") => Some(Frame::Ned),
        Some("enu") => Some(Frame::Enu),
        Some(other) => {
            return Err(DataError::new(
                here,
                format!("unknown frame `{other}` for `{signal}`"),
                "\"enu\" (ROS, REP 103) or \"ned\" (north-east-down, the marine heading)",
            ));
        }
    };
    Ok(SignalSpec {
        signal: signal.to_string(),
        source,
        field,
        interpolate,
        yaw,
        frame,
        instant,
        at: here,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(text: &str) -> Result<Manifest, DataError> {
        parse("m.toml", text, "m", Path::new("logs"))
    }

    #[test]
    fn a_manifest_reads_with_its_defaults() {
        let m = parsed(
            "step = 0.1\n[sources.twist]\nfile = \"twist.csv\"\ntime = [\"secs\", \"nsecs\"]\n\
             [sources.tau]\nfile = \"tau.csv\"\ntime = \"stamp\"\ntime_unit = \"ns\"\n\
             [sources.bag]\nfile = \"f.mcap\"\n\
             [signals]\nu = \"twist:u\"\ntau_x = { from = \"tau:Fx\", interpolate = \"linear\" }\n\
             psi = { from = \"bag:/imu.orientation\", as = \"yaw\", frame = \"enu\" }\n\
             [[keep]]\nfrom = 0\nto = 700\n[[keep]]\nwhen = \"tau:mode\"\nequals = 0\n",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.experiment, "m");
        assert_eq!(m.step, Some(0.1));
        assert_eq!(m.max_gap, None);
        let keys: Vec<&str> = m.sources.iter().map(|s| s.key.as_str()).collect();
        assert_eq!(keys, ["bag", "tau", "twist"]);
        assert_eq!(m.sources[0].clock, Clock::Bag);
        assert_eq!(m.sources[2].file, Path::new("logs/twist.csv"));
        let psi = &m.signals[0];
        assert_eq!(
            (psi.signal.as_str(), psi.field.as_str(), psi.yaw),
            ("psi", "/imu.orientation", true)
        );
        assert_eq!(psi.frame, Some(Frame::Enu));
        assert_eq!(m.signals[1].interpolate, Some(Interpolate::Linear));
        assert_eq!(m.keep.len(), 2);
        assert_eq!(m.keep[0].from, Some(TimeRef::FromStart(0.0)));
        let when = m.keep[1]
            .when
            .as_ref()
            .map(|w| (w.source, w.field.as_str()));
        assert_eq!(when, Some((1, "mode")));
    }

    #[test]
    fn a_window_may_be_a_toml_date_time_or_text_of_the_same_instant() {
        let window = |from: &str| {
            parsed(&format!(
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = \"a:u\"\n[[keep]]\nfrom = {from}\n"
            ))
            .map(|m| m.keep[0].from)
            .unwrap_or_else(|e| panic!("{from}: {e}"))
        };
        let at = Some(TimeRef::At(1_700_000_016_500_000_000));
        for from in [
            "2023-11-14T22:13:36.5Z",
            "\"2023-11-14T22:13:36.5Z\"",
            "2023-11-14T23:13:36.5+01:00",
            "\"2023-11-14T21:13:36.5-01:00\"",
            "2023-11-14 22:13:36.5z",
        ] {
            assert_eq!(window(from), at, "{from}");
        }
    }

    #[test]
    fn every_mistake_is_located() {
        let cases = [
            (
                "[signals]\nu = \"twist:u\"\n",
                "m.toml:2:5",
                "does not declare",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = \"u\"\n",
                "m.toml:4:5",
                "names no source",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\ntime_unit = \"h\"\n[signals]\nu = \"a:u\"\n",
                "m.toml:3:13",
                "unknown time unit",
            ),
            ("stepp = 1\n", "m.toml:1:1", "unknown field"),
            ("step = -1\n[signals]\n", "m.toml:1:8", "positive"),
            (
                "max_gap_steps = 1\n[signals]\n",
                "m.toml:1:17",
                "at least 1.5",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = { from = \"a:u\", interpolate = \"cubic\" }\n",
                "m.toml:4:5",
                "unknown interpolation",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\npsi = { from = \"a:q\", as = \"yaw\" }\n",
                "m.toml:4:7",
                "without its frame",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\ntime = [\"s\", \"ns\"]\ntime_unit = \"ms\"\n[signals]\nu = \"a:u\"\n",
                "m.toml:4:13",
                "does not apply",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = \"a:u\"\n[[keep]]\nfrom = 5\nto = 2\n",
                "m.toml:5:1",
                "is empty",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = \"a:u\"\n[[keep]]\nwhen = \"b:mode\"\nequals = 1\n",
                "m.toml:6:8",
                "does not declare",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = \"a:u\"\n[[keep]]\nequals = 1\n",
                "m.toml:5:1",
                "names none",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = \"a:u\"\n[[keep]]\nfrom = \"10:00\"\n",
                "m.toml:6:8",
                "ISO",
            ),
            (
                "[sources.a]\nfile = \"a.csv\"\n[signals]\nu = \"a:u\"\n[[keep]]\nfrom = 2023-11-14T22:13:36\n",
                "m.toml:6:8",
                "no UTC offset",
            ),
        ];
        for (text, at, says) in cases {
            let e = parsed(text)
                .err()
                .unwrap_or_else(|| panic!("{text} is refused"));
            assert_eq!(e.location, at, "{text}: {e}");
            assert!(e.message.contains(says), "{text}: {e}");
        }
    }
}
