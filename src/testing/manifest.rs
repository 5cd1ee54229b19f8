//! Test manifests (`lsdtest.toml`): which programs to run, with what overrides, against which
//! reference, within which tolerances, and which checks to make. Read with the `toml` crate;
//! every error names the file, line and column (`docs/commands.md`, *test*).

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::prepare::settings::SettingsChanges;
use crate::prepare::{Integrator, Override};

/// The file name `lsdc test DIR` looks for.
pub const MANIFEST_NAME: &str = "lsdtest.toml";

/// Significant digits of a recorded reference unless the manifest says otherwise.
pub const DEFAULT_PRECISION: usize = 12;

/// How a variable's differences over time are summed up into one error (`docs/commands.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Measure {
    /// The worst time: every reference time must be within the tolerance.
    #[default]
    Max,
    /// The last reference time only.
    Final,
    /// The root mean square of the differences against the root mean square of the reference.
    L2,
}

/// A variable's tolerance, as OpenModelica's `compareSimulationResults` reads it: a value is
/// within it when |actual − reference| ≤ max(absolute, relative · max(|actual|, |reference|)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Tolerance {
    pub relative: f64,
    pub absolute: f64,
    pub measure: Measure,
}

impl Tolerance {
    /// The largest difference allowed between two values of this size.
    pub fn allowed(&self, scale: f64) -> f64 {
        self.absolute.max(self.relative * scale)
    }
}

/// What a case expects of a failure (`expect_failure`): any failure, or one whose message has
/// this text.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ExpectedFailure {
    Any,
    Containing(String),
}

/// Checks of a case besides the comparison with its reference.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Checks {
    /// The mobility at the assembled configuration.
    pub mobility: Option<usize>,
    /// Whether the mechanism must assemble without moving a given value (W0801).
    pub assembly: Option<bool>,
    /// Bound on the run report's relative energy drift (or energy balance).
    pub energy_drift: Option<f64>,
    /// Bound on the largest closure residual of the run (positions, before projection too).
    pub closure_residual: Option<f64>,
    pub expect_failure: Option<ExpectedFailure>,
}

/// One test case, its paths resolved against the manifest's folder.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    /// The manifest and the line of the case in it (for messages).
    pub manifest: PathBuf,
    pub line: usize,
    pub program: PathBuf,
    /// The program's scene the case runs (`scene = "NAME"`; its first scene when `None`).
    pub scene: Option<String>,
    pub reference: Option<PathBuf>,
    pub overrides: Vec<Override>,
    pub settings: SettingsChanges,
    /// The variables compared (all of the reference's when `None`).
    pub outputs: Option<Vec<String>>,
    pub tolerance: Tolerance,
    pub variables: BTreeMap<String, Tolerance>,
    pub checks: Checks,
    /// Significant digits of the reference when recorded (`--update`).
    pub precision: usize,
    /// The program's decimal numbers moved by round-off (`--perturb`, and `--calibrate`'s
    /// probe of the geometry); none as the manifest reads.
    pub numbers: Option<crate::elab::Perturbation>,
}

impl Case {
    /// The tolerance of a variable: its own, or the case's.
    pub fn tolerance_of(&self, variable: &str) -> Tolerance {
        self.variables
            .get(variable)
            .copied()
            .unwrap_or(self.tolerance)
    }
}

/// A manifest that cannot be used: where, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct ManifestError {
    pub path: PathBuf,
    /// 1-based line and column, when the error has a place in the file.
    pub position: Option<(usize, usize)>,
    pub message: String,
}

impl fmt::Display for ManifestError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.position {
            Some((line, column)) => write!(
                f,
                "{}:{line}:{column}: {}",
                self.path.display(),
                self.message
            ),
            None => write!(f, "{}: {}", self.path.display(), self.message),
        }
    }
}

impl std::error::Error for ManifestError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    defaults: Defaults,
    #[serde(default, rename = "case")]
    cases: Vec<Spanned<CaseEntry>>,
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct Defaults {
    relative: Option<Spanned<f64>>,
    absolute: Option<Spanned<f64>>,
    measure: Option<Measure>,
    precision: Option<Spanned<usize>>,
}

#[derive(Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ToleranceEntry {
    relative: Option<Spanned<f64>>,
    absolute: Option<Spanned<f64>>,
    measure: Option<Measure>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseEntry {
    name: String,
    program: String,
    scene: Option<String>,
    reference: Option<String>,
    #[serde(default)]
    set: Vec<Spanned<String>>,
    outputs: Option<Vec<String>>,
    #[serde(default)]
    simulate: SimulateEntry,
    relative: Option<Spanned<f64>>,
    absolute: Option<Spanned<f64>>,
    measure: Option<Measure>,
    #[serde(default)]
    variables: BTreeMap<String, ToleranceEntry>,
    #[serde(default)]
    checks: ChecksEntry,
    precision: Option<Spanned<usize>>,
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulateEntry {
    integrator: Option<IntegratorName>,
    duration: Option<f64>,
    every: Option<f64>,
    tolerance: Option<f64>,
    step: Option<f64>,
}

/// An integrator named as the registry names it (`lsdc::integrators`); any other name is an
/// error that lists the known ones.
struct IntegratorName(Integrator);

impl<'de> Deserialize<'de> for IntegratorName {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        Integrator::from_name(&name)
            .map(IntegratorName)
            .map_err(serde::de::Error::custom)
    }
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ChecksEntry {
    mobility: Option<usize>,
    assembly: Option<bool>,
    energy_drift: Option<Spanned<f64>>,
    closure_residual: Option<Spanned<f64>>,
    expect_failure: Option<ExpectFailureEntry>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ExpectFailureEntry {
    Flag(bool),
    Message(String),
}

/// Reads and checks a manifest.
pub fn read(path: &Path) -> Result<Vec<Case>, ManifestError> {
    let text = std::fs::read_to_string(path).map_err(|error| ManifestError {
        path: path.to_path_buf(),
        position: None,
        message: format!("cannot read it: {error}"),
    })?;
    parse(&text, path)
}

/// Checks a manifest's text; `path` places its relative paths and names it in errors.
pub fn parse(text: &str, path: &Path) -> Result<Vec<Case>, ManifestError> {
    let error_at = |span: Option<Range<usize>>, message: String| ManifestError {
        path: path.to_path_buf(),
        position: span.map(|s| line_and_column(text, s.start)),
        message,
    };
    let file: File = toml::from_str(text).map_err(|e| error_at(e.span(), e.message().into()))?;
    let folder = path.parent().unwrap_or(Path::new(""));
    let defaults = Tolerance {
        relative: 0.0,
        absolute: 0.0,
        measure: Measure::Max,
    };
    let entry = ToleranceEntry {
        relative: file.defaults.relative,
        absolute: file.defaults.absolute,
        measure: file.defaults.measure,
    };
    let defaults = entry
        .over(defaults)
        .map_err(|(s, m)| error_at(Some(s), m))?;
    let precision = precision_of(file.defaults.precision, DEFAULT_PRECISION)
        .map_err(|(s, m)| error_at(Some(s), m))?;
    let mut cases: Vec<Case> = Vec::new();
    for entry in file.cases {
        let line = line_and_column(text, entry.span().start).0;
        let span = entry.span();
        let case = resolve(entry.into_inner(), folder, defaults, precision)
            .map_err(|(s, m)| error_at(Some(s), m))?;
        if cases.iter().any(|c| c.name == case.name) {
            return Err(error_at(
                Some(span),
                format!("a second case named `{}`", case.name),
            ));
        }
        cases.push(Case {
            manifest: path.to_path_buf(),
            line,
            ..case
        });
    }
    Ok(cases)
}

/// An error of a manifest's value: its place in the text and what is wrong.
type Placed = (Range<usize>, String);

fn resolve(
    entry: CaseEntry,
    folder: &Path,
    defaults: Tolerance,
    precision: usize,
) -> Result<Case, Placed> {
    let own = ToleranceEntry {
        relative: entry.relative,
        absolute: entry.absolute,
        measure: entry.measure,
    };
    let tolerance = own.over(defaults)?;
    let variables = (entry.variables.into_iter())
        .map(|(name, t)| Ok((name, t.over(tolerance)?)))
        .collect::<Result<_, Placed>>()?;
    let overrides = (entry.set.iter())
        .map(|s| {
            s.get_ref()
                .parse()
                .map_err(|e: crate::kinematics::unknowns::OverrideError| (s.span(), e.to_string()))
        })
        .collect::<Result<_, Placed>>()?;
    Ok(Case {
        name: entry.name,
        manifest: PathBuf::new(),
        line: 0,
        program: folder.join(entry.program),
        scene: entry.scene,
        reference: entry.reference.map(|r| folder.join(r)),
        overrides,
        settings: entry.simulate.changes(),
        outputs: entry.outputs,
        tolerance,
        variables,
        checks: entry.checks.resolve()?,
        precision: precision_of(entry.precision, precision)?,
        numbers: None,
    })
}

impl ToleranceEntry {
    /// This entry's values, the others from `outer`.
    fn over(self, outer: Tolerance) -> Result<Tolerance, Placed> {
        Ok(Tolerance {
            relative: bound(self.relative)?.unwrap_or(outer.relative),
            absolute: bound(self.absolute)?.unwrap_or(outer.absolute),
            measure: self.measure.unwrap_or(outer.measure),
        })
    }
}

impl SimulateEntry {
    fn changes(self) -> SettingsChanges {
        SettingsChanges {
            integrator: self.integrator.map(|IntegratorName(integrator)| integrator),
            duration: self.duration,
            output: self.every,
            tolerance: self.tolerance,
            step: self.step,
            ..SettingsChanges::default()
        }
    }
}

impl ChecksEntry {
    fn resolve(self) -> Result<Checks, Placed> {
        Ok(Checks {
            mobility: self.mobility,
            assembly: self.assembly,
            energy_drift: bound(self.energy_drift)?,
            closure_residual: bound(self.closure_residual)?,
            expect_failure: match self.expect_failure {
                None | Some(ExpectFailureEntry::Flag(false)) => None,
                Some(ExpectFailureEntry::Flag(true)) => Some(ExpectedFailure::Any),
                Some(ExpectFailureEntry::Message(text)) => Some(ExpectedFailure::Containing(text)),
            },
        })
    }
}

/// A tolerance or a bound: a finite number at least 0.
fn bound(value: Option<Spanned<f64>>) -> Result<Option<f64>, Placed> {
    match value {
        Some(v) if !(v.get_ref().is_finite() && *v.get_ref() >= 0.0) => Err((
            v.span(),
            format!(
                "a tolerance or bound must be a finite number ≥ 0, not {}",
                v.get_ref()
            ),
        )),
        other => Ok(other.map(Spanned::into_inner)),
    }
}

/// Significant digits of recorded references: 1 to 17 (17 keeps every bit of a double).
fn precision_of(value: Option<Spanned<usize>>, default: usize) -> Result<usize, Placed> {
    match value {
        Some(p) if !(1..=17).contains(p.get_ref()) => Err((
            p.span(),
            format!(
                "`precision` is a number of significant digits from 1 to 17, not {}",
                p.get_ref()
            ),
        )),
        other => Ok(other.map_or(default, Spanned::into_inner)),
    }
}

/// The 1-based line and column (in characters) of a byte offset.
fn line_and_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// The manifests under `paths`: a file is a manifest; a folder is searched for `lsdtest.toml`
/// files (recursively, in name order).
pub fn discover(paths: &[PathBuf]) -> Result<Vec<PathBuf>, ManifestError> {
    let mut found = Vec::new();
    for path in paths {
        if path.is_dir() {
            search(path, &mut found).map_err(|error| ManifestError {
                path: path.clone(),
                position: None,
                message: format!("cannot read the folder: {error}"),
            })?;
        } else if path.is_file() {
            found.push(path.clone());
        } else {
            return Err(ManifestError {
                path: path.clone(),
                position: None,
                message: "no such file or folder".into(),
            });
        }
    }
    Ok(found)
}

fn search(folder: &Path, found: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(folder)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    entries.sort();
    for entry in entries {
        if entry.is_dir() {
            search(&entry, found)?;
        } else if entry.file_name().is_some_and(|n| n == MANIFEST_NAME) {
            found.push(entry);
        }
    }
    Ok(())
}
