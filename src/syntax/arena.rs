//! Where the syntax tree's nodes live: [`Node`] (a boxed value) and [`Nodes`] (a boxed slice),
//! carved in order from chunks of 256 KiB, each chunk given back to the system as soon as the
//! last node in it is dropped.
//!
//! Why not `Box`: a large file's tree is millions of blocks of 24 to 120 bytes. The system
//! allocator adds a header and a rounding to 16 bytes to each (a tenth of the tree), and once the
//! tree is freed, declaration by declaration as the elaborator goes (`elab::elaborate_consuming`),
//! its blocks are holes between the blocks still alive, so the process keeps every page the tree
//! ever took while the mechanism grows beside them. Here a node is eight-byte aligned with no
//! header, and nodes made together share chunks: a declaration's nodes are neighbours, the
//! elaborator frees the declarations in order, and the chunks empty and go back in that order.
//!
//! Each chunk counts the nodes alive in it (atomically: a tree may be dropped on another thread
//! than the one that parsed it), plus one while a thread is still carving nodes from it. A node
//! finds its chunk's count by masking its address, since chunks are aligned to their size.

use std::alloc::Layout;
use std::cell::RefCell;
use std::fmt;
use std::marker::PhantomData;
use std::mem::{self, ManuallyDrop};
use std::ops::{Deref, DerefMut};
use std::ptr::NonNull;
use std::sync::atomic::{fence, AtomicUsize, Ordering};

/// The size and alignment of a chunk.
const CHUNK: usize = 256 * 1024;

/// A value larger than this takes a mapping of its own rather than ending a chunk early.
const LARGE: usize = CHUNK / 16;

/// The largest alignment of a value in a chunk (that of the syntax tree's values is 8).
const ALIGN: usize = 16;

/// The start of every chunk.
#[repr(C)]
struct Header {
    /// Nodes alive in the chunk, plus one while it is a thread's current chunk.
    live: AtomicUsize,
    /// The bytes mapped for the chunk: `CHUNK`, or more for one large value.
    size: usize,
}

/// The bytes of all chunks mapped now.
static MAPPED: AtomicUsize = AtomicUsize::new(0);

/// The bytes of all chunks mapped now, by every thread: what the syntax trees alive hold, with
/// the free ends of the chunks being carved.
#[cfg(lsdc_internals)]
pub fn mapped_bytes() -> usize {
    MAPPED.load(Ordering::Relaxed)
}

/// The first address of a chunk usable for nodes.
const FIRST: usize = mem::size_of::<Header>().next_multiple_of(ALIGN);

/// The chunk this thread carves nodes from: the next free address and the chunk's end.
struct Carver {
    chunk: Option<NonNull<Header>>,
    next: usize,
    end: usize,
}

impl Drop for Carver {
    fn drop(&mut self) {
        if let Some(chunk) = self.chunk.take() {
            release_chunk(chunk);
        }
    }
}

thread_local! {
    static CARVER: RefCell<Carver> = const {
        RefCell::new(Carver { chunk: None, next: 0, end: 0 })
    };
}

/// Room for a value of `layout` (nonzero size, alignment at most `ALIGN`), counted in its chunk.
fn allocate(layout: Layout) -> NonNull<u8> {
    if layout.size() > LARGE {
        return allocate_alone(layout);
    }
    let carved = CARVER.try_with(|carver| {
        let mut carver = carver.borrow_mut();
        let mut start = carver.next.next_multiple_of(layout.align());
        if carver.chunk.is_none() || start + layout.size() > carver.end {
            let chunk = map_chunk(CHUNK);
            if let Some(old) = carver.chunk.replace(chunk) {
                release_chunk(old);
            }
            carver.next = chunk.as_ptr() as usize + FIRST;
            carver.end = chunk.as_ptr() as usize + CHUNK;
            start = carver.next.next_multiple_of(layout.align());
        }
        carver.next = start + layout.size();
        let chunk = carver.chunk.expect("a chunk was just mapped");
        // SAFETY: the chunk is mapped and its header written; the carver's count keeps it so.
        unsafe { chunk.as_ref() }
            .live
            .fetch_add(1, Ordering::Relaxed);
        start
    });
    match carved {
        // SAFETY: `start` is inside a mapped chunk, hence not null.
        Ok(start) => unsafe { NonNull::new_unchecked(start as *mut u8) },
        // The thread is ending and its carver is gone.
        Err(_) => allocate_alone(layout),
    }
}

/// A mapping of its own for one value, counted once.
fn allocate_alone(layout: Layout) -> NonNull<u8> {
    let offset = FIRST.next_multiple_of(layout.align());
    let chunk = map_chunk((offset + layout.size()).next_multiple_of(CHUNK));
    // SAFETY: the chunk was just mapped, with its count at one (the value's).
    unsafe { NonNull::new_unchecked((chunk.as_ptr() as *mut u8).add(offset)) }
}

/// Gives back the place of `count` values at `first` (at least one), once they are gone
/// (dropped or moved out): its count in its chunk is dropped, freeing the chunk if it was the
/// last. In builds with debug assertions (the test suite's) the place is first overwritten, so
/// that a node read after it is gone reads this pattern rather than a value that still looks
/// right, since its chunk stays mapped while its neighbours live.
fn vacate<T>(first: NonNull<T>, count: usize) {
    let place = first.as_ptr().cast::<u8>();
    if cfg!(debug_assertions) {
        // SAFETY: the values occupied these bytes and are gone; they are the caller's to write.
        unsafe { std::ptr::write_bytes(place, 0xA5, count * mem::size_of::<T>()) };
    }
    let chunk = (place as usize & !(CHUNK - 1)) as *mut Header;
    // SAFETY: every value handed out lies in the first `CHUNK` bytes of its chunk, whose
    // header is at the chunk's aligned start.
    release_chunk(unsafe { NonNull::new_unchecked(chunk) });
}

fn release_chunk(chunk: NonNull<Header>) {
    // SAFETY: the chunk stays mapped while its count is above zero, and the caller holds one.
    let header = unsafe { chunk.as_ref() };
    if header.live.fetch_sub(1, Ordering::Release) == 1 {
        // Every other holder's writes to the chunk happen before it is unmapped.
        fence(Ordering::Acquire);
        let size = header.size;
        unmap_chunk(chunk, size);
    }
}

/// A chunk of `size` bytes (a multiple of `CHUNK`), aligned to `CHUNK`, with its count at one.
fn map_chunk(size: usize) -> NonNull<Header> {
    let chunk = system::map(size).cast::<Header>();
    MAPPED.fetch_add(size, Ordering::Relaxed);
    // SAFETY: the mapping is `size` bytes, writable and aligned for the header.
    unsafe {
        chunk.as_ptr().write(Header {
            live: AtomicUsize::new(1),
            size,
        })
    };
    chunk
}

fn unmap_chunk(chunk: NonNull<Header>, size: usize) {
    // SAFETY: the count reached zero: no node and no carver refers to the chunk any more.
    unsafe { system::unmap(chunk.cast(), size) };
    MAPPED.fetch_sub(size, Ordering::Relaxed);
}

/// Chunks straight from the system on Unix (an emptied chunk is unmapped, so its pages go back
/// at once whatever the allocator's thresholds), from the global allocator elsewhere.
#[cfg(unix)]
mod system {
    use super::CHUNK;
    use std::ptr::NonNull;

    /// Maps `size` bytes aligned to `CHUNK`: maps `CHUNK` more, then unmaps what is before the
    /// first aligned address and after the chunk.
    pub(super) fn map(size: usize) -> NonNull<u8> {
        let span = size + CHUNK;
        // SAFETY: an anonymous private mapping at an address of the system's choosing.
        let base = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                span,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        if base == libc::MAP_FAILED {
            std::alloc::handle_alloc_error(
                std::alloc::Layout::from_size_align(size, CHUNK).unwrap(),
            );
        }
        let base = base as usize;
        let start = base.next_multiple_of(CHUNK);
        // SAFETY: both pieces lie inside the mapping just made and are no part of the chunk.
        unsafe {
            if start > base {
                libc::munmap(base as *mut libc::c_void, start - base);
            }
            let tail = base + span - (start + size);
            if tail > 0 {
                libc::munmap((start + size) as *mut libc::c_void, tail);
            }
            NonNull::new_unchecked(start as *mut u8)
        }
    }

    /// # Safety
    /// `chunk` was mapped by [`map`] with `size`, and nothing refers to it any more.
    pub(super) unsafe fn unmap(chunk: NonNull<u8>, size: usize) {
        libc::munmap(chunk.as_ptr() as *mut libc::c_void, size);
    }
}

#[cfg(not(unix))]
mod system {
    use super::CHUNK;
    use std::alloc::Layout;
    use std::ptr::NonNull;

    fn layout(size: usize) -> Layout {
        Layout::from_size_align(size, CHUNK).expect("a chunk's size is a multiple of its alignment")
    }

    pub(super) fn map(size: usize) -> NonNull<u8> {
        // SAFETY: the layout has a nonzero size.
        let chunk = unsafe { std::alloc::alloc(layout(size)) };
        NonNull::new(chunk).unwrap_or_else(|| std::alloc::handle_alloc_error(layout(size)))
    }

    /// # Safety
    /// `chunk` was mapped by [`map`] with `size`, and nothing refers to it any more.
    pub(super) unsafe fn unmap(chunk: NonNull<u8>, size: usize) {
        std::alloc::dealloc(chunk.as_ptr(), layout(size));
    }
}

/// A value of the syntax tree in a chunk: as a `Box`, with no header and freed with its
/// neighbours.
pub struct Node<T> {
    value: NonNull<T>,
    owns: PhantomData<T>,
}

// SAFETY: a node owns its value as a `Box` does; its chunk's count is atomic.
unsafe impl<T: Send> Send for Node<T> {}
// SAFETY: as above; a shared node only gives shared access to its value.
unsafe impl<T: Sync> Sync for Node<T> {}

impl<T> Node<T> {
    const FITS: () = assert!(
        mem::size_of::<T>() > 0 && mem::align_of::<T>() <= ALIGN,
        "a node holds a value with a size, aligned to 16 bytes at most"
    );

    pub fn new(value: T) -> Node<T> {
        let () = Self::FITS;
        let place = allocate(Layout::new::<T>()).cast::<T>();
        // SAFETY: the place is fresh, aligned and large enough for a `T`.
        unsafe { place.as_ptr().write(value) };
        Node {
            value: place,
            owns: PhantomData,
        }
    }

    /// The value, its place freed.
    pub fn into_inner(self) -> T {
        let node = ManuallyDrop::new(self);
        // SAFETY: the value is read once and its place released without dropping it again.
        let value = unsafe { node.value.as_ptr().read() };
        vacate(node.value, 1);
        value
    }
}

impl<T> Drop for Node<T> {
    fn drop(&mut self) {
        // SAFETY: the node owns its value, dropped once, then its place released.
        unsafe { self.value.as_ptr().drop_in_place() };
        vacate(self.value, 1);
    }
}

impl<T> Deref for Node<T> {
    type Target = T;

    fn deref(&self) -> &T {
        // SAFETY: the value lives as long as the node.
        unsafe { self.value.as_ref() }
    }
}

impl<T> DerefMut for Node<T> {
    fn deref_mut(&mut self) -> &mut T {
        // SAFETY: the node owns its value, and `&mut self` makes this access unique.
        unsafe { self.value.as_mut() }
    }
}

impl<T: Clone> Clone for Node<T> {
    fn clone(&self) -> Node<T> {
        Node::new((**self).clone())
    }
}

impl<T: PartialEq> PartialEq for Node<T> {
    fn eq(&self, other: &Node<T>) -> bool {
        **self == **other
    }
}

impl<T: fmt::Debug> fmt::Debug for Node<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        (**self).fmt(f)
    }
}

/// A list of the syntax tree at its exact length, in a chunk: as a `Box<[T]>`.
pub struct Nodes<T> {
    first: NonNull<T>,
    len: usize,
    owns: PhantomData<T>,
}

// SAFETY: as for `Node`.
unsafe impl<T: Send> Send for Nodes<T> {}
// SAFETY: as for `Node`.
unsafe impl<T: Sync> Sync for Nodes<T> {}

impl<T> Nodes<T> {
    const FITS: () = assert!(
        mem::size_of::<T>() > 0 && mem::align_of::<T>() <= ALIGN,
        "a list holds values with a size, aligned to 16 bytes at most"
    );

    /// The elements, moved out into a vector and their place freed.
    pub fn into_vec(self) -> Vec<T> {
        let nodes = ManuallyDrop::new(self);
        let mut elements = Vec::with_capacity(nodes.len);
        // SAFETY: the elements are moved once into the vector, which has room for them, and
        // their place released without dropping them again.
        unsafe {
            std::ptr::copy_nonoverlapping(nodes.first.as_ptr(), elements.as_mut_ptr(), nodes.len);
            elements.set_len(nodes.len);
        }
        if nodes.len > 0 {
            vacate(nodes.first, nodes.len);
        }
        elements
    }
}

impl<T> From<Vec<T>> for Nodes<T> {
    fn from(mut elements: Vec<T>) -> Nodes<T> {
        let () = Self::FITS;
        let len = elements.len();
        if len == 0 {
            return Nodes::default();
        }
        let layout = Layout::array::<T>(len).expect("a list the size of a file's text");
        let first = allocate(layout).cast::<T>();
        // SAFETY: the place is fresh and has room for `len` elements; the vector gives up its
        // elements without dropping them.
        unsafe {
            std::ptr::copy_nonoverlapping(elements.as_ptr(), first.as_ptr(), len);
            elements.set_len(0);
        }
        Nodes {
            first,
            len,
            owns: PhantomData,
        }
    }
}

impl<T> FromIterator<T> for Nodes<T> {
    fn from_iter<I: IntoIterator<Item = T>>(elements: I) -> Nodes<T> {
        Nodes::from(elements.into_iter().collect::<Vec<T>>())
    }
}

impl<T> Default for Nodes<T> {
    fn default() -> Nodes<T> {
        Nodes {
            first: NonNull::dangling(),
            len: 0,
            owns: PhantomData,
        }
    }
}

impl<T> Drop for Nodes<T> {
    fn drop(&mut self) {
        if self.len == 0 {
            return;
        }
        // SAFETY: the list owns its elements, dropped once, then their place released.
        unsafe {
            std::ptr::slice_from_raw_parts_mut(self.first.as_ptr(), self.len).drop_in_place()
        };
        vacate(self.first, self.len);
    }
}

impl<T> Deref for Nodes<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        // SAFETY: `len` elements live at `first` as long as the list (none when empty, where
        // `first` is dangling but aligned).
        unsafe { std::slice::from_raw_parts(self.first.as_ptr(), self.len) }
    }
}

impl<T> DerefMut for Nodes<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        // SAFETY: as in `deref`, and `&mut self` makes this access unique.
        unsafe { std::slice::from_raw_parts_mut(self.first.as_ptr(), self.len) }
    }
}

impl<T: Clone> Clone for Nodes<T> {
    fn clone(&self) -> Nodes<T> {
        Nodes::from(self.to_vec())
    }
}

impl<T: PartialEq> PartialEq for Nodes<T> {
    fn eq(&self, other: &Nodes<T>) -> bool {
        **self == **other
    }
}

impl<T: fmt::Debug> fmt::Debug for Nodes<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        (**self).fmt(f)
    }
}

impl<'a, T> IntoIterator for &'a Nodes<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;

    fn into_iter(self) -> std::slice::Iter<'a, T> {
        self.iter()
    }
}
