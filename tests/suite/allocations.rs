//! The simulator's right-hand side and projection allocate nothing once their scratch is sized,
//! on every example: the test binary's allocator counts the allocations of each thread (a
//! thread-local counter, so that tests running beside this one do not count), and one derivative
//! and one projection at each example's initial state, after two of each have sized every
//! buffer, must make none.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::{Cell, RefCell};
use std::path::PathBuf;
use std::rc::Rc;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::simulate::prepare::{prepare, Settings};
use lsdc::simulate::system::MechanicalSystem;

/// The system allocator, counting the allocations of each thread.
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    // During a thread's teardown the counter may be gone: nothing to count then.
    let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
}

// SAFETY: every call is forwarded to the system allocator unchanged; the counter is a
// thread-local cell initialised without allocating.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, passed on as is.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` with `layout` (through `alloc` above).
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: as for `dealloc`, and `new_size` is the caller's valid request.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on this thread.
fn allocations(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.with(Cell::get);
    f();
    ALLOCATIONS.with(Cell::get) - before
}

fn examples() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["examples", "examples/hard"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(dir).expect("examples"))
        .map(|entry| entry.expect("entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "lsd"))
        .collect();
    files.sort();
    files
}

#[test]
fn derivatives_and_projections_allocate_nothing_on_every_example() {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let mut counted = 0;
    let mut allocating = Vec::new();
    for file in examples() {
        // Examples that need values from the command line do not prepare on their own.
        let Ok(compilation) = compile_files(std::slice::from_ref(&file), &options) else {
            continue;
        };
        let Some(mechanism) = compilation.mechanism else {
            continue;
        };
        let Ok(prepared) = prepare(&mechanism, &[], &Settings::default()) else {
            continue;
        };
        let model = &prepared.model;
        let (mut y, v) = model
            .state_from_declared(&prepared.coordinates, &prepared.rates)
            .expect("initial state");
        y.extend_from_slice(&v);
        let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
        let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
        system.start_loops(&mut y).expect("loops close");
        let mut dydt = vec![0.0; y.len()];
        // A mechanism that cannot move as given (a massless body on a moving joint, waiting for
        // a value from the command line) has no derivative to count.
        if system.derivative(0.0, &y, &mut dydt).is_err() {
            continue;
        }
        let mut z = y.clone();
        for _ in 0..2 {
            system.derivative(0.0, &y, &mut dydt).expect("evaluates");
            system.keep_closed(0.0, &mut z).expect("projects");
        }
        let derivative = allocations(|| {
            system.derivative(0.0, &y, &mut dydt).expect("evaluates");
        });
        let projection = allocations(|| {
            system.keep_closed(0.0, &mut z).expect("projects");
        });
        if derivative + projection > 0 {
            allocating.push(format!(
                "{}: {derivative} per derivative, {projection} per projection",
                file.display()
            ));
        }
        counted += 1;
    }
    assert!(counted >= 20, "only {counted} examples counted");
    assert!(allocating.is_empty(), "allocations: {allocating:#?}");
}

#[test]
fn the_counter_counts() {
    // The test above could not fail if the counter saw nothing.
    let made = allocations(|| {
        std::hint::black_box(vec![1.0_f64; 16]);
    });
    assert_eq!(made, 1);
}
