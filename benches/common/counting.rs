//! A global allocator that counts the allocations of each thread, and the count per evaluation of
//! every example, for the benchmark that prints it and the test that asserts it
//! (`benches/allocations.rs`, `tests/suite/allocations.rs`). A thread-local counter: tests
//! running beside the counting one do not count.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};
use lsdc::simulate::system::MechanicalSystem;

/// The system allocator, counting the allocations of each thread.
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    /// Bytes this thread allocated and has not freed (memory freed by another thread counts
    /// there), and their highest value since `peak_bytes` last reset it.
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn count() {
    // During a thread's teardown the counter may be gone: nothing to count then.
    let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
}

/// `bytes` more (or fewer) held by this thread.
fn hold(bytes: isize) {
    let _ = LIVE.try_with(|live| {
        live.set(live.get() + bytes);
        let _ = PEAK.try_with(|peak| peak.set(peak.get().max(live.get())));
    });
}

// SAFETY: every call is forwarded to the system allocator unchanged; the counter is a
// thread-local cell initialised without allocating.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        hold(layout.size() as isize);
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, passed on as is.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        hold(-(layout.size() as isize));
        // SAFETY: `ptr` was allocated by `System` with `layout` (through `alloc` above).
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        hold(new_size as isize - layout.size() as isize);
        // SAFETY: as for `dealloc`, and `new_size` is the caller's valid request.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on this thread.
pub fn allocations(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.with(Cell::get);
    f();
    ALLOCATIONS.with(Cell::get) - before
}

/// The most bytes `f` held at once on this thread, beyond what the thread held before it.
#[allow(dead_code)] // the allocations benchmark counts calls only
pub fn peak_bytes(f: impl FnOnce()) -> usize {
    let before = LIVE.with(Cell::get);
    PEAK.with(|peak| peak.set(before));
    f();
    (PEAK.with(Cell::get) - before).max(0) as usize
}

/// The example programs (`examples/`, `examples/hard/`), sorted.
pub fn examples() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["examples", "examples/hard"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(dir).expect("examples"))
        .map(|entry| entry.expect("entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "lsd"))
        .collect();
    files.sort();
    files
}

/// What one evaluation of a program's mechanism allocates at its initial state, once two of
/// each have sized every buffer: (loops, allocations per derivative, per projection onto the
/// loops or contacts if it has any). None for a program that needs values from the command
/// line, or whose mechanism cannot move as given (a massless body on a moving joint).
pub fn per_evaluation(file: &Path) -> Option<(usize, usize, Option<usize>)> {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[file.to_path_buf()], &options).ok()?;
    let prepared = prepare(&compilation.mechanism?, &[], &Settings::default()).ok()?;
    let model = &prepared.model;
    let (mut y, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .ok()?;
    y.extend_from_slice(&v);
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    system.start_loops(&mut y).ok()?;
    let mut dydt = vec![0.0; y.len()];
    let mut z = y.clone();
    for _ in 0..2 {
        system.derivative(0.0, &y, &mut dydt).ok()?;
        system.keep_closed(0.0, &mut z).ok()?;
    }
    let derivative = allocations(|| {
        let _ = system.derivative(0.0, &y, &mut dydt);
    });
    let projection = allocations(|| {
        let _ = system.keep_closed(0.0, &mut z);
    });
    Some((
        model.loops.len(),
        derivative,
        (model.has_loops() || model.has_contacts()).then_some(projection),
    ))
}
