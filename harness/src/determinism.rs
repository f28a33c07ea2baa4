//! `nc-conform run --check-determinism`: the run is made twice and the two written traces are
//! compared byte for byte (as a digest, so memory does not grow with the trace); different bytes
//! exit with [`EXIT_NONDETERMINISTIC`] (INV-10, `docs/invariants.md`).

use std::io::{self, Write};

/// Exit status: the two runs of `--check-determinism` wrote different traces.
pub const EXIT_NONDETERMINISTIC: u8 = 3;

/// A writer that digests everything written through it (FNV-1a, 64 bit) and passes it on to
/// `inner`, if any.
#[derive(Debug)]
pub struct Digest<W> {
    inner: Option<W>,
    hash: u64,
    bytes: u64,
    lines: u64,
    /// Whether the bytes are hashed (a digest only counts bytes when no comparison needs it).
    hashing: bool,
}

impl<W: Write> Digest<W> {
    /// A digest that also writes to `inner`.
    pub fn new(inner: Option<W>) -> Self {
        Digest { inner, hash: 0xcbf2_9ce4_8422_2325, bytes: 0, lines: 0, hashing: true }
    }

    /// The same, hashing only when `hashing` (else the digest and line count stay at their
    /// start: `nc-conform run` without `--check-determinism` writes at full speed).
    pub fn hashing(mut self, hashing: bool) -> Self {
        self.hashing = hashing;
        self
    }

    /// The digest, byte count and line count so far.
    pub fn summary(&self) -> (u64, u64, u64) {
        (self.hash, self.bytes, self.lines)
    }
}

impl<W: Write> Write for Digest<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = match &mut self.inner {
            Some(w) => w.write(buf)?,
            None => buf.len(),
        };
        if self.hashing {
            for &b in &buf[..n] {
                self.hash = (self.hash ^ b as u64).wrapping_mul(0x0100_0000_01b3);
                self.lines += (b == b'\n') as u64;
            }
        }
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.inner {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

/// The message when two runs differ.
pub fn report(a: (u64, u64, u64), b: (u64, u64, u64)) -> String {
    format!(
        "nondeterministic: two runs of the same input wrote different traces \
         (first: {} bytes, {} lines, digest {:016x}; second: {} bytes, {} lines, digest {:016x})",
        a.1, a.2, a.0, b.1, b.2, b.0
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_digest_sees_every_byte_and_passes_it_on() {
        let mut d = Digest::new(Some(Vec::new()));
        d.write_all(b"a\nb\n").unwrap();
        let (h, bytes, lines) = d.summary();
        assert_eq!((bytes, lines), (4, 2));
        let mut e = Digest::<Vec<u8>>::new(None);
        e.write_all(b"a\nc\n").unwrap();
        assert_ne!(e.summary().0, h, "one changed byte changes the digest");
        assert_eq!(d.inner.unwrap(), b"a\nb\n");
    }
}
