//! lsdc: the compiler and simulator for LSD, a declarative language for describing mechanisms.
//!
//! Start with [`api`]: a program from text or a file, its diagnostics, its mechanism, a prepared
//! simulation and its run, the dynamics at given states.
//!
//! The pipeline, one module per phase, data flowing one way (no module uses a later one):
//! `source` (files, spans) → `syntax` (text to AST) → `load` (imports, libraries, URDF) →
//! `check` (names and types) → `elab` (values: bodies, frames, links, joins, efforts,
//! unknowns) → `topology` (numbering, principal and complementary links) → `kinematics` →
//! `dynamics` → `prepare` (a program made ready to run) → `integrate` and `simulate` → `studies` (built on runs) → `output`; `symbolic` writes the equations from the
//! mechanism. `diag` holds the diagnostics every phase reports.

//!
//! # The library's boundary
//!
//! What the crate offers its users is [`api`], the facade above, and the algorithms it is built on:
//! the dynamic model and its scratch ([`dynamics::model::Model`], [`dynamics::algorithms::Data`]),
//! the recursive algorithms on them (RNEA, CRBA, ABA, forward kinematics, in
//! [`dynamics::algorithms`], and their analytical derivatives in its modules `rnea_derivatives`,
//! `aba_derivatives` and `crba_derivatives`, and RNEA's regressor in the inertial parameters,
//! `regressor`) and the spatial algebra they are written in
//! ([`spatial`]). Every other module is the library's own: `pub(crate)`, unless the crate is
//! compiled with `--cfg lsdc_internals`, which the repository's `.cargo/config.toml` passes to its
//! own builds (the command line, tests, benchmarks and examples, which reach into them), so that
//! `cargo build` and `cargo test` build the library once, with the same flags. A crate that depends
//! on lsdc does not read that file, and rustdoc gets no rustflags: both see the boundary. The
//! command line's commands (`cli`, not documented) are in the library, so that the binary needs
//! nothing else of it and builds without the cfg too.

// The command line's files name the library `lsdc`, as they did when they were the binary's.
extern crate self as lsdc;

/// Declares the library's own modules: `pub` when the crate is compiled with
/// `--cfg lsdc_internals` (the repository's own builds, `.cargo/config.toml`), `pub(crate)`
/// otherwise (a crate depending on lsdc, and rustdoc). See "The library's boundary" above.
macro_rules! internal {
    ($($(#[$attribute:meta])* mod $name:ident;)*) => {
        $(
            $(#[$attribute])*
            #[cfg(lsdc_internals)]
            pub mod $name;
            $(#[$attribute])*
            #[cfg(not(lsdc_internals))]
            pub(crate) mod $name;
        )*
    };
}

pub mod api;
#[doc(hidden)]
pub mod cli;
pub mod dynamics;
pub mod spatial;

internal! {
    mod check;
    mod corrector;
    mod diag;
    mod driver;
    mod elab;
    mod elimination;
    mod ide;
    mod integrate;
    mod integrators;
    mod kinematics;
    mod linalg;
    mod load;
    mod output;
    mod prepare;
    mod simulate;
    mod source;
    mod studies;
    mod symbolic;
    mod syntax;
    mod testing;
    mod topology;
    mod view;
}
