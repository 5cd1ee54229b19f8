//! The checker's tables, against plain oracles.

use std::collections::BTreeMap;

use lsdc::check::resolutions::{Cursor, Resolutions};
use lsdc::check::scope::{ScopeId, Target};
use lsdc::source::{FileId, Span};

/// A pseudo-random sequence (SplitMix64), so that the test is the same at each run.
fn sequence(mut seed: u64) -> impl FnMut() -> u64 {
    move || {
        seed = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = seed;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// Resolutions recorded in source order with local disorder (a call's name after its
/// arguments), names recorded again (a definition's body), resolutions far out of order (a
/// file checked in the middle of another, in the same list), in three files: each is found as a
/// map from span to target says, by `get` and by `get_near` whatever the cursor.
#[test]
fn resolutions_are_found_as_a_map_finds_them() {
    let mut next = sequence(7);
    let mut oracle = BTreeMap::new();
    let mut resolutions = Resolutions::default();
    let mut record = |span: Span, oracle: &mut BTreeMap<(u32, u32, u32), Target>| {
        let target = match span.start() % 3 {
            0 => Target::Local,
            1 => Target::Builtin,
            _ => Target::Global(ScopeId(span.end() % 5)),
        };
        oracle.insert((span.file().0, span.start(), span.end()), target);
        resolutions.insert(span, target);
    };
    for position in 0..3000u32 {
        let file = FileId(position % 3);
        let start = 10 * position;
        let span = Span::new(
            file,
            start as usize,
            start as usize + 1 + (position % 4) as usize,
        );
        record(span, &mut oracle);
        if next().is_multiple_of(5) {
            // A name a little before, recorded late.
            let back = start.saturating_sub(3 * (next() % 40) as u32 + 5);
            record(
                Span::new(file, back as usize, back as usize + 2),
                &mut oracle,
            );
        }
        if next().is_multiple_of(50) {
            // A name far before, recorded again.
            let (&(f, s, e), _) = oracle
                .iter()
                .nth((next() % oracle.len() as u64) as usize)
                .unwrap();
            record(Span::new(FileId(f), s as usize, e as usize), &mut oracle);
        }
        if next().is_multiple_of(300) {
            // A name far before, recorded for the first time.
            let back = (next() % 1000) as u32 * 10 + 7;
            record(
                Span::new(file, back as usize, back as usize + 1),
                &mut oracle,
            );
        }
    }
    resolutions.finish();
    let mut cursor = Cursor::default();
    for (&(file, start, end), &target) in &oracle {
        let span = Span::new(FileId(file), start as usize, end as usize);
        assert_eq!(resolutions.get(span), Some(target), "{span:?}");
        assert_eq!(resolutions.get_near(span, &mut cursor), Some(target));
        let elsewhere = Span::new(FileId(file), start as usize, end as usize + 10);
        assert_eq!(resolutions.get_near(elsewhere, &mut cursor), None);
    }
    // In an order of their own, the cursor left anywhere.
    for _ in 0..2000 {
        let (&(file, start, end), &target) = oracle
            .iter()
            .nth((next() % oracle.len() as u64) as usize)
            .unwrap();
        let span = Span::new(FileId(file), start as usize, end as usize);
        assert_eq!(resolutions.get_near(span, &mut cursor), Some(target));
    }
    assert_eq!(resolutions.get(Span::new(FileId(9), 0, 1)), None);
}
