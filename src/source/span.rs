//! Source locations: every token, AST node and diagnostic label carries a `Span`.

use serde::Serialize;
use std::cell::RefCell;
use std::cmp::Ordering;
use std::fmt;
use std::hash::{Hash, Hasher};

use crate::source::interner::Interner;

/// Index of a file in the [`SourceMap`](crate::source::SourceMap).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct FileId(pub u32);

/// A byte range in one source file, in eight bytes: the syntax tree holds one on every node.
///
/// A span is its start, length and file when its length and file index each fit 16 bits (every
/// node but a few whole declarations and packages of a very long file); otherwise `file` is
/// `u16::MAX` and `start` the index of the whole span in a process-wide table. The form is
/// chosen by the span alone, so two equal spans have equal fields, and equality compares
/// fields.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Span {
    start: u32,
    len: u16,
    file: u16,
}

/// The `file` of a span kept in the table of long spans.
const LONG: u16 = u16::MAX;

/// A span in full: file, start, end.
type Full = (FileId, u32, u32);

thread_local! {
    static LONG_SPANS: RefCell<Vec<Full>> = const { RefCell::new(Vec::new()) };
}

/// The spans too long (or of a file too far in the map) for the short form. Only a few nodes
/// of a file span more than 64 KiB (a large package, its declaration), so the language
/// server, which parses each version of a file it is sent, adds a few entries per version.
static LONG_TABLE: Interner<Full> = Interner::new(&LONG_SPANS);

impl Span {
    #[inline]
    pub fn new(file: FileId, start: usize, end: usize) -> Span {
        Span::from_full((file, start as u32, end as u32))
    }

    #[inline]
    fn from_full((file, start, end): Full) -> Span {
        let len = end
            .checked_sub(start)
            .and_then(|len| u16::try_from(len).ok());
        match (len, u16::try_from(file.0)) {
            (Some(len), Ok(file)) if file != LONG => Span { start, len, file },
            _ => Span::long((file, start, end)),
        }
    }

    /// A span in the table of long spans (rare, so kept out of the inlined path).
    #[cold]
    #[inline(never)]
    fn long(full: Full) -> Span {
        Span {
            start: LONG_TABLE.intern(&full, |&full| full),
            len: 0,
            file: LONG,
        }
    }

    #[inline]
    fn full(self) -> Full {
        if self.file == LONG {
            return Span::read_long(self.start);
        }
        let end = self.start + u32::from(self.len);
        (FileId(u32::from(self.file)), self.start, end)
    }

    #[cold]
    #[inline(never)]
    fn read_long(index: u32) -> Full {
        LONG_TABLE.get(index)
    }

    /// The file the span is in.
    #[inline]
    pub fn file(self) -> FileId {
        self.full().0
    }

    /// Byte offset of the span's start in its file.
    #[inline]
    pub fn start(self) -> u32 {
        self.full().1
    }

    /// Byte offset just past the span's end in its file.
    #[inline]
    pub fn end(self) -> u32 {
        self.full().2
    }

    /// The first `len` bytes of the span: where it starts, `len` bytes long.
    pub fn head(self, len: u32) -> Span {
        let (file, start, _) = self.full();
        Span::from_full((file, start, start + len))
    }

    /// The smallest span covering both `self` and `other` (same file).
    pub fn to(self, other: Span) -> Span {
        let (file, start, end) = self.full();
        let (_, other_start, other_end) = other.full();
        Span::from_full((file, start.min(other_start), end.max(other_end)))
    }

    #[inline]
    pub fn range(self) -> std::ops::Range<usize> {
        let (_, start, end) = self.full();
        start as usize..end as usize
    }
}

/// Hashed as its file, start and end, as when those were its fields: a table keyed by spans
/// iterates in the same order whichever form its spans take.
impl Hash for Span {
    fn hash<H: Hasher>(&self, state: &mut H) {
        let (file, start, end) = self.full();
        file.hash(state);
        start.hash(state);
        end.hash(state);
    }
}

/// Ordered by file, then start, then end, whichever form each span takes.
impl PartialOrd for Span {
    fn partial_cmp(&self, other: &Span) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Span {
    fn cmp(&self, other: &Span) -> Ordering {
        self.full().cmp(&other.full())
    }
}

impl fmt::Debug for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (file, start, end) = self.full();
        f.debug_struct("Span")
            .field("file", &file)
            .field("start", &start)
            .field("end", &end)
            .finish()
    }
}
