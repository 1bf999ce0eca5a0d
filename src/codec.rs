//! Little-endian bytes for slayer's own binary files (the session file, `session::file`):
//! a writer that appends and a reader that checks every length against what is left, so a
//! truncated or forged file is an error naming what was being read, never a panic or an
//! allocation the file's bytes could not fill.

use bytemuck::Pod;
use thiserror::Error;

// Arrays are written as their in-memory bytes: every target wgpu runs on is little-endian.
#[cfg(target_endian = "big")]
compile_error!("slayer's binary files assume a little-endian target");

/// A read past the end of the bytes, or a value no writer produces.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{what}: {problem}")]
pub struct DecodeError {
    pub what: String,
    pub problem: String,
}

impl DecodeError {
    pub fn new(what: impl Into<String>, problem: impl Into<String>) -> DecodeError {
        DecodeError {
            what: what.into(),
            problem: problem.into(),
        }
    }
}

/// Appends values to a byte vector.
#[derive(Debug, Default)]
pub struct Writer {
    pub bytes: Vec<u8>,
}

impl Writer {
    pub fn u32(&mut self, value: u32) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    pub fn u64(&mut self, value: u64) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    /// A length-prefixed array of plain values.
    pub fn array<T: Pod>(&mut self, values: &[T]) {
        self.u64(values.len() as u64);
        self.bytes.extend_from_slice(bytemuck::cast_slice(values));
    }

    /// A length-prefixed UTF-8 string.
    pub fn string(&mut self, text: &str) {
        self.array(text.as_bytes());
    }

    pub fn strings(&mut self, texts: &[String]) {
        self.u64(texts.len() as u64);
        for text in texts {
            self.string(text);
        }
    }
}

/// Reads values back in the order a [`Writer`] wrote them.
#[derive(Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader { bytes }
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len()
    }

    pub fn take(&mut self, count: usize, what: &str) -> Result<&'a [u8], DecodeError> {
        if count > self.bytes.len() {
            return Err(DecodeError::new(
                what,
                format!(
                    "needs {count} bytes but only {} are left (truncated file?)",
                    self.bytes.len()
                ),
            ));
        }
        let (head, rest) = self.bytes.split_at(count);
        self.bytes = rest;
        Ok(head)
    }

    pub fn u32(&mut self, what: &str) -> Result<u32, DecodeError> {
        let bytes = self.take(4, what)?;
        Ok(u32::from_le_bytes(bytes.try_into().expect("four bytes")))
    }

    pub fn u64(&mut self, what: &str) -> Result<u64, DecodeError> {
        let bytes = self.take(8, what)?;
        Ok(u64::from_le_bytes(bytes.try_into().expect("eight bytes")))
    }

    /// A length-prefixed array; its length is checked against the bytes left before anything
    /// is allocated.
    pub fn array<T: Pod>(&mut self, what: &str) -> Result<Vec<T>, DecodeError> {
        let count = self.count(what)?;
        let size = std::mem::size_of::<T>();
        let bytes = count
            .checked_mul(size)
            .filter(|&b| b <= self.bytes.len())
            .ok_or_else(|| {
                DecodeError::new(
                    what,
                    format!(
                        "claims {count} entries of {size} bytes but only {} bytes are left",
                        self.bytes.len()
                    ),
                )
            })?;
        Ok(bytemuck::pod_collect_to_vec(self.take(bytes, what)?))
    }

    pub fn string(&mut self, what: &str) -> Result<String, DecodeError> {
        let bytes: Vec<u8> = self.array(what)?;
        String::from_utf8(bytes).map_err(|_| DecodeError::new(what, "is not UTF-8"))
    }

    pub fn strings(&mut self, what: &str) -> Result<Vec<String>, DecodeError> {
        let count = self.count(what)?;
        // Each string takes at least its 8-byte length.
        if count > self.bytes.len() / 8 {
            return Err(DecodeError::new(
                what,
                format!("claims {count} strings in {} bytes", self.bytes.len()),
            ));
        }
        (0..count).map(|_| self.string(what)).collect()
    }

    fn count(&mut self, what: &str) -> Result<usize, DecodeError> {
        let count = self.u64(what)?;
        usize::try_from(count).map_err(|_| DecodeError::new(what, "length does not fit memory"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_come_back_in_order() {
        let mut w = Writer::default();
        w.u32(7);
        w.array(&[1.5f32, -0.0, f32::NAN]);
        w.strings(&["plaster".to_string(), "paint".to_string()]);
        w.u64(u64::MAX);
        let mut r = Reader::new(&w.bytes);
        assert_eq!(r.u32("a").unwrap(), 7);
        let floats: Vec<f32> = r.array("b").unwrap();
        assert_eq!(
            floats.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
            [1.5f32.to_bits(), (-0.0f32).to_bits(), f32::NAN.to_bits()]
        );
        assert_eq!(r.strings("c").unwrap(), ["plaster", "paint"]);
        assert_eq!(r.u64("d").unwrap(), u64::MAX);
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn forged_lengths_are_errors_not_allocations() {
        let mut w = Writer::default();
        w.u64(u64::MAX / 2);
        let error = Reader::new(&w.bytes).array::<u32>("positions").unwrap_err();
        assert!(
            error.to_string().starts_with("positions: claims"),
            "{error}"
        );
        let error = Reader::new(&w.bytes).strings("names").unwrap_err();
        assert!(error.to_string().contains("names"), "{error}");
        let error = Reader::new(&[1, 2]).u32("version").unwrap_err();
        assert!(error.to_string().contains("truncated"), "{error}");
    }
}
