//! A log read as written: its manifest (or a bag whose topics the model's
//! `data { }` block names), every source read once, the signals joined on
//! the grid, and the joined samples handed to leeway-data's one validating
//! pass — units, outliers, minimum lengths — loaded or streamed like any
//! data file.

use crate::join::{Between, Joined, Track, join, seconds};
use crate::manifest::{Clock, Interpolate, Manifest, SignalSpec, SourceSpec};
use crate::series::{Series, read_table};
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
            SignalSpec {
                yaw: role == Role::Heading && field.ends_with("orientation"),
                signal,
                source: 0,
                field,
                interpolate: None,
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
        max_gap: None,
        sources: vec![SourceSpec {
            key: "bag".into(),
            file: path.to_path_buf(),
            clock: Clock::Bag,
            at: file,
        }],
        signals,
    })
}

/// Reads and joins the log at `path`.
fn joined(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<JoinedLog, DataError> {
    let m = manifest(path, ir)?;
    let specs = match_model(&m, ir)?;
    let h = grid_step(&m, ir, options)?;
    let limit = m.max_gap.unwrap_or(options.max_gap);
    let series = read_signals(&m, &specs)?;
    // A quaternion's yaw is in radians: stated in the signal's declared
    // unit, so that the validating pass converts it back exactly once.
    let values: Vec<Vec<f64>> = series
        .iter()
        .zip(&specs)
        .map(|(s, (spec, _))| {
            let factor = if spec.yaw {
                unit_factor(ir, &spec.signal)
            } else {
                1.0
            };
            s.values[0].iter().map(|v| v / factor).collect()
        })
        .collect();
    let mut tracks = Vec::with_capacity(series.len());
    let mut signals = Vec::with_capacity(series.len());
    for ((s, (spec, role)), values) in series.iter().zip(&specs).zip(&values) {
        let steps: Vec<f64> = s
            .stamps
            .windows(2)
            .map(|w| (w[1] - w[0]) as f64 / 1e9)
            .collect();
        let between = between(spec, role);
        tracks.push(Track {
            signal: &spec.signal,
            stamps: &s.stamps,
            values,
            between,
            limit: limit.seconds(&steps, h) * 1e9,
        });
        signals.push(signal_note(&m, spec, s, &steps, between));
    }
    let joined = join(&tracks, h, &m.experiment);
    check_joined(&m, &joined, &tracks)?;
    for (note, t) in signals.iter_mut().zip(&tracks) {
        note.first = seconds(t.stamps[0], joined.origin);
        note.last = seconds(t.stamps[t.stamps.len() - 1], joined.origin);
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

/// Every mapped signal's series, in the order of `specs`, each source read
/// once; a signal with fewer than two samples is an error.
fn read_signals(m: &Manifest, specs: &[(&SignalSpec, Role)]) -> Result<Vec<Series>, DataError> {
    let mut series: Vec<(Series, usize)> = Vec::with_capacity(specs.len());
    for (s, source) in m.sources.iter().enumerate() {
        let wanted: Vec<usize> = (0..specs.len())
            .filter(|k| specs[*k].0.source == s)
            .collect();
        if wanted.is_empty() {
            continue;
        }
        let asked: Vec<&SignalSpec> = wanted.iter().map(|k| specs[*k].0).collect();
        series.extend(read_source(source, &asked)?.into_iter().zip(wanted));
    }
    series.sort_by_key(|(_, k)| *k);
    for (s, k) in &series {
        let spec = specs[*k].0;
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
fn signal_note(
    m: &Manifest,
    spec: &SignalSpec,
    s: &Series,
    steps: &[f64],
    between: Between,
) -> SignalNote {
    SignalNote {
        signal: spec.signal.clone(),
        source: format!("{}:{}", m.sources[spec.source].file.display(), spec.field),
        samples: s.stamps.len(),
        median_step: leeway_data::gaps::median(steps).unwrap_or(0.0),
        first: 0.0,
        last: 0.0,
        repeated_stamps: s.repeated,
        between: match between {
            Between::Hold => "hold",
            Between::Linear => "linear",
            Between::Angle => "angle",
        }
        .into(),
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
            ..TimeNotes::default()
        }],
        origin: Some(crate::stamps::iso(joined.origin)),
        signals,
        ..FileNotes::default()
    }
}

/// How a signal is read between samples: a command held, a measurement
/// interpolated (a heading along the short arc), unless the manifest says.
fn between(spec: &SignalSpec, role: &Role) -> Between {
    match (spec.interpolate, role) {
        (Some(Interpolate::Hold), _) => Between::Hold,
        (Some(Interpolate::Linear), Role::Heading) | (None, Role::Heading) => Between::Angle,
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
            &m.file,
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
    if source.clock == Clock::Bag {
        return crate::bag_source::read(source, wanted);
    }
    let fields: Vec<String> = wanted.iter().map(|s| s.field.clone()).collect();
    let all = leeway_data::with_table(&source.file, "--data", |t| read_table(t, source, &fields))?;
    Ok((0..fields.len())
        .map(|j| Series {
            file: all.file.clone(),
            stamps: all.stamps.clone(),
            values: vec![all.values[j].clone()],
            repeated: all.repeated,
        })
        .collect())
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
        leeway_data::load_file_noted(path, ir, options)
    }
}

/// Opens any data file for streaming, as [`load_path`] loads it.
pub fn open_path(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<StreamedFile, DataError> {
    if is_log(path) {
        open_log(path, ir, options)
    } else {
        leeway_data::open_file(path, ir, options)
    }
}
