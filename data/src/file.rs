//! Data files by path: CSV or Parquet, chosen by extension or magic bytes.

use crate::csv_fast::CsvFile;
use crate::error::DataError;
use crate::notes::LoadedFile;
use crate::options::LoadOptions;
use crate::spill::{StreamedFile, open_table};
use crate::validate::{Table, load_table};
use leeway_structure::ir::Ir;
use std::path::Path;

/// Reads a data file as a [`Table`] and hands it to `f`: a Parquet file
/// (extension `.parquet` or the magic bytes `PAR1`, with the `parquet`
/// feature), else CSV text ([`CsvFile`]: parsed in parallel, bit for bit as
/// [`Records`](crate::csv::Records) reads it). `what` names the option that
/// gave the file.
pub fn with_table<T>(
    path: &Path,
    what: &str,
    f: impl FnOnce(&mut dyn Table) -> Result<T, DataError>,
) -> Result<T, DataError> {
    #[cfg(feature = "parquet")]
    if crate::parquet::is_parquet(path) {
        return f(&mut crate::parquet::ParquetFile::open(path)?);
    }
    #[cfg(not(feature = "parquet"))]
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"))
    {
        return Err(DataError::new(
            path.display().to_string(),
            "this leeway was built without Parquet support",
            "build it with the cargo feature `parquet` (of `leeway` or `leeway-data`; leeway-cli has it by default), or convert the file to CSV",
        ));
    }
    f(&mut CsvFile::open(path, what)?)
}

/// Loads a data file, CSV or Parquet (see [`with_table`]), into memory with
/// what was noted ([`load_csv_noted`](crate::csv_fast::load_csv_noted) for CSV).
pub fn load_file_noted(
    path: &Path,
    ir: &Ir,
    options: &LoadOptions,
) -> Result<LoadedFile, DataError> {
    with_table(path, "--data", |t| load_table(t, ir, options))
}

/// Opens a data file, CSV or Parquet (see [`with_table`]), for streaming
/// ([`open_csv`](crate::csv_fast::open_csv) for CSV).
pub fn open_file(path: &Path, ir: &Ir, options: &LoadOptions) -> Result<StreamedFile, DataError> {
    with_table(path, "--data", |t| open_table(t, ir, options))
}
