//! The Maple output (`--format maple`) read back by an evaluator of its own (Maple is not at
//! hand): its statements parsed with Maple's precedences and evaluated at random values, equal
//! to the equations it was written from on every example; and golden files for the thesis's
//! satellite and the double pendulum.

use std::collections::HashMap;
use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::symbolic::{self, emit, Equations};

use crate::common::symbolic::Sequence;

/// Values of a Maple worksheet's names: scalars, and the entries of `M`, `S`, … by index.
#[derive(Default)]
struct Worksheet {
    names: HashMap<String, f64>,
    entries: HashMap<(String, Vec<usize>), f64>,
    /// Values of the unknown functions, by name (whatever their arguments).
    functions: HashMap<String, f64>,
}

/// A recursive-descent reader of one Maple expression: sums, products, unary minus, `^` between
/// atoms, calls, `piecewise(test >= 0, a, b)`.
struct Reader<'a> {
    text: &'a [u8],
    at: usize,
    sheet: &'a Worksheet,
}

impl Reader<'_> {
    fn skip(&mut self) {
        while self.at < self.text.len() && self.text[self.at] == b' ' {
            self.at += 1;
        }
    }
    fn peek(&mut self) -> Option<u8> {
        self.skip();
        self.text.get(self.at).copied()
    }
    fn expect(&mut self, token: &str) {
        self.skip();
        assert!(
            self.text[self.at..].starts_with(token.as_bytes()),
            "expected `{token}` at {} in {}",
            self.at,
            String::from_utf8_lossy(self.text)
        );
        self.at += token.len();
    }
    fn sum(&mut self) -> f64 {
        let mut value = self.product();
        loop {
            match self.peek() {
                Some(b'+') => {
                    self.at += 1;
                    value += self.product();
                }
                Some(b'-') => {
                    self.at += 1;
                    value -= self.product();
                }
                _ => return value,
            }
        }
    }
    fn product(&mut self) -> f64 {
        let mut value = self.unary();
        loop {
            match self.peek() {
                Some(b'*') => {
                    self.at += 1;
                    value *= self.power();
                }
                Some(b'/') => {
                    self.at += 1;
                    value /= self.power();
                }
                _ => return value,
            }
        }
    }
    /// A sign only at the start of a product (Maple takes none after `*`, `/` or `^`).
    fn unary(&mut self) -> f64 {
        if self.peek() == Some(b'-') {
            self.at += 1;
            return -self.unary();
        }
        self.power()
    }
    fn power(&mut self) -> f64 {
        let base = self.atom();
        if self.peek() == Some(b'^') {
            self.at += 1;
            return base.powf(self.atom());
        }
        base
    }
    fn word(&mut self) -> String {
        self.skip();
        let start = self.at;
        while self.at < self.text.len()
            && (self.text[self.at].is_ascii_alphanumeric() || self.text[self.at] == b'_')
        {
            self.at += 1;
        }
        String::from_utf8_lossy(&self.text[start..self.at]).to_string()
    }
    fn atom(&mut self) -> f64 {
        match self.peek().expect("an atom") {
            b'(' => {
                self.at += 1;
                let value = self.sum();
                self.expect(")");
                value
            }
            c if c.is_ascii_digit() => {
                let start = self.at;
                while self.at < self.text.len()
                    && (self.text[self.at].is_ascii_digit()
                        || b".eE".contains(&self.text[self.at])
                        || (b"+-".contains(&self.text[self.at])
                            && b"eE".contains(&self.text[self.at - 1])))
                {
                    self.at += 1;
                }
                let number = String::from_utf8_lossy(&self.text[start..self.at]);
                number.parse().expect("a number")
            }
            _ => {
                let name = self.word();
                assert!(!name.is_empty(), "a name at {}", self.at);
                if self.peek() != Some(b'(') {
                    return *(self.sheet.names.get(&name))
                        .unwrap_or_else(|| panic!("`{name}` has no value"));
                }
                self.at += 1;
                if name == "piecewise" {
                    let test = self.sum();
                    self.expect(">=");
                    self.expect("0");
                    self.expect(",");
                    let (when, otherwise) = (self.sum(), {
                        self.expect(",");
                        self.sum()
                    });
                    self.expect(")");
                    return if test >= 0.0 { when } else { otherwise };
                }
                let mut arguments = vec![self.sum()];
                while self.peek() == Some(b',') {
                    self.at += 1;
                    arguments.push(self.sum());
                }
                self.expect(")");
                call(self.sheet, &name, &arguments)
            }
        }
    }
}

fn call(sheet: &Worksheet, name: &str, a: &[f64]) -> f64 {
    match (name, a.len()) {
        ("sin", 1) => a[0].sin(),
        ("cos", 1) => a[0].cos(),
        ("tan", 1) => a[0].tan(),
        ("arcsin", 1) => a[0].asin(),
        ("arccos", 1) => a[0].acos(),
        ("arctan", 1) => a[0].atan(),
        ("arctan", 2) => a[0].atan2(a[1]),
        ("sqrt", 1) => a[0].sqrt(),
        ("exp", 1) => a[0].exp(),
        ("ln", 1) => a[0].ln(),
        ("abs", 1) => a[0].abs(),
        ("floor", 1) => a[0].floor(),
        _ => *(sheet.functions.get(name)).unwrap_or_else(|| panic!("no function `{name}`")),
    }
}

/// Runs the worksheet's assignments (`name := expr;`, `Name[i, j] := expr;`); declarations of
/// matrices and vectors are skipped.
fn run(text: &str, sheet: &mut Worksheet) {
    for line in text.lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let statement = line.strip_suffix(';').expect("a statement ends with `;`");
        let (target, expression) = statement.split_once(" := ").expect("an assignment");
        if expression.starts_with("Matrix(") || expression.starts_with("Vector(") {
            continue;
        }
        let mut reader = Reader {
            text: expression.as_bytes(),
            at: 0,
            sheet,
        };
        let value = reader.sum();
        assert_eq!(reader.peek(), None, "unread text in {line}");
        match target.split_once('[') {
            None => {
                sheet.names.insert(target.to_string(), value);
            }
            Some((name, index)) => {
                let index = (index.trim_end_matches(']').split(", "))
                    .map(|i| i.parse().expect("an index"))
                    .collect();
                sheet.entries.insert((name.to_string(), index), value);
            }
        }
    }
}

/// A Maple name for a program's name, as the documentation describes it: `'` is `_dot`, any
/// other character but letters, digits and `_` is `_`.
fn maple_name(name: &str) -> String {
    name.chars()
        .map(|c| match c {
            '\'' => "_dot".to_string(),
            c if c.is_ascii_alphanumeric() || c == '_' => c.to_string(),
            _ => "_".to_string(),
        })
        .collect()
}

fn equations_of(path: &std::path::Path) -> Option<Equations> {
    let compilation =
        compile_files(&[path.to_path_buf()], &LoadOptions::default()).expect("readable");
    let mechanism = compilation.mechanism.as_ref()?;
    let topology = lsdc::topology::build(mechanism).ok()?;
    symbolic::generate(mechanism, &topology).ok()
}

/// The worksheet's M, S, F, Δ, Δ̇q and accelerations against the equations' at random values.
fn compare(eq: &Equations, text: &str, seed: u64) -> f64 {
    let mut random = Sequence(seed);
    let mut sheet = Worksheet::default();
    let mut by_symbol = HashMap::new();
    let v = &eq.variables;
    for variable in v.positions.iter().chain(&v.rates).chain(&v.parameters) {
        let value = 1.0 + 0.5 * random.next();
        sheet.names.insert(maple_name(&variable.name), value);
        by_symbol.insert(variable.name.clone(), value);
    }
    let time = 1.0 + random.next();
    sheet.names.insert("t".to_string(), time);
    by_symbol.insert("t".to_string(), time);
    for f in &v.functions {
        let value = *(sheet.functions)
            .entry(maple_name(&f.name))
            .or_insert_with(|| random.next());
        by_symbol.insert(
            eq.pool.name_of(f.symbol).expect("a symbol").to_string(),
            value,
        );
    }
    run(text, &mut sheet);
    let symbols = eq
        .symbol_values(|name| by_symbol.get(name).copied())
        .expect("every symbol has a value");
    let at = eq.evaluate(&eq.tape(), &symbols);
    let entry = |name: &str, index: Vec<usize>| {
        sheet
            .entries
            .get(&(name.to_string(), index))
            .copied()
            .unwrap_or(0.0)
    };
    let (n, m) = (eq.dimension(), eq.constraint_rows());
    let mut pairs = Vec::new();
    for i in 0..n {
        for j in i..n {
            pairs.push((entry("M", vec![i + 1, j + 1]), at.mass[(i, j)]));
        }
        pairs.push((entry("S", vec![i + 1]), at.second_member[i]));
        pairs.push((entry("F", vec![i + 1]), at.forces[i]));
        if let Some(a) = &at.accelerations {
            pairs.push((entry("accelerations", vec![i + 1]), a[i]));
        }
        for r in 0..m {
            pairs.push((entry("Delta", vec![r + 1, i + 1]), at.constraints[(r, i)]));
        }
    }
    for r in 0..m {
        pairs.push((entry("Delta_bias", vec![r + 1]), at.constraint_bias[r]));
    }
    let scale = pairs.iter().fold(1.0f64, |s, (_, b)| s.max(b.abs()));
    pairs.iter().fold(0.0f64, |g, (a, b)| g.max((a - b).abs())) / scale
}

#[test]
fn maple_worksheets_evaluate_to_the_equations_on_every_example() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("examples")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lsd"))
        .collect();
    paths.sort();
    let mut read = 0;
    for path in paths {
        let Some(eq) = equations_of(&path) else {
            continue;
        };
        let text = emit::maple(&eq, "example");
        for seed in [3, 4] {
            let gap = compare(&eq, &text, seed);
            assert!(
                gap < 1e-12,
                "{}: the worksheet differs by {gap:e}",
                path.display()
            );
        }
        read += 1;
    }
    assert!(read >= 25, "only {read} worksheets read");
}

/// `tests/maple/NAME.mpl` is `lsdc compile examples/NAME.lsd --emit equations --format maple`.
#[test]
fn maple_worksheets_match_golden_files() {
    let update = std::env::var_os("UPDATE_GOLDEN").is_some();
    for name in ["satellite", "double_pendulum"] {
        let source = format!("examples/{name}.lsd");
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(&source);
        let eq = equations_of(&path).expect("written");
        let actual = emit::maple(&eq, &source);
        let golden = format!("tests/maple/{name}.mpl");
        if update {
            std::fs::write(&golden, &actual).expect("writable");
            continue;
        }
        let expected = std::fs::read_to_string(&golden).unwrap_or_default();
        assert_eq!(actual, expected, "{golden} differs");
    }
}
