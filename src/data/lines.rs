//! Line numbers of CSV records as a person counts them: the csv crate's record positions point
//! before skipped blank and comment lines (and drift with CRLF), so readers count newlines here.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io::Read;
use std::rc::Rc;

/// Offsets of the newlines a reader has passed, so a byte offset can be turned into a line.
/// csv's own record positions point before skipped blank/comment lines (and drift with CRLF),
/// so lines are counted here; the queue only holds newlines still in csv's read-ahead buffer.
#[derive(Default)]
pub(crate) struct Newlines {
    read: u64,
    pending: VecDeque<u64>,
    before: u64,
}

impl Newlines {
    /// Number of newlines strictly before byte offset `byte` (offsets must not decrease).
    pub(crate) fn count_before(&mut self, byte: u64) -> u64 {
        while self.pending.front().is_some_and(|&nl| nl < byte) {
            self.pending.pop_front();
            self.before += 1;
        }
        self.before
    }
}

/// A reader that records where its newlines are.
pub(crate) struct LineCounter<R> {
    inner: R,
    lines: Rc<RefCell<Newlines>>,
}

impl<R: Read> Read for LineCounter<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let mut lines = self.lines.borrow_mut();
        let start = lines.read;
        for (i, _) in buf[..n].iter().enumerate().filter(|(_, &b)| b == b'\n') {
            lines.pending.push_back(start + i as u64);
        }
        lines.read += n as u64;
        Ok(n)
    }
}

impl<R: Read> LineCounter<R> {
    /// Wrap `inner`; the shared [`Newlines`] answers which line a byte offset is on.
    pub(crate) fn wrap(inner: R) -> (Self, Rc<RefCell<Newlines>>) {
        let lines = Rc::new(RefCell::new(Newlines::default()));
        (
            LineCounter {
                inner,
                lines: Rc::clone(&lines),
            },
            lines,
        )
    }
}
