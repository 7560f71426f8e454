//! The MCAP container, record by record, in one pass: every length read
//! from the file is bounded by the bytes the file has left before anything
//! is allocated for it, and every checksum the format carries is verified
//! (the data section's, in `DataEnd`; each chunk's; each attachment's; the
//! summary's, in the footer). A CRC of 0 means "not computed" and is skipped.
//!
//! Chunks are decompressed by the `mcap` crate's reader, fed one chunk at a
//! time with a record-length limit of that chunk's bound, so that a damaged
//! length inside a chunk cannot ask for more either.

use std::io::Read;

use crc32fast::Hasher;
use leeway_data::error::DataError;
use mcap::McapError;
use mcap::records::{Record, op};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};

/// Bytes asked of the file at once.
const READ_SIZE: usize = 1 << 20;

/// A record (or a chunk's records, uncompressed) longer than this is
/// corrupt: images and point clouds are far smaller.
pub const RECORD_LIMIT: u64 = 1 << 30;

/// A chunk's records, uncompressed, are at most this many times its
/// compressed bytes (zstd and lz4 on ROS messages give 2 to 20)…
pub const CHUNK_RATIO: u64 = 1024;

/// … or this many bytes, whichever is larger (and at most [`RECORD_LIMIT`]).
pub const CHUNK_FLOOR: u64 = 16 << 20;

const HINT: &str = "copy the file again, or recover what is intact with `mcap recover`";

/// The part of the file being read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Section {
    Data,
    Summary,
}

/// A record's name, for errors.
fn record_name(opcode: u8) -> String {
    match opcode {
        op::HEADER => "Header".into(),
        op::FOOTER => "Footer".into(),
        op::SCHEMA => "Schema".into(),
        op::CHANNEL => "Channel".into(),
        op::MESSAGE => "Message".into(),
        op::CHUNK => "Chunk".into(),
        op::MESSAGE_INDEX => "MessageIndex".into(),
        op::CHUNK_INDEX => "ChunkIndex".into(),
        op::ATTACHMENT => "Attachment".into(),
        op::ATTACHMENT_INDEX => "AttachmentIndex".into(),
        op::STATISTICS => "Statistics".into(),
        op::METADATA => "Metadata".into(),
        op::METADATA_INDEX => "MetadataIndex".into(),
        op::SUMMARY_OFFSET => "SummaryOffset".into(),
        op::DATA_END => "DataEnd".into(),
        other => format!("opcode {other:#04x}"),
    }
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    let mut word = [0; 8];
    if let Some(slice) = bytes.get(at..at + 8) {
        word.copy_from_slice(slice);
    }
    u64::from_le_bytes(word)
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    let mut word = [0; 4];
    if let Some(slice) = bytes.get(at..at + 4) {
        word.copy_from_slice(slice);
    }
    u32::from_le_bytes(word)
}

/// An MCAP file being read: its bytes from `source`, `len` of them.
pub struct Container<R> {
    source: R,
    file: String,
    len: u64,
    /// Bytes read so far: the offset of the next.
    offset: u64,
    /// The running CRC of the section being read.
    hasher: Hasher,
    /// A record's content (schemas, channels, messages outside chunks).
    buffer: Vec<u8>,
}

impl<R: Read> Container<R> {
    /// The file shown as `file`, `len` bytes long, read from `source`.
    pub fn new(source: R, file: String, len: u64) -> Container<R> {
        Container {
            source,
            file,
            len,
            offset: 0,
            hasher: Hasher::new(),
            buffer: Vec::new(),
        }
    }

    /// An error about the record at `offset`.
    pub fn error(&self, offset: u64, message: impl std::fmt::Display) -> DataError {
        DataError::new(&self.file, format!("{message} (offset {offset})"), HINT)
    }

    fn not_mcap(&self) -> DataError {
        DataError::new(
            &self.file,
            "not an MCAP file: no MCAP magic where it starts (offset 0)",
            "leeway reads ROS 2 bags stored as MCAP: the .mcap file in the bag's folder \
             (sqlite3 .db3 bags: `ros2 bag convert` them to MCAP)",
        )
    }

    fn left(&self) -> u64 {
        self.len.saturating_sub(self.offset)
    }

    /// Fills `out` from the file, unhashed.
    fn fill_raw(&mut self, out: &mut [u8]) -> Result<(), DataError> {
        self.source.read_exact(out).map_err(|e| {
            DataError::new(
                &self.file,
                format!("cannot read the bag at offset {}: {e}", self.offset),
                "check the file system (was the file changed while it was read?)",
            )
        })?;
        self.offset += out.len() as u64;
        Ok(())
    }

    /// Fills `out` from the file, hashed into the section's CRC.
    fn fill(&mut self, out: &mut [u8]) -> Result<(), DataError> {
        self.fill_raw(out)?;
        self.hasher.update(out);
        Ok(())
    }

    /// Skips `n` bytes (hashed), each piece also passed to `also`.
    fn skip(&mut self, n: u64, mut also: Option<&mut Hasher>) -> Result<(), DataError> {
        let mut piece = vec![0; READ_SIZE.min(usize::try_from(n).unwrap_or(READ_SIZE))];
        let mut left = n;
        while left > 0 {
            let k = piece
                .len()
                .min(usize::try_from(left).unwrap_or(piece.len()));
            self.fill(&mut piece[..k])?;
            if let Some(hasher) = also.as_deref_mut() {
                hasher.update(&piece[..k]);
            }
            left -= k as u64;
        }
        Ok(())
    }

    /// Reads every record, passing schemas, channels and messages (those
    /// of the chunks too) to `visit` with the offset of their record (or
    /// of their chunk).
    pub fn read(
        &mut self,
        mut visit: impl FnMut(Record<'_>, u64) -> Result<(), DataError>,
    ) -> Result<(), DataError> {
        let mut magic = [0; 8];
        if self.len < 8 {
            return Err(self.not_mcap());
        }
        self.fill(&mut magic)?;
        if magic != mcap::MAGIC {
            return Err(self.not_mcap());
        }
        let mut section = Section::Data;
        loop {
            let at = self.offset;
            if self.left() < 9 {
                return Err(self.error(
                    at,
                    if self.left() == 0 {
                        "the bag ends before its footer: it is truncated"
                    } else {
                        "the bag ends in the middle of a record: it is truncated"
                    },
                ));
            }
            let mut head = [0; 9];
            self.fill_raw(&mut head)?;
            let opcode = head[0];
            let len = u64_at(&head, 1);
            if len > self.left() {
                return Err(self.error(
                    at,
                    format!(
                        "a {} record declares {len} bytes, and the file has {} after its header: \
                         it is truncated, or the length is corrupt",
                        record_name(opcode),
                        self.left()
                    ),
                ));
            }
            match (opcode, section) {
                (op::DATA_END, Section::Data) => {
                    // The data section's CRC: every byte before this record.
                    let computed = std::mem::replace(&mut self.hasher, Hasher::new()).finalize();
                    if len < 4 {
                        return Err(self.error(at, format!("a DataEnd record of {len} bytes")));
                    }
                    let mut saved = [0; 4];
                    self.fill_raw(&mut saved)?;
                    let saved = u32::from_le_bytes(saved);
                    if saved != 0 && saved != computed {
                        return Err(self.error(at, "data section CRC mismatch"));
                    }
                    // Fields a later version may add, outside both sections.
                    self.skip(len - 4, None)?;
                    self.hasher = Hasher::new();
                    section = Section::Summary;
                    continue;
                }
                (op::FOOTER, Section::Summary) => {
                    self.hasher.update(&head);
                    return self.footer(at, len);
                }
                (op::DATA_END | op::FOOTER, _) => {
                    return Err(self.error(
                        at,
                        format!(
                            "a {} record where the {} section goes on",
                            record_name(opcode),
                            if section == Section::Data {
                                "data"
                            } else {
                                "summary"
                            }
                        ),
                    ));
                }
                (op::CHUNK | op::MESSAGE | op::ATTACHMENT, Section::Summary) => {
                    return Err(self.error(
                        at,
                        format!(
                            "a {} record after the data section's end",
                            record_name(opcode)
                        ),
                    ));
                }
                _ => {}
            }
            self.hasher.update(&head);
            match opcode {
                op::CHUNK => self.chunk(at, len, &mut visit)?,
                op::ATTACHMENT => self.attachment(at, len)?,
                op::SCHEMA | op::CHANNEL | op::MESSAGE => {
                    if len > RECORD_LIMIT {
                        return Err(self.error(
                            at,
                            format!(
                                "a {} record of {len} bytes, beyond leeway's limit of {RECORD_LIMIT}",
                                record_name(opcode)
                            ),
                        ));
                    }
                    let mut buffer = std::mem::take(&mut self.buffer);
                    // At most the bytes the file has left (checked above).
                    buffer.resize(len as usize, 0);
                    self.fill(&mut buffer)?;
                    let record = mcap::parse_record(opcode, &buffer).map_err(|e| {
                        self.error(at, format!("a corrupt {} record: {e}", record_name(opcode)))
                    })?;
                    visit(record, at)?;
                    self.buffer = buffer;
                }
                _ => self.skip(len, None)?,
            }
        }
    }

    /// The footer at `at` (its header hashed), its summary CRC, and the end magic.
    fn footer(&mut self, at: u64, len: u64) -> Result<(), DataError> {
        if len < 20 {
            return Err(self.error(at, format!("a Footer record of {len} bytes")));
        }
        let mut fields = [0; 20];
        self.fill_raw(&mut fields)?;
        // summary_start and summary_offset_start are under the CRC, the CRC is not.
        self.hasher.update(&fields[..16]);
        let computed = std::mem::replace(&mut self.hasher, Hasher::new()).finalize();
        let saved = u32_at(&fields, 16);
        if saved != 0 && saved != computed {
            return Err(self.error(at, "summary section CRC mismatch"));
        }
        self.skip(len - 20, None)?;
        let mut magic = [0; 8];
        if self.left() < 8 {
            return Err(self.error(
                self.offset,
                "the bag ends before its end magic: it is truncated",
            ));
        }
        self.fill_raw(&mut magic)?;
        if magic != mcap::MAGIC {
            return Err(self.error(
                self.offset - 8,
                "the MCAP magic after the footer is corrupt",
            ));
        }
        Ok(())
    }

    /// An attachment's content (`len` bytes after its header at `at`): its
    /// CRC covers all but its last 4 bytes, which hold it.
    fn attachment(&mut self, at: u64, len: u64) -> Result<(), DataError> {
        if len < 4 {
            return Err(self.error(at, format!("an Attachment record of {len} bytes")));
        }
        let mut crc = Hasher::new();
        self.skip(len - 4, Some(&mut crc))?;
        let mut saved = [0; 4];
        self.fill(&mut saved)?;
        let saved = u32::from_le_bytes(saved);
        if saved != 0 && saved != crc.finalize() {
            return Err(self.error(at, "attachment CRC mismatch"));
        }
        Ok(())
    }

    /// The chunk at `at` (`len` bytes after its header): its header checked
    /// against the file and the bound on its uncompressed size, then its
    /// records decompressed by `mcap` (CRC checked before any is passed on).
    fn chunk(
        &mut self,
        at: u64,
        len: u64,
        visit: &mut impl FnMut(Record<'_>, u64) -> Result<(), DataError>,
    ) -> Result<(), DataError> {
        // Start and end times, uncompressed size and CRC, the compression's
        // name (a length and its bytes), the compressed size.
        const FIXED: u64 = 8 + 8 + 8 + 4 + 4 + 8;
        const NAME_LIMIT: u64 = 64;
        if len < FIXED {
            return Err(self.error(at, format!("a Chunk record of {len} bytes")));
        }
        let mut header = vec![0; 32];
        self.fill(&mut header)?;
        let uncompressed = u64_at(&header, 16);
        let name_len = u64::from(u32_at(&header, 28));
        if name_len > NAME_LIMIT || FIXED + name_len > len {
            return Err(self.error(
                at,
                format!("a chunk's compression name of {name_len} bytes: the chunk is corrupt"),
            ));
        }
        header.resize(32 + name_len as usize + 8, 0);
        self.fill(&mut header[32..])?;
        let compressed = u64_at(&header, 32 + name_len as usize);
        let body = len - FIXED - name_len;
        if compressed > body {
            return Err(self.error(
                at,
                format!(
                    "a chunk declares {compressed} bytes of records, and holds {body}: it is corrupt"
                ),
            ));
        }
        let compression = &header[32..32 + name_len as usize];
        let bound = if compression.is_empty() {
            if uncompressed != compressed {
                return Err(self.error(
                    at,
                    format!(
                        "an uncompressed chunk declares {uncompressed} bytes of records, and holds {compressed}: it is corrupt"
                    ),
                ));
            }
            compressed
        } else {
            compressed.saturating_mul(CHUNK_RATIO).max(CHUNK_FLOOR)
        }
        .min(RECORD_LIMIT);
        if uncompressed > bound {
            return Err(self.error(
                at,
                format!(
                    "a chunk declares {uncompressed} bytes uncompressed from {compressed}: \
                     beyond leeway's bound (the larger of {CHUNK_RATIO} times the compressed bytes \
                     and {CHUNK_FLOOR}, at most {RECORD_LIMIT}); the chunk is corrupt"
                ),
            ));
        }
        // mcap's reader, for this chunk alone: its header again, then the
        // rest from the file. Nothing in it may be longer than the bound.
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_skip_start_magic(true)
                .with_skip_end_magic(true)
                .with_prevalidate_chunk_crcs(true)
                .with_record_length_limit(bound.max(compressed.min(RECORD_LIMIT)) as usize),
        );
        let mut prefix = vec![op::CHUNK];
        prefix.extend_from_slice(&len.to_le_bytes());
        prefix.extend_from_slice(&header);
        reader.insert(prefix.len()).copy_from_slice(&prefix);
        reader.notify_read(prefix.len());
        let mut left = len - header.len() as u64;
        while let Some(event) = reader.next_event() {
            match event.map_err(|e| self.chunk_error(at, &e))? {
                LinearReadEvent::ReadRequest(need) => {
                    // Nothing left: 0, the end, which the reader reports
                    // if it still needs bytes.
                    let k = need
                        .clamp(1, READ_SIZE)
                        .min(usize::try_from(left).unwrap_or(READ_SIZE));
                    let buffer = reader.insert(k);
                    self.fill(buffer)?;
                    left -= k as u64;
                    reader.notify_read(k);
                }
                LinearReadEvent::Record { data, opcode } => {
                    let record =
                        mcap::parse_record(opcode, data).map_err(|e| self.chunk_error(at, &e))?;
                    visit(record, at)?;
                }
            }
        }
        // Bytes after the records a later version may add.
        self.skip(left, None)
    }

    fn chunk_error(&self, at: u64, error: &McapError) -> DataError {
        match error {
            McapError::BadChunkCrc { .. } => self.error(at, "chunk CRC mismatch"),
            McapError::UnexpectedEof | McapError::UnexpectedEoc => {
                self.error(at, "a chunk whose records run past its end: it is corrupt")
            }
            other => self.error(at, format!("a corrupt chunk: {other}")),
        }
    }
}
