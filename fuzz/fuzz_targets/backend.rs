//! Feeds programs to the whole back end (tree, assembly, equations and their C code, a short
//! simulation with each integrator, samples written, URDF export): none of it may panic. The
//! input is a program's text, started from the examples (`fuzz/seeds/backend`) and mutated by
//! the fuzzer; each input also goes through the suite's semantic mutations (degenerate numbers,
//! swapped joints and integrators, zero axes, dropped or duplicated declarations), chosen by a
//! hash of the input.
#![no_main]

use std::hash::{Hash, Hasher};
use std::path::Path;

use libfuzzer_sys::fuzz_target;

#[path = "../../tests/suite/mutants.rs"]
mod mutants;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let examples = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples"));
    mutants::exercise(text, Some(examples));
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    text.hash(&mut hasher);
    let mut choices = mutants::Choices::new(hasher.finish());
    let mutant = mutants::mutate(text, &mut choices);
    if mutant != text {
        mutants::exercise(&mutant, Some(examples));
    }
});
