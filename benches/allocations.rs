//! Heap allocations per right-hand side and per projection, on every example: a counting global
//! allocator around the system allocator counts the calls to `alloc` (and `realloc`) made while
//! one derivative is evaluated at the example's initial state, after a first evaluation has sized
//! every scratch buffer. Run with `cargo bench --bench allocations`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicUsize, Ordering};

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::simulate::prepare::{prepare, Settings};
use lsdc::simulate::system::MechanicalSystem;

/// The system allocator, counting allocations.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded to the system allocator unchanged; the counter is atomic.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, passed on as is.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` with `layout` (through `alloc` above).
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as for `dealloc`, and `new_size` is the caller's valid request.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f`.
fn allocations(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    f();
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

fn main() {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let mut files: Vec<_> = std::fs::read_dir("examples")
        .expect("examples")
        .chain(std::fs::read_dir("examples/hard").expect("the hard set"))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lsd"))
        .collect();
    files.sort();
    println!(
        "{:<36} {:>6} {:>12} {:>12}",
        "example", "loops", "per RHS", "per projection"
    );
    for file in files {
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
        let Ok((q, v)) = model.state_from_declared(&prepared.coordinates, &prepared.rates) else {
            continue;
        };
        let mut y = q;
        y.extend_from_slice(&v);
        let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
        let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
        if system.start_loops(&mut y).is_err() {
            continue;
        }
        let mut dydt = vec![0.0; y.len()];
        if system.derivative(0.0, &y, &mut dydt).is_err() {
            continue;
        }
        let rhs = allocations(|| {
            let _ = system.derivative(0.0, &y, &mut dydt);
        });
        let projection = if model.has_loops() {
            let mut z = y.clone();
            let _ = system.keep_closed(0.0, &mut z);
            allocations(|| {
                let _ = system.keep_closed(0.0, &mut z);
            })
            .to_string()
        } else {
            "-".to_string()
        };
        let name = file.display().to_string();
        println!(
            "{:<36} {:>6} {:>12} {:>12}",
            name.trim_start_matches("examples/"),
            model.loops.len(),
            rhs,
            projection
        );
    }
}
