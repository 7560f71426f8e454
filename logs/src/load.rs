//! A log read as written: its manifest (or a bag whose topics the model's
//! `data { }` block names), every source read once, the signals joined on
//! the grid, and the joined samples handed to leeway-data's one validating
//! pass — units, outliers, minimum lengths — loaded or streamed like any
//! data file.

use crate::join::{Between, Joined, Rule, Track, join, seconds};
use crate::manifest::{Clock, Frame, Interpolate, Keep, Manifest, SignalSpec, SourceSpec, TimeRef};
use crate::series::{Series, read_table};
use crate::stamps::Nanos;
use leeway_data::columns::{Columns, Labels};
use leeway_data::signals::{Role, required_signals, unit_factor};
use leeway_data::validate::load_table;
use leeway_data::{
    DataError, FileNotes, LoadOptions, LoadedFile, SignalNote, StreamedFile, TimeNotes, open_table,
};
use leeway_model::experiment::column_name;
use leeway_structure::ir::Ir;
use std::path::Path;

/// Whether `path` is a log leeway joins: a manifest (`.toml`) or a ROS 2 bag (`.mcap`).
pub fn is_log(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml") || e.eq_ignore_ascii_case("mcap"))
}

/// Loads the log at `path` into memory, joined on the grid.
pub fn load_log(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<LoadedFile, DataError> {
    let j = joined(path, ir, options)?;
    let mut loaded = j.with_table(ir, |t, o| load_table(t, ir, o))?;
    loaded.notes = j.notes;
    Ok(loaded)
}

/// Opens the log at `path` for streaming (see [`leeway_data::open_table`]).
pub fn open_log(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<StreamedFile, DataError> {
    let j = joined(path, ir, options)?;
    let mut streamed = j.with_table(ir, |t, o| open_table(t, ir, o))?;
    streamed.notes = j.notes;
    Ok(streamed)
}

/// A log joined on its grid, before validation.
struct JoinedLog {
    /// The model's signals in row order, with their grid values per piece.
    signals: Vec<String>,
    joined: Joined,
    h: f64,
    name: String,
    options: LoadOptions,
    notes: FileNotes,
}

impl JoinedLog {
    /// The joined samples as a table (one column per signal, experiments
    /// labelled by piece), handed to `f` with the options that read it.
    fn with_table<T>(
        &self,
        ir: &Ir,
        f: impl FnOnce(&mut Columns, &LoadOptions) -> Result<T, DataError>,
    ) -> Result<T, DataError> {
        let width = self.signals.len();
        let mut columns: Vec<Vec<f64>> = vec![Vec::new(); width];
        let mut codes = Vec::new();
        let mut names = Vec::new();
        for (p, piece) in self.joined.pieces.iter().enumerate() {
            for (c, values) in columns.iter_mut().zip(&piece.columns) {
                c.extend_from_slice(values);
            }
            codes.extend(std::iter::repeat_n(
                p as i64,
                piece.columns.first().map_or(0, Vec::len),
            ));
            names.push(piece.name.clone());
        }
        let headers: Vec<String> = self.signals.iter().map(|s| column_name(ir, s)).collect();
        let named: Vec<(&str, &[f64])> = headers
            .iter()
            .map(String::as_str)
            .zip(columns.iter().map(Vec::as_slice))
            .collect();
        let label = column_name(ir, "experiment");
        let mut table = Columns::new(
            &self.name,
            &named,
            Some((
                &label,
                Labels::Coded {
                    codes: &codes,
                    names: &names,
                },
            )),
        )?;
        // The grid is uniform: the sample time is its step, not a mean of stamps.
        let options = LoadOptions {
            step: ir.step.is_none().then_some(self.h),
            resample: None,
            ..self.options.clone()
        };
        f(&mut table, &options)
    }
}

/// The manifest of `path`: read from a `.toml`, made for a `.mcap` from the
/// model's `data { }` block (each signal's column the bag's `topic.field.path`).
fn manifest(path: &Path, ir: &Ir) -> Result<Manifest, DataError> {
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        return crate::manifest::read(path);
    }
    let file = path.display().to_string();
    let signals = required_signals(ir)
        .into_iter()
        .map(|(signal, role)| {
            let field = column_name(ir, &signal);
            let yaw = role == Role::Heading && field.ends_with("orientation");
            SignalSpec {
                yaw,
                signal,
                source: 0,
                field,
                interpolate: None,
                // A bag without a manifest follows ROS (REP 103): ENU.
                frame: yaw.then_some(Frame::Enu),
                instant: false,
                at: file.clone(),
            }
        })
        .collect();
    Ok(Manifest {
        file: file.clone(),
        experiment: path
            .file_stem()
            .map_or("bag".into(), |s| s.to_string_lossy().into_owned()),
        step: None,
        step_at: None,
        max_gap: None,
        max_gap_at: None,
        sources: vec![SourceSpec {
            key: "bag".into(),
            file: path.to_path_buf(),
            clock: Clock::Bag,
            at: file,
        }],
        signals,
        keep: Vec::new(),
    })
}

/// A stall: a hole longer than this many of a signal's own median steps
/// (and than one grid step) but within the gap limit, noted.
const STALL_STEPS: f64 = 10.0;

/// Reads and joins the log at `path`.
fn joined(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<JoinedLog, DataError> {
    let m = with_options(manifest(path, ir)?, options)?;
    let specs = match_model(&m, ir)?;
    let h = grid_step(&m, ir, options)?;
    let limit = m.max_gap.unwrap_or(options.max_gap);
    let conditions = condition_specs(&m);
    let mut asked: Vec<&SignalSpec> = specs.iter().map(|(s, _)| *s).collect();
    asked.extend(&conditions);
    let mut series = read_signals(&m, &asked)?;
    let windows: Vec<Series> = series.split_off(specs.len());
    let values: Vec<Vec<f64>> = series
        .iter()
        .zip(&specs)
        .map(|(s, (spec, role))| heading_values(ir, spec, role, &s.values[0]))
        .collect();
    let mut tracks = Vec::with_capacity(series.len());
    let mut signals = Vec::with_capacity(series.len());
    for ((s, (spec, role)), values) in series.iter().zip(&specs).zip(&values) {
        #[allow(clippy::cast_precision_loss)]
        let steps: Vec<f64> = s
            .stamps
            .windows(2)
            .map(|w| (w[1] - w[0]) as f64 / 1e9)
            .collect();
        let median = leeway_data::gaps::median(&steps).unwrap_or(h);
        let rule = Rule::for_signal(
            between(ir, spec, role),
            matches!(role, Role::Input(_)),
            if spec.instant { f64::INFINITY } else { median },
            h,
        );
        let limit = limit.seconds(&steps, h);
        tracks.push(Track {
            signal: &spec.signal,
            stamps: &s.stamps,
            values,
            rule,
            limit: limit * 1e9,
            stall: (STALL_STEPS * median).max(h).min(limit) * 1e9,
        });
        signals.push(signal_note(&m, spec, s, median, rule));
    }
    let keep = kept_windows(&m, &tracks, &windows)?;
    let joined = join(&tracks, h, &m.experiment, keep.as_deref());
    check_joined(&m, &joined, &tracks)?;
    for ((note, t), samples) in signals.iter_mut().zip(&tracks).zip(&joined.samples) {
        note.first = seconds(t.stamps[0], joined.origin);
        note.last = seconds(t.stamps[t.stamps.len() - 1], joined.origin);
        note.on_grid = t.rule.describe(*samples);
        if note.median_step > 1.5 * h {
            // A slow source is read at the grid time: say how seldom it changes.
            note.on_grid.push_str(&format!(
                " (slower than the grid: a sample every {} steps)",
                leeway_model::number::short_number(note.median_step / h)
            ));
        }
    }
    let notes = join_notes(&m, &joined, signals);
    Ok(JoinedLog {
        signals: specs.iter().map(|(s, _)| s.signal.clone()).collect(),
        joined,
        h,
        name: format!("{} (joined)", m.file),
        options: options.clone(),
        notes,
    })
}

/// The manifest with the options the command line gives: an option that
/// the manifest also sets must agree with it (a conflict is an error, never
/// silently resolved); `--keep` windows stand where the manifest has none.
fn with_options(mut m: Manifest, options: &LoadOptions) -> Result<Manifest, DataError> {
    // At the manifest's value.
    let conflict = |at: &Option<String>, what: String, hint: &str| {
        Err(DataError::new(
            at.as_deref().unwrap_or(&m.file),
            what,
            hint.to_string(),
        ))
    };
    if let Some(given) = m.max_gap
        && options.max_gap != leeway_data::gaps::GapLimit::default()
        && options.max_gap != given
    {
        return conflict(
            &m.max_gap_at,
            format!(
                "--max-gap ({}) conflicts with the manifest's gap limit ({})",
                gap_text(options.max_gap),
                gap_text(given)
            ),
            "give the gap limit in one place: drop --max-gap, or `max_gap` from the manifest",
        );
    }
    if let (Some(step), Some(resample)) = (m.step, options.resample)
        && (step - resample).abs() > 1e-9 * step
    {
        return conflict(
            &m.step_at,
            format!("--resample {resample} conflicts with the manifest's step = {step}"),
            "give the grid's step in one place: drop --resample, or `step` from the manifest",
        );
    }
    if !options.keep.is_empty() {
        if let Some(k) = m.keep.first() {
            return Err(DataError::new(
                &k.at,
                "--keep is given and the manifest has its own [[keep]] windows",
                "give the windows in one place: drop --keep, or the manifest's [[keep]] tables",
            ));
        }
        m.keep = options
            .keep
            .iter()
            .enumerate()
            .map(|(i, (from, to))| Keep {
                from: from.map(TimeRef::FromStart),
                to: to.map(TimeRef::FromStart),
                when: None,
                at: format!("--keep (window {})", i + 1),
            })
            .collect();
    }
    Ok(m)
}

/// A gap limit as the user wrote it.
fn gap_text(g: leeway_data::gaps::GapLimit) -> String {
    match g {
        leeway_data::gaps::GapLimit::Seconds(s) => format!("{s} s"),
        leeway_data::gaps::GapLimit::Steps(n) => format!("{n} median steps"),
    }
}

/// A signal's values as the grid reads them. A heading is stated in its
/// declared unit, so that the validating pass converts it exactly once: a
/// quaternion's yaw (radians) scaled to that unit, and a heading logged in
/// ENU (yaw from east, counter-clockwise) turned into the NED heading the
/// model reads, ψ = 90° − yaw.
fn heading_values(ir: &Ir, spec: &SignalSpec, role: &Role, values: &[f64]) -> Vec<f64> {
    let factor = unit_factor(ir, &spec.signal);
    let scale = if spec.yaw { 1.0 / factor } else { 1.0 };
    let quarter = std::f64::consts::FRAC_PI_2 / factor;
    match (role, spec.frame) {
        (Role::Heading, Some(Frame::Enu)) => values.iter().map(|v| quarter - v * scale).collect(),
        _ => values.iter().map(|v| v * scale).collect(),
    }
}

/// The columns the manifest's windows test, as signals to read.
fn condition_specs(m: &Manifest) -> Vec<SignalSpec> {
    m.keep
        .iter()
        .filter_map(|k| {
            k.when.as_ref().map(|w| SignalSpec {
                signal: format!("the window at {}", k.at),
                source: w.source,
                field: w.field.clone(),
                interpolate: None,
                yaw: false,
                frame: None,
                instant: false,
                at: k.at.clone(),
            })
        })
        .collect()
}

/// The windows the manifest keeps, as sorted disjoint stretches of stamps
/// (`None`: the whole log); `conditions` are the series of the windows'
/// conditions, in order. A window that keeps nothing where every signal
/// has samples is an error naming it.
fn kept_windows(
    m: &Manifest,
    tracks: &[Track],
    conditions: &[Series],
) -> Result<Option<Vec<(Nanos, Nanos)>>, DataError> {
    if m.keep.is_empty() {
        return Ok(None);
    }
    let origin = tracks.iter().map(|t| t.stamps[0]).min().unwrap_or(0);
    let lo = tracks.iter().map(|t| t.stamps[0]).max().unwrap_or(0);
    let hi = tracks
        .iter()
        .map(|t| t.stamps[t.stamps.len() - 1])
        .min()
        .unwrap_or(0);
    let mut conditions = conditions.iter();
    let mut all = Vec::new();
    for k in &m.keep {
        let stretches = match &k.when {
            Some(w) => match conditions.next() {
                Some(s) => holds(s, |x| w.holds(x)),
                None => Vec::new(),
            },
            None => vec![(Nanos::MIN, Nanos::MAX)],
        };
        let (a, b) = (
            time_of(k.from, origin, Nanos::MIN),
            time_of(k.to, origin, Nanos::MAX),
        );
        let mine: Vec<(Nanos, Nanos)> = stretches
            .into_iter()
            .map(|(x, y)| (x.max(a), y.min(b)))
            .filter(|(x, y)| x <= y)
            .collect();
        if !mine.iter().any(|(x, y)| *x <= hi && *y >= lo) {
            return Err(keeps_nothing(m, k, origin, lo, hi));
        }
        all.extend(mine);
    }
    all.sort_unstable();
    let mut merged: Vec<(Nanos, Nanos)> = Vec::with_capacity(all.len());
    for (a, b) in all {
        match merged.last_mut() {
            Some(last) if a <= last.1.saturating_add(1) => last.1 = last.1.max(b),
            _ => merged.push((a, b)),
        }
    }
    Ok(Some(merged))
}

/// The stretches where `s` meets `test`: from a sample that meets it until
/// just before the next sample.
fn holds(s: &Series, test: impl Fn(f64) -> bool) -> Vec<(Nanos, Nanos)> {
    let mut out: Vec<(Nanos, Nanos)> = Vec::new();
    for (k, (&t, &x)) in s.stamps.iter().zip(&s.values[0]).enumerate() {
        if !test(x) {
            continue;
        }
        let end = s.stamps.get(k + 1).map_or(t, |next| next - 1);
        match out.last_mut() {
            Some(last) if last.1 + 1 == t => last.1 = end,
            _ => out.push((t, end)),
        }
    }
    out
}

/// A window's time as a stamp (`open` when not given).
fn time_of(t: Option<TimeRef>, origin: Nanos, open: Nanos) -> Nanos {
    match t {
        None => open,
        #[allow(clippy::cast_possible_truncation)]
        Some(TimeRef::FromStart(s)) => origin.saturating_add((s * 1e9).round() as Nanos),
        Some(TimeRef::At(ns)) => ns,
    }
}

/// The error of a window that keeps nothing.
fn keeps_nothing(m: &Manifest, k: &Keep, origin: Nanos, lo: Nanos, hi: Nanos) -> DataError {
    use leeway_model::number::short_number as num;
    DataError::new(
        &k.at,
        format!(
            "this window keeps nothing of `{}`: every signal has samples only from t = {} to {} s (from the log's first stamp, {})",
            m.experiment,
            num(seconds(lo, origin)),
            num(seconds(hi, origin)),
            crate::stamps::iso(origin)
        ),
        "a window's from/to are seconds from the log's first stamp (or ISO-8601 stamps); a condition must hold somewhere in that span",
    )
}

/// Every asked signal's series, in the order of `asked`, each source read
/// once; a signal with fewer than two samples is an error.
fn read_signals(m: &Manifest, asked: &[&SignalSpec]) -> Result<Vec<Series>, DataError> {
    let mut series: Vec<(Series, usize)> = Vec::with_capacity(asked.len());
    for (s, source) in m.sources.iter().enumerate() {
        let wanted: Vec<usize> = (0..asked.len()).filter(|k| asked[*k].source == s).collect();
        if wanted.is_empty() {
            continue;
        }
        let these: Vec<&SignalSpec> = wanted.iter().map(|k| asked[*k]).collect();
        series.extend(read_source(source, &these)?.into_iter().zip(wanted));
    }
    series.sort_by_key(|(_, k)| *k);
    for (s, k) in &series {
        let spec = asked[*k];
        if s.stamps.len() < 2 {
            return Err(DataError::new(
                &spec.at,
                format!(
                    "signal `{}` has {} samples in `{}`",
                    spec.signal,
                    s.stamps.len(),
                    m.sources[spec.source].file.display()
                ),
                "a signal needs samples along the experiment: check the topic or column",
            ));
        }
    }
    Ok(series.into_iter().map(|(s, _)| s).collect())
}

/// What the notes say of one signal as read (its first and last stamps are
/// set once the origin is known).
fn signal_note(m: &Manifest, spec: &SignalSpec, s: &Series, median: f64, rule: Rule) -> SignalNote {
    SignalNote {
        signal: spec.signal.clone(),
        source: format!("{}:{}", m.sources[spec.source].file.display(), spec.field),
        samples: s.stamps.len(),
        median_step: median,
        first: 0.0,
        last: 0.0,
        repeated_stamps: s.repeated,
        between: match rule.between {
            Between::Hold => "hold",
            Between::Linear => "linear",
            Between::Angle { .. } => "angle",
        }
        .into(),
        on_grid: String::new(),
    }
}

/// The notes of a joined log: its gaps and pieces, its signals, its origin.
fn join_notes(m: &Manifest, joined: &Joined, signals: Vec<SignalNote>) -> FileNotes {
    let samples = joined
        .pieces
        .iter()
        .map(|p| p.columns.first().map_or(0, Vec::len))
        .sum();
    FileNotes {
        file: m.file.clone(),
        experiments: vec![TimeNotes {
            experiment: m.experiment.clone(),
            rows: samples,
            gaps: joined.gaps.clone(),
            pieces: joined.notes.clone(),
            stalls: joined.stalls.clone(),
            ..TimeNotes::default()
        }],
        origin: Some(crate::stamps::iso(joined.origin)),
        signals,
        ..FileNotes::default()
    }
}

/// How a signal is read between samples: a command held, a measurement
/// interpolated (a heading along the short arc of a turn in its declared
/// unit: 360 for degrees), unless the manifest says.
fn between(ir: &Ir, spec: &SignalSpec, role: &Role) -> Between {
    match (spec.interpolate, role) {
        (Some(Interpolate::Hold), _) => Between::Hold,
        (Some(Interpolate::Linear), Role::Heading) | (None, Role::Heading) => Between::Angle {
            turn: 2.0 * std::f64::consts::PI / unit_factor(ir, &spec.signal),
        },
        (Some(Interpolate::Linear), _) => Between::Linear,
        (None, Role::Input(_)) => Between::Hold,
        (None, _) => Between::Linear,
    }
}

/// Every signal the model reads mapped once, and nothing else: in the
/// model's row order, with its role.
fn match_model<'m>(m: &'m Manifest, ir: &Ir) -> Result<Vec<(&'m SignalSpec, Role)>, DataError> {
    let wanted = required_signals(ir);
    for s in &m.signals {
        if !wanted.iter().any(|(w, _)| *w == s.signal) {
            return Err(DataError::new(
                &s.at,
                format!("the model reads no signal `{}` from data", s.signal),
                format!(
                    "the model's signals are: {}",
                    wanted
                        .iter()
                        .map(|(w, _)| w.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    }
    wanted
        .into_iter()
        .map(
            |(signal, role)| match m.signals.iter().find(|s| s.signal == signal) {
                Some(s) => Ok((s, role)),
                None => Err(DataError::new(
                    &m.file,
                    format!("signal `{signal}` is not mapped to a source"),
                    format!("add it under [signals]: {signal} = \"<source>:<column>\""),
                )),
            },
        )
        .collect()
}

/// The grid's step: the manifest's, else `--resample`, else the model's or `--step`.
fn grid_step(m: &Manifest, ir: &Ir, options: &LoadOptions) -> Result<f64, DataError> {
    let declared = ir.step.or(options.step);
    match (m.step.or(options.resample), declared) {
        (Some(g), Some(d)) if (g - d).abs() > 1e-9 * d => Err(DataError::new(
            // At the manifest's step when it is the grid's.
            m.step_at.as_deref().unwrap_or(&m.file),
            format!("the grid step {g} s differs from the model's sample time {d} s"),
            "drop `step` from the manifest (the model's step is used), or make them equal",
        )),
        (Some(g), _) | (None, Some(g)) => Ok(g),
        (None, None) => Err(DataError::new(
            &m.file,
            "the log has no grid step: the model declares no `step` and the manifest none",
            "add `step = 0.1` (seconds) to the manifest, or `step` to the model",
        )),
    }
}

/// A source's requested signals: one series per signal, each with its own stamps.
fn read_source(source: &SourceSpec, wanted: &[&SignalSpec]) -> Result<Vec<Series>, DataError> {
    a_file(source)?;
    if source.clock == Clock::Bag {
        return crate::bag_source::read(source, wanted);
    }
    // A yaw reads a quaternion's four columns `field.x`, `.y`, `.z`, `.w`.
    let mut fields: Vec<String> = Vec::new();
    let mut at = Vec::with_capacity(wanted.len());
    for s in wanted {
        at.push(fields.len());
        if s.yaw {
            fields.extend(QUATERNION.iter().map(|c| format!("{}.{c}", s.field)));
        } else {
            fields.push(s.field.clone());
        }
    }
    let all = leeway_data::with_table(&source.file, "--data", |t| {
        for s in wanted.iter().filter(|s| s.yaw) {
            quaternion_columns(t, s)?;
        }
        read_table(t, source, &fields)
    })?;
    Ok(wanted
        .iter()
        .zip(at)
        .map(|(s, j)| Series {
            file: all.file.clone(),
            stamps: all.stamps.clone(),
            values: vec![if s.yaw {
                let q = &all.values[j..j + 4];
                (0..all.stamps.len())
                    .map(|k| crate::bag::plan::yaw(q[0][k], q[1][k], q[2][k], q[3][k]))
                    .collect()
            } else {
                all.values[j].clone()
            }],
            repeated: all.repeated,
        })
        .collect())
}

/// A source must be a file (a bag also its rosbag2 folder): a manifest
/// never makes leeway wait on a pipe or a terminal, or read a device. Asked
/// before the source is opened (opening a pipe waits for its writer); a
/// path that does not exist is left to the reader's own error.
fn a_file(source: &SourceSpec) -> Result<(), DataError> {
    let Ok(kind) = std::fs::metadata(&source.file).map(|m| m.file_type()) else {
        return Ok(());
    };
    let what = match kind {
        k if k.is_file() => return Ok(()),
        k if k.is_dir() && source.clock == Clock::Bag => return Ok(()),
        k if k.is_dir() => "a folder",
        k => special(k),
    };
    Err(DataError::new(
        &source.at,
        format!(
            "source `{}` is {what}, not a file: `{}`",
            source.key,
            source.file.display()
        ),
        "a log's sources are the files its logger wrote (a bag also its folder); name them in [sources]",
    ))
}

/// What a file that is neither a regular file nor a folder is.
#[cfg(unix)]
fn special(kind: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if kind.is_fifo() {
        "a pipe (FIFO)"
    } else if kind.is_socket() {
        "a socket"
    } else if kind.is_char_device() || kind.is_block_device() {
        "a device"
    } else {
        "not a regular file"
    }
}

/// What a file that is neither a regular file nor a folder is.
#[cfg(not(unix))]
fn special(_: std::fs::FileType) -> &'static str {
    "not a regular file"
}

/// A quaternion's columns, after its name: `orientation.x`, … as ROS 2
/// exports write a `geometry_msgs/Quaternion`.
const QUATERNION: [&str; 4] = ["x", "y", "z", "w"];

/// A yaw's four quaternion columns must all be there; a scalar column of
/// the yaw's name is refused, never read as a heading.
fn quaternion_columns(
    t: &dyn leeway_data::validate::Table,
    s: &SignalSpec,
) -> Result<(), DataError> {
    let headers = t.headers();
    let missing: Vec<String> = QUATERNION
        .iter()
        .map(|c| format!("{}.{c}", s.field))
        .filter(|c| !headers.contains(c))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let why = if headers.contains(&s.field) {
        format!(
            "`{}` is one column, and `as = \"yaw\"` reads a quaternion: a scalar is never taken for a yaw",
            s.field
        )
    } else {
        format!(
            "`{}` reads a quaternion's yaw, and the source has no column {}",
            s.signal,
            missing.join(", ")
        )
    };
    Err(DataError::new(
        &s.at,
        why,
        format!(
            "a quaternion is four columns `{0}.x`, `{0}.y`, `{0}.z`, `{0}.w`; a heading already in one column is mapped without `as` (its unit in the model's data {{ }} block)",
            s.field
        ),
    ))
}

/// A log that leaves no experiment: one error saying why.
fn check_joined(m: &Manifest, j: &Joined, tracks: &[Track]) -> Result<(), DataError> {
    if !j.pieces.is_empty() {
        return Ok(());
    }
    let lo = tracks.iter().map(|t| (t.stamps[0], t.signal)).max();
    let hi = tracks
        .iter()
        .map(|t| (t.stamps[t.stamps.len() - 1], t.signal))
        .min();
    let why = match (lo, hi) {
        (Some((a, sa)), Some((b, sb))) if a > b => format!(
            "the signals never overlap in time: `{sa}` starts at {} but `{sb}` ends at {} (clocks in different time zones, or files of different runs?)",
            crate::stamps::iso(a),
            crate::stamps::iso(b)
        ),
        _ => format!(
            "every stretch where all signals have samples is shorter than {} samples ({} gaps split it)",
            leeway_model::experiment::MIN_SAMPLES,
            j.gaps.len()
        ),
    };
    Err(DataError::new(
        &m.file,
        format!("the log leaves no experiment: {why}"),
        "check each source's clock and the gap limit (max_gap in the manifest, --max-gap)",
    ))
}

/// Loads any data file: a log (see [`is_log`]) joined, else one CSV or
/// Parquet file ([`leeway_data::load_file_noted`]).
pub fn load_path(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<LoadedFile, DataError> {
    if is_log(path) {
        load_log(path, ir, options)
    } else {
        no_windows(path, options)?;
        leeway_data::load_file_noted(path, ir, options)
    }
}

/// `--keep` on a plain data file: refused, as windows of a log only.
fn no_windows(path: &Path, options: &LoadOptions) -> Result<(), DataError> {
    if options.keep.is_empty() {
        return Ok(());
    }
    Err(DataError::new(
        path.display().to_string(),
        "--keep keeps windows of a joined log (a manifest or a bag), and this is one data file",
        "name the file in a manifest with one source (docs/logs.md) to keep windows of it, or cut the file",
    ))
}

/// Opens any data file for streaming, as [`load_path`] loads it.
pub fn open_path(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<StreamedFile, DataError> {
    if is_log(path) {
        open_log(path, ir, options)
    } else {
        no_windows(path, options)?;
        leeway_data::open_file(path, ir, options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;
    use std::fmt::Write as _;

    fn model(extra: &str) -> Ir {
        let src = format!(
            "model M {{ step 0.1 state u, r input n heading psi integrates r {extra}
             der u = X*u + T*n der r = N*r + M*n
             nominal {{ X = -0.1, T = 1, N = -0.2, M = 0.5 }} }}"
        );
        leeway_structure::compile(&src, &leeway_structure::CompileOptions::default())
            .ir
            .unwrap_or_else(|| panic!("the test model compiles"))
    }

    /// A CSV topic stamped `secs,nsecs` from `rows` of (seconds, cells).
    fn topic(header: &str, rows: impl Iterator<Item = (f64, String)>) -> String {
        let mut out = format!("secs,nsecs,{header}\n");
        for (t, cells) in rows {
            let ns = (t * 1e9).round() as i64;
            let _ = writeln!(out, "{},{},{cells}", ns / 1_000_000_000, ns % 1_000_000_000);
        }
        out
    }

    /// A log of three sources: `u`, `r` and `n` at 10 Hz on the grid, the
    /// heading at 1 Hz turning at 18°/s (`heading` writes its cells), 60 s.
    fn write_log(dir: &Path, heading_header: &str, heading: impl Fn(f64) -> String, extra: &str) {
        let fast = (0..=600).map(|k| f64::from(k) / 10.0);
        let w = |name: &str, text: String| {
            std::fs::write(dir.join(name), text).unwrap_or_else(|e| panic!("{e}"));
        };
        w(
            "motion.csv",
            topic(
                "u,r,n",
                fast.map(|t| (t, format!("1,{},{}", 0.1 * PI, (t * 7.3).sin()))),
            ),
        );
        w(
            "heading.csv",
            topic(
                heading_header,
                (0..=60).map(|k| (f64::from(k), heading(f64::from(k)))),
            ),
        );
        let manifest = format!(
            "[sources.m]\nfile = \"motion.csv\"\ntime = [\"secs\", \"nsecs\"]\n\
             [sources.h]\nfile = \"heading.csv\"\ntime = [\"secs\", \"nsecs\"]\n\
             [signals]\nu = \"m:u\"\nr = \"m:r\"\nn = \"m:n\"\n{extra}"
        );
        w("log.toml", manifest);
    }

    fn psi_of(loaded: &LoadedFile) -> Vec<f64> {
        loaded
            .experiments
            .iter()
            .flat_map(|e| e.heading.clone())
            .collect()
    }

    /// The heading turning at 18°/s from 0, as the model reads it (rad).
    fn truth(k: usize) -> f64 {
        let t = k as f64 * 0.1;
        let a = (0.1 * PI * t).rem_euclid(2.0 * PI);
        if a > PI { a - 2.0 * PI } else { a }
    }

    fn close_as_angles(got: &[f64]) {
        assert_eq!(got.len(), 601);
        for (k, g) in got.iter().enumerate() {
            let e = leeway_data::rates::short_arc(truth(k), *g);
            assert!(e.abs() < 1e-9, "sample {k}: {g} against {}", truth(k));
        }
    }

    #[test]
    fn a_heading_in_degrees_is_interpolated_along_the_short_arc_of_degrees() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        // Wrapped at ±180°, 18° between samples: radians' short arc (3.14)
        // would take every step in degrees for a wrap.
        write_log(
            dir.path(),
            "psi",
            |t| {
                let a = (18.0 * t).rem_euclid(360.0);
                format!("{}", if a > 180.0 { a - 360.0 } else { a })
            },
            "psi = \"h:psi\"\n",
        );
        let ir = model("data { psi in deg }");
        let loaded = load_log(&dir.path().join("log.toml"), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        close_as_angles(&psi_of(&loaded));
        // As a compass writes it, 0–360°, in the same unit.
        write_log(
            dir.path(),
            "psi",
            |t| format!("{}", (18.0 * t).rem_euclid(360.0)),
            "psi = \"h:psi\"\n",
        );
        let loaded = load_log(&dir.path().join("log.toml"), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        close_as_angles(&psi_of(&loaded));
    }

    #[test]
    fn an_enu_quaternion_gives_the_marine_heading_and_a_scalar_yaw_is_refused() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let q = |t: f64| {
            let yaw = PI / 2.0 - 0.1 * PI * t;
            format!("0,0,{},{}", (yaw / 2.0).sin(), (yaw / 2.0).cos())
        };
        let header = "q.x,q.y,q.z,q.w";
        write_log(
            dir.path(),
            header,
            q,
            "psi = { from = \"h:q\", as = \"yaw\", frame = \"enu\" }\n",
        );
        let ir = model("");
        let loaded = load_log(&dir.path().join("log.toml"), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        close_as_angles(&psi_of(&loaded));
        // The quaternion's z alone, mapped as a yaw: refused, never read.
        write_log(
            dir.path(),
            "q",
            |t| format!("{}", (0.05 * PI * t).sin()),
            "psi = { from = \"h:q\", as = \"yaw\", frame = \"ned\" }\n",
        );
        let e = load_log(&dir.path().join("log.toml"), &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("a scalar yaw is refused"));
        assert!(e.message.contains("is one column"), "{e}");
        assert!(e.location.ends_with("log.toml:11:7"), "{e}");
    }

    #[test]
    fn an_option_against_the_manifests_value_is_located_at_that_value() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        write_log(
            dir.path(),
            "psi",
            |t| format!("{}", 0.1 * t),
            "psi = \"h:psi\"\n",
        );
        let path = dir.path().join("log.toml");
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(
            &path,
            format!("experiment = \"a\"\nstep = 0.2\n  max_gap = 2.0\n{text}"),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let error = |options: &LoadOptions| {
            load_log(&path, &model(""), options)
                .err()
                .unwrap_or_else(|| panic!("refused"))
        };
        let gap = LoadOptions {
            max_gap: leeway_data::gaps::GapLimit::Seconds(1.0),
            ..LoadOptions::default()
        };
        let e = error(&gap);
        assert!(e.location.ends_with("log.toml:3:13"), "{e}");
        assert!(e.message.contains("--max-gap (1 s) conflicts"), "{e}");
        let resample = LoadOptions {
            resample: Some(0.1),
            ..LoadOptions::default()
        };
        let e = error(&resample);
        assert!(e.location.ends_with("log.toml:2:8"), "{e}");
        // The manifest's step against the model's: at the step.
        let e = error(&LoadOptions::default());
        assert!(e.location.ends_with("log.toml:2:8"), "{e}");
        assert!(
            e.message.contains("differs from the model's sample time"),
            "{e}"
        );
    }

    #[test]
    fn windows_keep_their_stretches_and_one_keeping_nothing_is_named() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let psi = |t: f64| format!("{}", truth((t * 10.0).round() as usize));
        write_log(
            dir.path(),
            "psi",
            psi,
            "psi = \"h:psi\"\n[[keep]]\nfrom = 2\nto = 20\n[[keep]]\nwhen = \"m:u\"\nmin = 0.5\nfrom = 40\n",
        );
        let ir = model("");
        let loaded = load_log(&dir.path().join("log.toml"), &ir, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let spans: Vec<(f64, f64, usize)> = loaded.notes.experiments[0]
            .pieces
            .iter()
            .map(|p| (p.from, p.to, p.samples))
            .collect();
        assert_eq!(spans, [(2.0, 20.0, 181), (40.0, 60.0, 201)]);
        let names: Vec<&str> = loaded.experiments.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["log/1", "log/2"]);
        write_log(
            dir.path(),
            "psi",
            psi,
            "psi = \"h:psi\"\n[[keep]]\nfrom = 70\n",
        );
        let e = load_log(&dir.path().join("log.toml"), &ir, &LoadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("a window beyond the log is refused"));
        assert!(e.message.contains("keeps nothing"), "{e}");
        assert!(e.location.ends_with("log.toml:12:1"), "{e}");
    }
}
