//! The little-endian byte layout OpenVDB streams use: fixed-size integers and floats,
//! length-prefixed strings, bit masks, and value arrays that may be zlib-compressed.
//! Kept apart from the tree and file layout so those read as a list of fields.

use std::io::Write;

use flate2::write::ZlibEncoder;

use super::{Compression, VdbError};

/// An in-memory output stream; absolute positions in it are the file offsets the
/// grid descriptors record.
pub(super) struct Out {
    /// Everything written so far.
    pub bytes: Vec<u8>,
}

impl Out {
    /// Current position (the offset of the next byte written).
    pub fn pos(&self) -> u64 {
        self.bytes.len() as u64
    }

    /// A byte.
    pub fn u8(&mut self, v: u8) {
        self.bytes.push(v);
    }

    /// A `u32`.
    pub fn u32(&mut self, v: u32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// An `i32`.
    pub fn i32(&mut self, v: i32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// An `i64`.
    pub fn i64(&mut self, v: i64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// An `f64`.
    pub fn f64(&mut self, v: f64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// Bytes as they are.
    pub fn raw(&mut self, b: &[u8]) {
        self.bytes.extend_from_slice(b);
    }

    /// A string as OpenVDB writes names: `u32` byte length, then the bytes (no terminator).
    pub fn string(&mut self, s: &str) -> Result<(), VdbError> {
        let n = u32::try_from(s.len()).map_err(|_| VdbError::TooLarge("string"))?;
        self.u32(n);
        self.raw(s.as_bytes());
        Ok(())
    }

    /// A node mask: its bits packed into `u64` words, bit `n` in word `n / 64`.
    pub fn mask(&mut self, words: &[u64]) {
        for w in words {
            self.bytes.extend_from_slice(&w.to_le_bytes());
        }
    }

    /// Overwrites 8 bytes at `at` with `v` (to fill in offsets known only later).
    pub fn patch_i64(&mut self, at: u64, v: i64) {
        let at = at as usize;
        self.bytes[at..at + 8].copy_from_slice(&v.to_le_bytes());
    }

    /// A node's value array (already serialised to `data`) under the grid's compression:
    /// raw, or with zlib an `i64` byte count followed by the zlib stream, where a
    /// non-positive count means `-count` raw bytes follow because zlib did not shrink them.
    pub fn values(&mut self, data: &[u8], compression: Compression) -> Result<(), VdbError> {
        match compression {
            Compression::None => self.raw(data),
            Compression::Zip => {
                let zipped = zip(data)?;
                if !data.is_empty() && zipped.len() < data.len() {
                    self.i64(zipped.len() as i64);
                    self.raw(&zipped);
                } else {
                    self.i64(-(data.len() as i64));
                    self.raw(data);
                }
            }
        }
        Ok(())
    }
}

/// zlib (RFC 1950) stream of `data`, the format zlib's `compress2` produces.
fn zip(data: &[u8]) -> Result<Vec<u8>, VdbError> {
    let mut enc = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(data)?;
    Ok(enc.finish()?)
}
