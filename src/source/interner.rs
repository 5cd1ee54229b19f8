//! A process-wide table of values, each stored once and named by a `u32` index: the names of
//! the syntax tree ([`Symbol`](crate::syntax::symbol::Symbol)) and the rare spans too long or
//! too far in a large compilation to fit a [`Span`](crate::source::Span)'s eight bytes.
//!
//! The table only grows, and lives as long as the process: a compiler run is short, and the
//! language server, which runs as long as its editor, keeps at most the distinct values
//! met in it. It is shared by all threads (`lsdc test` compiles on several); each thread reads
//! through its own copy of the values, extended from the shared table when it meets an index
//! newer than its copy, so that reading takes no lock.

use rustc_hash::FxHashMap;
use std::borrow::Borrow;
use std::cell::RefCell;
use std::hash::Hash;
use std::sync::{Mutex, MutexGuard};
use std::thread::LocalKey;

/// The shared table: the values in the order first met, and the index of each.
pub struct Interner<T: 'static> {
    shared: Mutex<Option<Shared<T>>>,
    /// This thread's copy of the values.
    local: &'static LocalKey<RefCell<Vec<T>>>,
}

struct Shared<T> {
    values: Vec<T>,
    indices: FxHashMap<T, u32>,
}

impl<T: Copy + Eq + Hash> Interner<T> {
    /// An empty table, read on each thread through `local` (a `thread_local!` of its own).
    pub const fn new(local: &'static LocalKey<RefCell<Vec<T>>>) -> Interner<T> {
        Interner {
            shared: Mutex::new(None),
            local,
        }
    }

    fn lock(&self) -> MutexGuard<'_, Option<Shared<T>>> {
        // A thread that panicked while holding the lock left the table whole (each value is
        // added in one step), so the table is used anyway.
        self.shared
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The index of the value `key` stands for; `make` builds that value when it is first met.
    pub fn intern<Q>(&self, key: &Q, make: impl FnOnce(&Q) -> T) -> u32
    where
        T: Borrow<Q>,
        Q: Hash + Eq + ?Sized,
    {
        let mut guard = self.lock();
        let table = guard.get_or_insert_with(|| Shared {
            values: Vec::new(),
            indices: FxHashMap::default(),
        });
        if let Some(&index) = table.indices.get(key) {
            return index;
        }
        let value = make(key);
        let index = u32::try_from(table.values.len()).expect("fewer than 2^32 values");
        table.values.push(value);
        table.indices.insert(value, index);
        index
    }

    /// The value of an index `intern` returned.
    #[inline]
    pub fn get(&self, index: u32) -> T {
        let copied = self
            .local
            .with(|local| local.borrow().get(index as usize).copied());
        copied.unwrap_or_else(|| self.refresh(index))
    }

    /// Brings this thread's copy up to date with the shared table, for an index newer than it.
    #[cold]
    #[inline(never)]
    fn refresh(&self, index: u32) -> T {
        self.local.with(|local| {
            let mut local = local.borrow_mut();
            let guard = self.lock();
            let all = &guard.as_ref().expect("a value was interned").values;
            let known = local.len();
            local.extend_from_slice(&all[known..]);
            local[index as usize]
        })
    }
}
