//! The checker's name resolutions: where each name use resolved, by the span of the name, for
//! the elaborator (which follows them instead of resolving again) and the editor.
//!
//! They are kept in one list per file, sorted by position: a resolution takes 12 bytes there,
//! where the hash table this replaces took 21 bytes a slot, with an eighth to a half of the
//! slots empty and, while the table grew, the old table and the new one both alive (a large
//! program has several name uses per line). The checker meets a file's names in order, but for
//! a call's name, resolved after its arguments, and the body of a definition, checked again at
//! its first use: a resolution out of order is inserted in its place when it is near the end
//! of the list, and otherwise the list is sorted once checking is done.

use super::scope::{ScopeId, Target};
use crate::source::Span;

/// A [`Target`] in four bytes: 0 is a local, 1 a built-in, `2 + s` a declaration of scope `s`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Packed(u32);

impl Packed {
    fn new(target: Target) -> Packed {
        Packed(match target {
            Target::Local => 0,
            Target::Builtin => 1,
            Target::Global(scope) => 2 + scope.0,
        })
    }

    fn target(self) -> Target {
        match self.0 {
            0 => Target::Local,
            1 => Target::Builtin,
            n => Target::Global(ScopeId(n - 2)),
        }
    }
}

/// Name resolutions by span (see the module's documentation).
#[derive(Debug, Default)]
pub struct Resolutions {
    files: Vec<FileResolutions>,
}

/// Where a look-up in [`Resolutions`] ended: a file and a position in its list.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cursor {
    file: u32,
    index: usize,
}

/// The resolutions of one file: the start and end of each name, and its target.
#[derive(Debug, Default)]
struct FileResolutions {
    entries: Vec<(u32, u32, Packed)>,
    /// Whether `entries` is in order (and without repeats) yet.
    sorted: bool,
}

/// How far from the end of a file's list a resolution out of order is inserted in its place:
/// farther, the list is sorted at the end instead (an insertion moves what follows it).
const NEAR_END: usize = 64;

impl Resolutions {
    /// Records that the name at `span` resolves to `target`. A name checked again (the body of
    /// a definition, at its first use) resolves the same way each time.
    pub fn insert(&mut self, span: Span, target: Target) {
        let file = span.file().0 as usize;
        if self.files.len() <= file {
            self.files.resize_with(file + 1, || FileResolutions {
                entries: Vec::new(),
                sorted: true,
            });
        }
        self.files[file].insert((span.start(), span.end(), Packed::new(target)));
    }

    /// Puts every file's resolutions in order, once all are recorded.
    pub fn finish(&mut self) {
        for file in &mut self.files {
            file.finish();
        }
    }

    /// The names inside `extent` that resolved to a declaration of `scope`, as spans, in any
    /// order (a scan of the file's list: for the rare question of what a definition reads).
    pub fn global_uses_within(&self, extent: Span, scope: ScopeId) -> Vec<Span> {
        let Some(file) = self.files.get(extent.file().0 as usize) else {
            return Vec::new();
        };
        let target = Packed::new(Target::Global(scope));
        (file.entries.iter())
            .filter(|e| e.2 == target && extent.start() <= e.0 && e.1 <= extent.end())
            .map(|e| Span::new(extent.file(), e.0 as usize, e.1 as usize))
            .collect()
    }

    /// Where the name at `span` resolved, if it did.
    pub fn get(&self, span: Span) -> Option<Target> {
        self.get_near(span, &mut Cursor::default())
    }

    /// As [`Resolutions::get`], looking first just after `cursor`, where the last look-up
    /// ended: names looked up in source order (the elaborator's, mostly) are found there
    /// without a search of the whole file.
    pub fn get_near(&self, span: Span, cursor: &mut Cursor) -> Option<Target> {
        let entries = &self.files.get(span.file().0 as usize)?.entries;
        let key = (span.start(), span.end());
        let near = match cursor.file == span.file().0 {
            true => entries.get(cursor.index..).unwrap_or_default(),
            false => &[],
        };
        let index = match near.iter().take(4).position(|e| (e.0, e.1) == key) {
            Some(offset) => cursor.index + offset,
            None => entries.binary_search_by_key(&key, |e| (e.0, e.1)).ok()?,
        };
        *cursor = Cursor {
            file: span.file().0,
            index,
        };
        Some(entries[index].2.target())
    }
}

impl FileResolutions {
    fn insert(&mut self, entry: (u32, u32, Packed)) {
        let key = (entry.0, entry.1);
        let in_order = (self.entries.last()).is_none_or(|last| (last.0, last.1) < key);
        if in_order || !self.sorted {
            self.entries.push(entry);
            return;
        }
        match self.entries.binary_search_by_key(&key, |e| (e.0, e.1)) {
            Ok(repeated) => {
                debug_assert_eq!(self.entries[repeated], entry, "a name resolved two ways")
            }
            Err(place) if self.entries.len() - place <= NEAR_END => {
                self.entries.insert(place, entry)
            }
            Err(_) => {
                self.entries.push(entry);
                self.sorted = false;
            }
        }
    }

    fn finish(&mut self) {
        if !self.sorted {
            self.entries.sort_unstable();
            debug_assert!(
                (self.entries.windows(2))
                    .all(|w| (w[0].0, w[0].1) != (w[1].0, w[1].1) || w[0] == w[1]),
                "a name resolved two ways"
            );
            self.entries.dedup();
            self.sorted = true;
        }
        self.entries.shrink_to_fit();
    }
}
