//! Semantic mutants of the bundled examples, and the back end run on a program: shared by the
//! mutation test (`robustness::mutants_neither_panic_nor_hang`) and the `backend` fuzz target
//! (`fuzz/fuzz_targets/backend.rs` includes this file).

use std::path::Path;

use lsdc::api::{run, Program, SettingsChanges};
use lsdc::load::LoadOptions;

/// What a number is replaced by: the degenerate values a user or a typo brings.
const NUMBERS: [&str; 8] = [
    "0", "1e308", "(1/0)", "(0/0)", "-1", "1e-300", "1e309", "-0.0",
];

/// Joints that take the same arguments, swapped for one another.
const JOINT_GROUPS: [&[&str]; 2] = [
    &["revolute", "prismatic", "continuous"],
    &["spherical", "weld", "planar", "free"],
];

const INTEGRATORS: [&str; 5] = ["rk4", "dopri5", "dop853", "implicit", "symplectic"];

/// A small deterministic generator (xorshift), so that a mutant is named by its seed.
pub struct Choices(u64);

impl Choices {
    pub fn new(seed: u64) -> Choices {
        Choices(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    pub fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n.max(1) as u64) as usize
    }
}

/// Byte ranges of the number literals of `text` (outside comments, roughly: digits not part of a
/// name).
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut found = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts = bytes[i].is_ascii_digit()
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if !starts {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
            i += 1;
        }
        if i < bytes.len() && bytes[i] == b'e' {
            i += 1;
            if i < bytes.len() && bytes[i] == b'-' {
                i += 1;
            }
            while i < bytes.len() && bytes[i].is_ascii_digit() {
                i += 1;
            }
        }
        found.push((start, i));
    }
    found
}

/// Byte ranges of whole-word occurrences of `word`.
fn words(text: &str, word: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let is_name = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    text.match_indices(word)
        .map(|(i, _)| (i, i + word.len()))
        .filter(|&(s, e)| {
            (s == 0 || !is_name(bytes[s - 1])) && (e == bytes.len() || !is_name(bytes[e]))
        })
        .collect()
}

fn replace(text: &str, (start, end): (usize, usize), with: &str) -> String {
    format!("{}{with}{}", &text[..start], &text[end..])
}

/// One mutation of `text`: a number replaced by a degenerate one, a joint or an integrator
/// swapped, an axis made zero, a declaration dropped or duplicated. A kind of mutation that finds
/// nothing to change falls back to a number.
pub fn mutate(text: &str, choices: &mut Choices) -> String {
    let kind = choices.below(6);
    let mutant = mutate_as(kind, text, choices);
    if mutant == text && kind > 1 {
        return mutate_as(0, text, choices);
    }
    mutant
}

fn mutate_as(kind: usize, text: &str, choices: &mut Choices) -> String {
    match kind {
        0 | 1 => {
            let found = numbers(text);
            if found.is_empty() {
                return text.to_string();
            }
            let at = found[choices.below(found.len())];
            replace(text, at, NUMBERS[choices.below(NUMBERS.len())])
        }
        2 => {
            let group = JOINT_GROUPS[choices.below(JOINT_GROUPS.len())];
            let found: Vec<_> = group.iter().flat_map(|w| words(text, w)).collect();
            if found.is_empty() {
                return text.to_string();
            }
            let at = found[choices.below(found.len())];
            replace(text, at, group[choices.below(group.len())])
        }
        3 => {
            let found: Vec<_> = INTEGRATORS.iter().flat_map(|w| words(text, w)).collect();
            match found.first() {
                Some(&at) => replace(text, at, INTEGRATORS[choices.below(INTEGRATORS.len())]),
                None => text.to_string(),
            }
        }
        4 => {
            let found = words(text, "[1, 0, 0]");
            let axes: Vec<_> = text
                .match_indices("[0, 0, 1]")
                .chain(text.match_indices("[1, 0, 0]"))
                .map(|(i, s)| (i, i + s.len()))
                .chain(found)
                .collect();
            match axes.get(choices.below(axes.len())) {
                Some(&at) => replace(text, at, "[0, 0, 0]"),
                None => text.to_string(),
            }
        }
        _ => {
            let decls: Vec<&str> = text.split_inclusive(";\n").collect();
            let k = choices.below(decls.len());
            let mut out = String::new();
            let duplicate = choices.below(2) == 0;
            for (i, decl) in decls.iter().enumerate() {
                if i != k || duplicate {
                    out += decl;
                }
                if i == k && duplicate {
                    out += decl;
                }
            }
            out
        }
    }
}

/// Runs the whole back end on a program: diagnostics rendered, the tree, the assembly, the
/// equations and their code, a short run with each integrator, its samples written, the URDF
/// export. Nothing may panic; every failure is a diagnostic or a reported run failure. Returns
/// how far the program went: 0 refused by the front end, 1 tree refused, 2 not prepared for
/// simulation, 3 simulated.
pub fn exercise(text: &str, dir: Option<&Path>) -> usize {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let program = Program::from_text("mutant.lsd", text, dir, &options);
    let _ = program.render();
    let Ok(mechanism) = program.mechanism() else {
        return 0;
    };
    let Ok(topology) = lsdc::topology::build(mechanism) else {
        return 1;
    };
    let _ = lsdc::topology::notation::notation(mechanism, &topology);
    let _ =
        lsdc::studies::analysis::assembled_model(mechanism, topology.clone(), &Default::default());
    if let Ok(equations) = lsdc::symbolic::generate(mechanism, &topology) {
        let _ = lsdc::symbolic::emit::c(&equations, "mutant.lsd");
        let _ = lsdc::symbolic::emit::text(&equations, "mutant.lsd");
    }
    // Every integrator the registry knows, so that a new one is exercised too.
    for integrator in lsdc::integrators::INTEGRATORS
        .iter()
        .map(|e| e.integrator.clone())
    {
        let changes = SettingsChanges {
            integrator: Some(integrator),
            duration: Some(0.01),
            output: Some(0.005),
            step: Some(1e-3),
            tolerance: Some(1e-6),
            ..Default::default()
        };
        let Ok(prepared) = program.prepare(&[], &changes) else {
            return 2;
        };
        let simulation = run(&prepared, &mut |_| {});
        let _ = lsdc::output::csv::to_csv(&simulation);
        let _ = lsdc::output::urdf::export_urdf(&prepared.model, "mutant");
    }
    3
}
