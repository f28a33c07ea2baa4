//! A bound on how deeply a VCD header nests `$scope`s.
//!
//! The `vcd` crate reads nested scopes by recursion, so a header of 50 000 nested `$scope`s
//! overflowed the stack. [`ScopeDepth`] sits between the file and that parser: it watches the
//! header's words as the parser consumes them and, past [`MAX_SCOPE_DEPTH`] open scopes, fails
//! the next read with an error naming the limit. After `$enddefinitions` it only passes bytes on.

use std::io::{self, BufRead, Read};

/// The deepest `$scope` nesting read (recorders write a handful of levels).
pub const MAX_SCOPE_DEPTH: usize = 256;

/// A reader that refuses a header nesting more than [`MAX_SCOPE_DEPTH`] scopes.
pub struct ScopeDepth<R> {
    inner: R,
    watch: Watch,
}

/// The header words seen so far.
#[derive(Default)]
struct Watch {
    word: Vec<u8>,
    depth: usize,
    too_deep: bool,
    done: bool,
}

impl<R: BufRead> ScopeDepth<R> {
    /// Wraps a reader positioned at the start of a VCD file.
    pub fn new(inner: R) -> Self {
        Self { inner, watch: Watch::default() }
    }

    fn refuse(&self) -> io::Result<()> {
        if self.watch.too_deep {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("more than {MAX_SCOPE_DEPTH} nested $scope commands"),
            ));
        }
        Ok(())
    }
}

impl Watch {
    fn word_ends(&mut self) {
        match self.word.as_slice() {
            b"$scope" => {
                self.depth += 1;
                self.too_deep |= self.depth > MAX_SCOPE_DEPTH;
            }
            b"$upscope" => self.depth = self.depth.saturating_sub(1),
            b"$enddefinitions" => self.done = true,
            _ => {}
        }
        self.word.clear();
    }

    fn watch(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.done {
                return;
            }
            if b.is_ascii_whitespace() {
                self.word_ends();
            } else if self.word.len() < 16 {
                self.word.push(b);
            }
        }
    }
}

impl<R: BufRead> Read for ScopeDepth<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.refuse()?;
        let n = self.inner.read(buf)?;
        self.watch.watch(&buf[..n]);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for ScopeDepth<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        self.refuse()?;
        self.inner.fill_buf()
    }

    fn consume(&mut self, amt: usize) {
        if !self.watch.done {
            if let Ok(b) = self.inner.fill_buf() {
                self.watch.watch(&b[..amt.min(b.len())]);
            }
        }
        self.inner.consume(amt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(depth: usize) -> String {
        format!(
            "$timescale 1us $end\n{}{}$enddefinitions $end\n#0\n",
            "$scope module a $end\n".repeat(depth),
            "$upscope $end\n".repeat(depth)
        )
    }

    #[test]
    fn deep_headers_are_refused_and_ordinary_ones_read() {
        let ok = header(MAX_SCOPE_DEPTH);
        let mut p = vcd::Parser::new(ScopeDepth::new(ok.as_bytes()));
        assert!(p.parse_header().is_ok());
        let deep = header(50_000);
        let mut p = vcd::Parser::new(ScopeDepth::new(deep.as_bytes()));
        let e = p.parse_header().unwrap_err();
        assert!(e.to_string().contains("nested $scope"), "{e}");
    }
}
