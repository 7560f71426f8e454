//! Frames handed over from Python, read by leeway-data's column table
//! (`leeway_data::Columns`), which feeds the same validating
//! pass as `leeway estimate --data`: the same header matching, units,
//! time-step checks, experiment splitting, outlier rules and errors, located
//! by positional row (`frame: row R, column `c``, R from 0 as `iloc`).
//!
//! The columns are borrowed from numpy without copying and read as they
//! are: no text pass, and the values bit for bit those a CSV file of the
//! same numbers would give. An estimate holds frames up to [`HELD_BYTES`]
//! and streams larger ones through the spill, so its memory is flat in the
//! rows.

use crate::failure::Failure;
use leeway_data::Columns;
use leeway_data::DataError;
use leeway_data::FileNotes;
use leeway_data::FileSource;
use leeway_data::Labels;
use leeway_data::LoadOptions;
use leeway_data::columns;
use leeway_data::load_table;
use leeway_data::open_table;
use leeway_estimate::EstimateError;
use leeway_model::Experiment;
use leeway_model::Source;
use leeway_model::interrupt::Interrupt;
use leeway_structure::ir::Ir;
use numpy::PyReadonlyArray1;

/// One frame: its name (the "file" of messages and of the experiment name
/// when it has no experiment column), float64 columns, experiment labels.
pub struct Frame<'a> {
    /// As named in messages.
    pub name: &'a str,
    /// The model's columns the frame has, by data column name.
    pub columns: Vec<(&'a str, &'a [f64])>,
    /// The experiment column's labels.
    pub experiment: Option<Labels<'a>>,
}

/// The data columns a model reads (after `data { }` mapping), time first:
/// only these are handed over, so other columns of a frame (notes, labels)
/// are ignored as the CSV loader ignores them.
pub fn model_columns(ir: &Ir) -> Vec<String> {
    leeway_data::columns::model_columns(ir)
}

/// Every frame's experiments, in order, with what loading noted; the first
/// failing frame raises.
pub fn load(
    ir: &Ir,
    frames: &[Frame<'_>],
    options: &LoadOptions,
) -> Result<(Vec<Experiment>, Vec<FileNotes>), Failure> {
    load_asking(ir, frames, options, None)
}

/// A frame's validating pass, `interrupt` asked as it reads (`None`: never).
fn read<'a, T>(
    ir: &Ir,
    frame: &Frame<'a>,
    interrupt: Option<&Interrupt>,
    pass: impl FnOnce(&mut Columns<'a>) -> Result<T, DataError>,
) -> Result<T, Failure> {
    let stopped = |e: DataError| match interrupt {
        // Ctrl-C, raised as Python's KeyboardInterrupt (failure.rs).
        Some(i) if i.requested() => Failure::estimate(&EstimateError {
            code: "interrupted",
            message: e.message,
            hint: e.hint,
        }),
        _ => Failure::data(&e),
    };
    let mut table = columns::frame(frame.name, &frame.columns, frame.experiment, ir)
        .map_err(|e| Failure::data(&e))?
        .interruptible(interrupt.cloned());
    pass(&mut table).map_err(stopped)
}

/// [`load`], asking `interrupt` while reading.
fn load_asking(
    ir: &Ir,
    frames: &[Frame<'_>],
    options: &LoadOptions,
    interrupt: Option<&Interrupt>,
) -> Result<(Vec<Experiment>, Vec<FileNotes>), Failure> {
    let mut experiments = Vec::new();
    let mut notes = Vec::new();
    for frame in frames {
        let loaded = read(ir, frame, interrupt, |t| load_table(t, ir, options))?;
        experiments.extend(loaded.experiments);
        notes.push(loaded.notes);
    }
    Ok((experiments, notes))
}

/// Frames up to this size (rows × the model's columns × 8 bytes) are held
/// in memory, where an estimate's passes keep what they compute (faster
/// refinements); larger ones are streamed, so memory stays flat in the rows.
pub const HELD_BYTES: usize = 64 << 20;

/// Frames as an estimate reads them: held, or streamed through a spill file.
pub enum Loaded {
    /// In memory (small frames, or `resample`, which needs the whole record).
    Held(Vec<Experiment>),
    /// Validated once, then read back from a temporary binary copy on every
    /// pass, as the CLI streams its data files.
    Streamed(Vec<FileSource>),
}

impl Loaded {
    /// A problem a later pass met reading a streamed frame's spill back (it
    /// then stopped short): whatever was computed from it is void.
    pub fn failure(&self) -> Option<Failure> {
        match self {
            Loaded::Held(_) => None,
            Loaded::Streamed(v) => v
                .iter()
                .find_map(FileSource::failure)
                .map(|e| Failure::data(&e)),
        }
    }

    /// Every experiment, in frame order.
    pub fn sources(&self) -> Vec<&dyn Source> {
        match self {
            Loaded::Held(v) => v.iter().map(|e| e as &dyn Source).collect(),
            Loaded::Streamed(v) => v.iter().map(|e| e as &dyn Source).collect(),
        }
    }
}

/// Every frame's experiments for an estimate: held when small or resampled,
/// else streamed (the same validation, the same values bit for bit).
pub fn load_for_estimate(
    ir: &Ir,
    frames: &[Frame<'_>],
    options: &LoadOptions,
    interrupt: Option<&Interrupt>,
) -> Result<(Loaded, Vec<FileNotes>), Failure> {
    let bytes: usize = frames
        .iter()
        .map(|f| 8 * f.columns.len() * f.columns.first().map_or(0, |(_, c)| c.len()))
        .sum();
    if options.resample.is_some() || bytes <= HELD_BYTES {
        return load_asking(ir, frames, options, interrupt).map(|(e, n)| (Loaded::Held(e), n));
    }
    let mut sources = Vec::new();
    let mut notes = Vec::new();
    for frame in frames {
        let opened = read(ir, frame, interrupt, |t| open_table(t, ir, options))?;
        sources.extend(opened.sources);
        notes.push(opened.notes);
    }
    Ok((Loaded::Streamed(sources), notes))
}

/// A frame as `leeway` hands it over: name, float64 columns, and the
/// experiment labels coded (`pandas.factorize`: a code per row, the names).
pub(crate) type FrameArg<'py> = (
    String,
    Vec<(String, PyReadonlyArray1<'py, f64>)>,
    Option<(PyReadonlyArray1<'py, i64>, Vec<String>)>,
);

/// The frames' columns borrowed in place (`leeway` hands over contiguous
/// float64 arrays).
pub(crate) fn borrow_frames<'a>(frames: &'a [FrameArg<'_>]) -> Result<Vec<Frame<'a>>, Failure> {
    frames
        .iter()
        .map(|(name, columns, experiment)| {
            let columns = columns
                .iter()
                .map(|(c, a)| {
                    a.as_slice().map(|s| (c.as_str(), s)).map_err(|_| {
                        Failure::data_plain(
                            name,
                            format!("column `{c}` is not a contiguous float64 array"),
                        )
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            let experiment = match experiment {
                Some((codes, names)) => Some(leeway_data::Labels::Coded {
                    codes: codes.as_slice().map_err(|_| {
                        Failure::data_plain(
                            name,
                            "the experiment codes are not a contiguous int64 array".into(),
                        )
                    })?,
                    names,
                }),
                None => None,
            };
            Ok(Frame {
                name,
                columns,
                experiment,
            })
        })
        .collect()
}
