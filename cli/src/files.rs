//! Reading files the user names: text and model sources, with located IO
//! errors; and creating the files the CLI writes, never through a symbolic link.

use crate::problem::Problem;
use leeway_structure::grammar;
use leeway_structure::grammar::source::Refused;
use std::path::Path;

/// The most bytes of a parameter file (`--params`, `--nominal`): 64 MiB,
/// room for an estimate's document with its covariance, far below memory.
pub const MAX_PARAMS_BYTES: u64 = 64 << 20;

/// Reads a text file of at most `limit` bytes; a problem names the path
/// and what went wrong. A larger regular file is refused by its size before
/// it is read, and at most `limit + 1` bytes are read from anything else (a
/// pipe, a device: `/dev/zero` costs `limit`, not all memory).
pub fn read_text(path: &Path, what: &str, limit: u64) -> Result<String, Problem> {
    use std::io::Read;
    let file = path.display().to_string();
    let refused = |reason: String| {
        Problem::error("io", format!("cannot read {what} `{file}`: {reason}")).at(&file)
    };
    let io = |e: std::io::Error| {
        refused(match e.kind() {
            std::io::ErrorKind::NotFound => "no such file".to_string(),
            std::io::ErrorKind::IsADirectory => "it is a directory".to_string(),
            _ => e.to_string(),
        })
    };
    let larger =
        |size: String| refused(format!("it is larger than {} ({size})", bytes_text(limit)));
    let handle = std::fs::File::open(path).map_err(io)?;
    let size = handle.metadata().map_err(io)?.len();
    if size > limit {
        return Err(larger(format!("{size} bytes")));
    }
    let mut bytes = Vec::new();
    handle.take(limit + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(larger("it goes on past that".to_string()));
    }
    String::from_utf8(bytes).map_err(|_| refused("it is not UTF-8 text".to_string()))
}

/// A limit in words: `1 MiB`, `64 MiB`.
fn bytes_text(limit: u64) -> String {
    match limit {
        l if l % (1 << 20) == 0 => format!("{} MiB", l >> 20),
        l => format!("{l} bytes"),
    }
}

/// Reads a model file: its size is checked before reading (a file over
/// [`grammar::MAX_SOURCE_BYTES`] is never read whole: at most one byte more is
/// read), then the bytes are decoded, a non-UTF-8 file refused with the
/// line and column of its first invalid byte. `Err` is an IO failure.
pub fn read_model(path: &Path) -> std::io::Result<Result<String, Box<Refused>>> {
    use std::io::Read;
    let file = std::fs::File::open(path)?;
    let size = file.metadata()?.len();
    let limit = grammar::MAX_SOURCE_BYTES as u64;
    if size > limit {
        return Ok(Err(Box::new(Refused {
            text: String::new(),
            diagnostic: grammar::source::too_large(size),
        })));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes)?;
    Ok(grammar::source::decode(bytes))
}

/// Why a model file cannot be read, as the CLI says it.
pub fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".to_string(),
        std::io::ErrorKind::IsADirectory => "it is a directory".to_string(),
        _ => e.to_string(),
    }
}

/// Opens an output file for writing without following a symbolic link: a
/// link in the way is refused (`Err` of kind `InvalidInput` naming it), a
/// regular file is removed and created anew (`create_new`: a link put there
/// in between makes it fail rather than be followed), a device or a pipe
/// (`--out /dev/stdout`) is written in place.
pub fn create_output(path: &Path) -> std::io::Result<std::fs::File> {
    use std::io::{Error, ErrorKind};
    let fresh = || {
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
    };
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => Err(Error::new(
            ErrorKind::InvalidInput,
            "it is a symbolic link, and leeway never writes through one",
        )),
        Ok(m) if m.is_dir() => Err(Error::new(ErrorKind::IsADirectory, "it is a directory")),
        Ok(m) if m.is_file() => {
            std::fs::remove_file(path)?;
            fresh()
        }
        Ok(_) => std::fs::OpenOptions::new()
            .write(true)
            .truncate(true)
            .open(path),
        Err(e) if e.kind() == ErrorKind::NotFound => fresh(),
        Err(e) => Err(e),
    }
}

/// Writes `bytes` into `path` through [`create_output`], every write checked.
pub fn write_output(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let mut file = create_output(path)?;
    file.write_all(bytes)?;
    file.flush()
}
