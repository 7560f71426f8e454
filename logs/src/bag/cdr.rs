//! Reading a CDR-encoded ROS 2 message in place: the 4-byte encapsulation
//! header (byte order, CDR version), then primitives aligned to their size
//! relative to the start of the payload after that header.
//!
//! Nothing here allocates: a [`Reader`] is a position in the message's bytes.

use super::schema::Primitive;

/// Why a message could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// The message ends before byte `need` of its payload (it has `len`).
    Short {
        /// Payload bytes needed.
        need: usize,
        /// Payload bytes there.
        len: usize,
    },
    /// A sequence holds `len` elements, and element `index` was asked for.
    IndexOutOfRange {
        /// The element asked for.
        index: usize,
        /// Elements in this message.
        len: usize,
    },
    /// An encapsulation other than plain CDR or plain CDR2.
    Encapsulation(u16),
    /// A 64-bit integer beyond ±2⁵³, which an `f64` cannot hold exactly.
    Inexact(String),
}

impl DecodeError {
    /// The problem in words.
    pub fn message(&self) -> String {
        match self {
            DecodeError::Short { need, len } => format!(
                "the message is shorter than its schema: it has {len} payload bytes, \
                 its fields need at least {need}"
            ),
            DecodeError::IndexOutOfRange { index, len } => {
                format!("element {index} asked for, and the sequence holds {len}")
            }
            DecodeError::Inexact(value) => {
                format!("the integer {value} is beyond ±2^53: an f64 cannot hold it exactly")
            }
            DecodeError::Encapsulation(kind) => format!(
                "CDR encapsulation {kind:#06x} is not plain CDR \
                 (0x0000/0x0001, or CDR2 0x0006/0x0007)"
            ),
        }
    }
}

/// The largest integer magnitude an `f64` holds exactly with its neighbours.
const EXACT: u64 = 1 << 53;

/// A position in one CDR message.
#[derive(Clone, Debug)]
pub struct Reader<'a> {
    payload: &'a [u8],
    position: usize,
    big_endian: bool,
    /// 8 in CDR, 4 in CDR2 (XCDR2 aligns 8-byte types to 4).
    max_align: usize,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `message`'s payload, after its encapsulation header.
    pub fn new(message: &'a [u8]) -> Result<Reader<'a>, DecodeError> {
        let Some((header, payload)) = message.split_first_chunk::<4>() else {
            return Err(DecodeError::Short {
                need: 4,
                len: message.len(),
            });
        };
        let kind = u16::from_be_bytes([header[0], header[1]]);
        let (big_endian, max_align) = match kind {
            0x0000 => (true, 8),
            0x0001 => (false, 8),
            0x0006 => (true, 4),
            0x0007 => (false, 4),
            other => return Err(DecodeError::Encapsulation(other)),
        };
        Ok(Reader {
            payload,
            position: 0,
            big_endian,
            max_align,
        })
    }

    /// Bytes of payload from the current position on.
    pub fn remaining(&self) -> usize {
        self.payload.len().saturating_sub(self.position)
    }

    /// Moves to the next multiple of `size` (capped by the CDR version).
    pub fn align(&mut self, size: usize) {
        let align = size.min(self.max_align);
        self.position = self.position.next_multiple_of(align);
    }

    /// Skips `n` bytes.
    pub fn advance(&mut self, n: usize) -> Result<(), DecodeError> {
        let end = self.position.saturating_add(n);
        if end > self.payload.len() {
            return Err(DecodeError::Short {
                need: end,
                len: self.payload.len(),
            });
        }
        self.position = end;
        Ok(())
    }

    /// The next `N` bytes, in the message's byte order turned little-endian.
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        self.align(N);
        let start = self.position;
        self.advance(N)?;
        let mut bytes = [0; N];
        bytes.copy_from_slice(&self.payload[start..start + N]);
        if self.big_endian {
            bytes.reverse();
        }
        Ok(bytes)
    }

    /// A `uint32` (string lengths and sequence counts too).
    pub fn read_u32(&mut self) -> Result<u32, DecodeError> {
        self.bytes::<4>().map(u32::from_le_bytes)
    }

    /// An `int32`.
    pub fn read_i32(&mut self) -> Result<i32, DecodeError> {
        self.bytes::<4>().map(i32::from_le_bytes)
    }

    /// A `float64`.
    pub fn read_f64(&mut self) -> Result<f64, DecodeError> {
        self.bytes::<8>().map(f64::from_le_bytes)
    }

    /// A primitive as an `f64`; a 64-bit integer beyond ±2⁵³ is an error,
    /// not a silent rounding (as in Parquet files).
    pub fn read_number(&mut self, primitive: Primitive) -> Result<f64, DecodeError> {
        Ok(match primitive {
            Primitive::Float64 => self.read_f64()?,
            Primitive::Float32 => f64::from(self.bytes::<4>().map(f32::from_le_bytes)?),
            Primitive::Int8 => f64::from(self.bytes::<1>().map(i8::from_le_bytes)?),
            Primitive::Uint8 | Primitive::Byte | Primitive::Char | Primitive::Bool => {
                f64::from(self.bytes::<1>()?[0])
            }
            Primitive::Int16 => f64::from(self.bytes::<2>().map(i16::from_le_bytes)?),
            Primitive::Uint16 => f64::from(self.bytes::<2>().map(u16::from_le_bytes)?),
            Primitive::Int32 => f64::from(self.read_i32()?),
            Primitive::Uint32 => f64::from(self.read_u32()?),
            Primitive::Int64 => {
                let value = self.bytes::<8>().map(i64::from_le_bytes)?;
                if value.unsigned_abs() > EXACT {
                    return Err(DecodeError::Inexact(value.to_string()));
                }
                // Exact: |value| ≤ 2^53.
                value as f64
            }
            Primitive::Uint64 => {
                let value = self.bytes::<8>().map(u64::from_le_bytes)?;
                if value > EXACT {
                    return Err(DecodeError::Inexact(value.to_string()));
                }
                value as f64
            }
        })
    }
}
