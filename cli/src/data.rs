//! Data files for a command: loaded or streamed, every failing file reported, and what loading noted.
//! `estimate` streams them ([`DataSet::Streamed`], or [`DataSet::Held`] under
//! `--resample`); `validate` loads them.

use crate::problem::{Failure, Problem};
use leeway_data::{FileNotes, FileSource, LoadOptions};
use leeway_estimate::parallel::{in_order, threads_for};
use leeway_logs::{load_path, open_path};
use leeway_model::{Experiment, Source};
use leeway_structure::ir::Ir;
use std::path::PathBuf;

/// Loads every data file (CSV, or Parquet: extension `.parquet` or the
/// magic `PAR1`); all files are read and every failing one reported.
/// What was noted while reading (comment lines, jitter, resampling) comes back
/// per file, for the output.
pub fn load_data(
    ir: &Ir,
    files: &[PathBuf],
    options: &LoadOptions,
) -> Result<(Vec<Experiment>, Vec<FileNotes>), Failure> {
    load_files(ir, files, options).map(|(e, n)| (e.experiments, n))
}

/// Experiments held in memory, each with its file as messages name it.
struct Held {
    experiments: Vec<Experiment>,
    files: Vec<String>,
}

/// Every file read with `read`, in order; every failing one reported.
fn each_file<T>(
    files: &[PathBuf],
    read: impl FnMut(&PathBuf) -> Result<T, leeway_data::DataError>,
) -> Result<Vec<T>, Failure> {
    every_one(files.iter().map(read).collect())
}

/// [`each_file`] with the files read side by side, one a core: opening a
/// file is one validating pass on one thread (Parquet's decoding, the spill
/// copy), so a campaign of many files would otherwise open on one core while
/// the others wait. Files and problems come back in file order, as from
/// [`each_file`]; each file is opened as it is alone.
fn each_file_side_by_side<T: Send>(
    files: &[PathBuf],
    read: impl Fn(&PathBuf) -> Result<T, leeway_data::DataError> + Sync,
) -> Result<Vec<T>, Failure> {
    let threads = threads_for(files.len());
    every_one(in_order(files.len(), threads, |i| read(&files[i])))
}

/// The files read, or every problem met, in file order.
fn every_one<T>(results: Vec<Result<T, leeway_data::DataError>>) -> Result<Vec<T>, Failure> {
    let mut read_files = Vec::with_capacity(results.len());
    let mut problems = Vec::new();
    for result in results {
        match result {
            Ok(f) => read_files.push(f),
            Err(e) => problems.push(Problem::data(&e)),
        }
    }
    if problems.is_empty() {
        Ok(read_files)
    } else {
        Err(Failure::Problems(problems))
    }
}

/// [`load_data`], with each experiment's file.
fn load_files(
    ir: &Ir,
    files: &[PathBuf],
    options: &LoadOptions,
) -> Result<(Held, Vec<FileNotes>), Failure> {
    let loaded = each_file(files, |path| {
        load_path(path, ir, options).map(|f| (path.display().to_string(), f))
    })?;
    let mut held = Held {
        experiments: Vec::new(),
        files: Vec::new(),
    };
    let mut notes = Vec::with_capacity(loaded.len());
    for (name, f) in loaded {
        held.files
            .extend(f.experiments.iter().map(|_| name.clone()));
        held.experiments.extend(f.experiments);
        notes.push(f.notes);
    }
    let sources: Vec<&dyn Source> = held.experiments.iter().map(|e| e as &dyn Source).collect();
    check_dead_times(ir, &sources, &held.files)?;
    Ok((held, notes))
}

/// Every experiment's sample time holds the model's dead times in whole
/// samples (a dead time in seconds on a model without `step`); every
/// record where it does not is reported, located at its file.
fn check_dead_times(ir: &Ir, sources: &[&dyn Source], files: &[String]) -> Result<(), Failure> {
    let problems: Vec<Problem> = sources
        .iter()
        .zip(files)
        .filter_map(|(e, file)| {
            leeway_model::delay::dead_times(ir, e.name(), e.step())
                .err()
                .map(|d| {
                    Problem::error("invalid-delay", d.to_string())
                        .at(file.as_str())
                        .help("declare the dead time in steps, or in seconds that are a whole number of every record's sample time (or resample with --resample)")
                })
        })
        .collect();
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Failure::Problems(problems))
    }
}

/// Experiments for an estimate: streamed from their files (validated once,
/// then read on every pass from a binary copy, flat memory in N), or held in
/// memory under `--resample`, which interpolates over a whole experiment.
pub enum DataSet {
    /// Read per pass from the validated copy.
    Streamed(Vec<FileSource>),
    /// Loaded (resampled), with each experiment's file.
    Held(Vec<Experiment>, Vec<String>),
}

impl DataSet {
    /// Every experiment as a source, in file order.
    pub fn sources(&self) -> Vec<&dyn Source> {
        match self {
            DataSet::Streamed(v) => v.iter().map(|e| e as &dyn Source).collect(),
            DataSet::Held(v, _) => v.iter().map(|e| e as &dyn Source).collect(),
        }
    }
    /// Each experiment's file, as named in messages.
    pub fn files(&self) -> Vec<&str> {
        match self {
            DataSet::Streamed(v) => v.iter().map(FileSource::file).collect(),
            DataSet::Held(_, files) => files.iter().map(String::as_str).collect(),
        }
    }
    /// A problem met by a later pass (the validated copy could not be read).
    pub fn failure(&self) -> Option<Problem> {
        match self {
            DataSet::Streamed(v) => v
                .iter()
                .find_map(FileSource::failure)
                .map(|e| Problem::data(&e)),
            DataSet::Held(..) => None,
        }
    }
}

/// [`load_data`] for an estimate: streamed unless `--resample` is given.
pub fn open_data(
    ir: &Ir,
    files: &[PathBuf],
    options: &LoadOptions,
) -> Result<(DataSet, Vec<FileNotes>), Failure> {
    if options.resample.is_some() {
        return load_files(ir, files, options)
            .map(|(h, n)| (DataSet::Held(h.experiments, h.files), n));
    }
    let opened = each_file_side_by_side(files, |path| open_path(path, ir, options))?;
    let mut sources = Vec::new();
    let mut notes = Vec::with_capacity(opened.len());
    for f in opened {
        sources.extend(f.sources);
        notes.push(f.notes);
    }
    let set = DataSet::Streamed(sources);
    let files: Vec<String> = set.files().into_iter().map(str::to_string).collect();
    check_dead_times(ir, &set.sources(), &files)?;
    Ok((set, notes))
}

/// Below this relative step deviation, time stamps count as uniform: decimal
/// stamps such as 0.1·k carry rounding of order 1e-15.
const JITTER_FLOOR: f64 = 1e-6;

/// What loading did, one line each, for the text output: comment lines
/// skipped, jitter tolerated, experiments resampled.
pub fn data_notes(notes: &[FileNotes]) -> Vec<String> {
    let mut lines = Vec::new();
    for f in notes {
        let skipped = |n: usize, what: &str| {
            (n > 0).then(|| {
                let plural = if n == 1 { "" } else { "s" };
                format!("{}: {n} {what} line{plural} skipped", f.file)
            })
        };
        lines.extend(skipped(f.comment_lines, "comment"));
        lines.extend(skipped(f.blank_lines, "blank"));
        for e in &f.experiments {
            if let Some(n) = e.resampled {
                lines.push(format!(
                    "{}: experiment `{}` resampled from {} rows to {n} samples",
                    f.file, e.experiment, e.rows
                ));
            }
            if let Some(d) = e.max_step_deviation.filter(|d| *d > JITTER_FLOOR) {
                lines.push(format!(
                    "{}: experiment `{}` time steps deviate up to {:.2} % from the nominal step{}",
                    f.file,
                    e.experiment,
                    100.0 * d,
                    if e.resampled.is_some() {
                        " (before resampling)"
                    } else {
                        " (within --time-tolerance)"
                    }
                ));
            }
            lines.extend(split_notes(&f.file, e));
        }
        lines.extend(grid_notes(f));
    }
    lines
}

/// A joined log's signals read by their mean over the step, and its
/// stalls: what the grid did that picking one sample would not say.
fn grid_notes(f: &FileNotes) -> Vec<String> {
    use leeway_model::number::{short_number as num, time_number as time};
    let mut lines: Vec<String> = f
        .signals
        .iter()
        .filter(|s| {
            s.on_grid.starts_with("mean")
                || s.on_grid.starts_with("centred")
                || s.on_grid.contains("slower than the grid")
        })
        .map(|s| format!("{}: {}: {}", f.file, s.signal, s.on_grid))
        .collect();
    for e in &f.experiments {
        for g in e.stalls.iter().take(MAX_SPLIT_LINES) {
            lines.push(format!(
                "{}: {} stalled from t = {} to {} s ({} s, beyond {} s but within the gap limit): {} across",
                f.file,
                g.signal.as_deref().unwrap_or("a signal"),
                time(g.from),
                time(g.to),
                num(g.to - g.from),
                num(g.limit),
                "held or interpolated"
            ));
        }
        if e.stalls.len() > MAX_SPLIT_LINES {
            lines.push(format!(
                "{}: … and {} more stalls (--json lists them all)",
                f.file,
                e.stalls.len() - MAX_SPLIT_LINES
            ));
        }
    }
    lines
}

/// Most lines of gaps, and of pieces, a file's notes print (`--json` lists all).
const MAX_SPLIT_LINES: usize = 8;

/// The gaps that split an experiment and the pieces they left, one line
/// each, at most [`MAX_SPLIT_LINES`] of each.
fn split_notes(file: &str, e: &leeway_data::TimeNotes) -> Vec<String> {
    use leeway_model::number::{short_number as num, time_number as time};
    let more = |n: usize, what: &str| {
        (n > MAX_SPLIT_LINES).then(|| {
            format!(
                "{file}: … and {} more {what} (--json lists them all)",
                n - MAX_SPLIT_LINES
            )
        })
    };
    let mut lines = Vec::new();
    for g in e.gaps.iter().take(MAX_SPLIT_LINES) {
        let what = g
            .signal
            .as_ref()
            .map_or(String::new(), |s| format!(" of {s}"));
        lines.push(format!(
            "{file}: experiment `{}` split: no samples{what} from t = {} to {} s ({} s, beyond the gap limit of {} s); not interpolated across",
            e.experiment,
            time(g.from),
            time(g.to),
            num(g.to - g.from),
            num(g.limit)
        ));
    }
    lines.extend(more(e.gaps.len(), "gaps"));
    for p in e.pieces.iter().take(MAX_SPLIT_LINES) {
        let span = format!("t = {} to {} s", time(p.from), time(p.to));
        lines.push(match &p.experiment {
            Some(name) => format!("{file}: `{name}`: {span}, {} samples", p.samples),
            None => format!(
                "{file}: dropped {span} of `{}`: {} samples, too few for an experiment",
                e.experiment, p.samples
            ),
        });
    }
    lines.extend(more(e.pieces.len(), "pieces"));
    lines
}
