//! Names as 4-byte symbols: each spelling is stored once for the whole process, and a name in
//! the syntax tree, the checker's scopes and the elaborator's tables is its index in that table
//! (a shared string took 16 bytes at every occurrence, and a generated chain names each body
//! five times).
//!
//! The spellings live as long as the process (see [`Interner`]): the language server keeps at
//! most the distinct names typed while its editor runs.
//! Symbols behave as their text: they compare, order, hash and print as their spelling, so that
//! a table keyed by names iterates, and a sorted list of names sorts, as it did with strings.

use std::cell::RefCell;
use std::cmp::Ordering;
use std::fmt;
use std::hash::{Hash, Hasher};
use std::num::NonZeroU32;
use std::ops::Deref;

use crate::source::interner::Interner;

/// A name: one more than its index in the process's table of spellings (nonzero, so that an
/// `Option` of it takes no more room).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Symbol(NonZeroU32);

thread_local! {
    static SPELLINGS: RefCell<Vec<&'static str>> = const { RefCell::new(Vec::new()) };
}

/// Every spelling interned, leaked: it lives as long as the process.
static INTERNER: Interner<&'static str> = Interner::new(&SPELLINGS);

impl Symbol {
    /// The symbol of a spelling, added to the table when first met.
    pub fn intern(text: &str) -> Symbol {
        let index = INTERNER.intern(text, |text| Box::leak(Box::from(text)));
        Symbol(NonZeroU32::new(index + 1).expect("fewer than 2^32 - 1 names"))
    }

    /// The spelling of the name.
    #[inline]
    pub fn as_str(self) -> &'static str {
        INTERNER.get(self.0.get() - 1)
    }
}

impl Deref for Symbol {
    type Target = str;

    fn deref(&self) -> &str {
        self.as_str()
    }
}

impl AsRef<str> for Symbol {
    fn as_ref(&self) -> &str {
        self.as_str()
    }
}

impl std::borrow::Borrow<str> for Symbol {
    fn borrow(&self) -> &str {
        self.as_str()
    }
}

impl From<&str> for Symbol {
    fn from(text: &str) -> Symbol {
        Symbol::intern(text)
    }
}

impl From<&String> for Symbol {
    fn from(text: &String) -> Symbol {
        Symbol::intern(text)
    }
}

impl From<String> for Symbol {
    fn from(text: String) -> Symbol {
        Symbol::intern(&text)
    }
}

impl PartialEq<str> for Symbol {
    fn eq(&self, other: &str) -> bool {
        self.as_str() == other
    }
}

impl PartialEq<&str> for Symbol {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// Hashed as its spelling, so that a table keyed by symbols can be searched with a `&str`
/// (`Borrow<str>`) and iterates in the order it did when keyed by strings.
impl Hash for Symbol {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.as_str().hash(state);
    }
}

/// Ordered as its spelling (alphabetically), not by when it was first met.
impl PartialOrd for Symbol {
    fn partial_cmp(&self, other: &Symbol) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Symbol {
    fn cmp(&self, other: &Symbol) -> Ordering {
        if self == other {
            return Ordering::Equal;
        }
        self.as_str().cmp(other.as_str())
    }
}

impl fmt::Display for Symbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self.as_str(), f)
    }
}

impl fmt::Debug for Symbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}
