//! The stamp that ties the checked-in parser to its grammar: a 64-bit FNV-1a hash of the grammar
//! text, written on the first line of the generated parser by `tools/parser-generator` and
//! checked by `build.rs`. It detects a grammar edited without regenerating the parser; it is not
//! a cryptographic hash (nothing adversarial is at stake), so a dozen lines rather than a crate.

/// The first line of the generated parser for this grammar text.
pub fn stamp_line(grammar: &[u8]) -> String {
    const OFFSET_BASIS: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0100_0000_01b3;
    let hash = grammar.iter().fold(OFFSET_BASIS, |hash, &byte| {
        (hash ^ u64::from(byte)).wrapping_mul(PRIME)
    });
    format!("// grammar stamp: {hash:016x} (tools/parser-generator writes this file; do not edit)")
}
