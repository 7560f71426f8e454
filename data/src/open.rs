//! Opening a data file by path, or one located error.

use crate::error::DataError;
use std::path::Path;

/// Opens a data file (`what` names the option that gave it, for the hint).
pub(crate) fn open_path(path: &Path, what: &str) -> Result<(String, std::fs::File), DataError> {
    let file = path.display().to_string();
    match std::fs::File::open(path) {
        Ok(handle) => Ok((file, handle)),
        Err(e) => Err(DataError::new(
            &file,
            format!("cannot read the file: {e}"),
            format!("check the path passed to {what}"),
        )),
    }
}
