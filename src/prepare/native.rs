//! `simulate --compiled`: the equations of motion as native code. The forward dynamics that
//! `lsdc compile --emit c` writes (the articulated-body recursion unrolled over the program's
//! constants) is compiled by the system's C compiler into a shared library, kept in a cache by
//! the hash of its source, loaded, and checked against the simulator's own right-hand side
//! before the run uses it. Measured 9–35× faster per evaluation than the compiled tape and the
//! articulated-body algorithm (`cargo bench --bench native`, BENCHMARKS.md); it serves trees in
//! the simulator's state (declared coordinates and rates, quaternions and body twists for
//! spherical and free joints: `symbolic::quaternion_joints`), and such mechanisms with loops,
//! whose accelerations are then solved on the run's kept rows in the generated code
//! (`symbolic::kept_rows_solve`). Wherever it cannot serve (no compiler, efforts reading a
//! ball's declared angles, unknown functions, a disagreement), the run goes on without it and
//! says why.

use std::ffi::c_int;
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::elab::mechanism::Mechanism;
use crate::kinematics::eval::UnknownValues;
use crate::symbolic::kept_rows_solve::{solve_on_kept_rows, KeptRows};
use crate::symbolic::quaternion_joints::QuaternionJoins;
use crate::symbolic::{self, Equations};
use crate::topology::Topology;

/// `int forward_dynamics(double t, const double *p, const double *q, const double *k,
/// double *qdd)`, as the C emitter writes it: 0 when q̈ was written.
type ForwardDynamics =
    unsafe extern "C" fn(f64, *const f64, *const f64, *const f64, *mut f64) -> c_int;

/// The loaded forward dynamics of one program, with the values of its parameters.
pub struct NativeDynamics {
    /// Kept loaded for as long as `forward` may be called.
    _library: libloading::Library,
    forward: ForwardDynamics,
    parameters: Vec<f64>,
    /// How many positions and rates it reads (the simulator's state: a ball joint has four
    /// positions, a quaternion, and three rates, its angular velocity).
    pub positions: usize,
    pub dimension: usize,
    /// For a mechanism with loops, the constraint rows its accelerations keep (`KeptRows`):
    /// the code serves the states at which the run keeps the same rows.
    pub kept_rows: Option<Vec<usize>>,
    /// The coordinates whose motions carry no mass that it holds at rest (`LoopRows::held`):
    /// the code serves while the run holds the same.
    pub held: Vec<usize>,
    /// Where the library was loaded from (for the run's report).
    pub path: PathBuf,
}

impl fmt::Debug for NativeDynamics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("NativeDynamics")
            .field("path", &self.path)
            .finish()
    }
}

impl NativeDynamics {
    /// q̈ at (t, p, q) into `accelerations`; false when the native code refused (a singular
    /// mass matrix or a value that is not finite), for the caller to evaluate otherwise.
    #[inline]
    pub fn accelerations(&self, t: f64, p: &[f64], q: &[f64], accelerations: &mut [f64]) -> bool {
        let n = self.dimension;
        assert!(p.len() == self.positions && q.len() == n && accelerations.len() == n);
        // SAFETY: the library was built from the C emitter's source for this program, whose
        // `forward_dynamics` reads its positions, N rates and the parameters and writes N
        // accelerations; the slices have those lengths (checked above) and the library is
        // held loaded by `self`.
        let status = unsafe {
            (self.forward)(
                t,
                p.as_ptr(),
                q.as_ptr(),
                self.parameters.as_ptr(),
                accelerations.as_mut_ptr(),
            )
        };
        status == 0
    }
}

/// Why the native code does not serve a run.
#[derive(Debug)]
pub enum Unavailable {
    /// The mechanism or its efforts are not what the generated code computes.
    Unsupported(String),
    /// The C compiler could not be started.
    NoCompiler { compiler: String, error: String },
    /// It ran and failed.
    CompileFailed { compiler: String, output: String },
    /// The library could not be loaded.
    NotLoaded(String),
    /// Its accelerations differ from the simulator's at the initial state.
    Disagrees { largest: f64 },
}

impl fmt::Display for Unavailable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Unavailable::Unsupported(why) => write!(f, "{why}"),
            Unavailable::NoCompiler { compiler, error } => write!(
                f,
                "no C compiler: `{compiler}` could not be started ({error}); set CC to one"
            ),
            Unavailable::CompileFailed { compiler, output } => {
                write!(f, "`{compiler}` failed on the generated code: {output}")
            }
            Unavailable::NotLoaded(error) => {
                write!(f, "the compiled library did not load: {error}")
            }
            Unavailable::Disagrees { largest } => write!(
                f,
                "its accelerations differ from the simulator's by {largest:e} at the start"
            ),
        }
    }
}

/// What the loops' accelerations are written on (`symbolic::kept_rows_solve`): the rows the run
/// keeps, the coordinates it leaves at rest (idle, and held for carrying no mass), how many
/// coordinates the tree has, and a closed state (positions, rates) at which the elimination's
/// pivots are chosen.
pub struct LoopRows<'a> {
    pub rows: &'a [usize],
    pub at_rest: &'a [usize],
    pub held: &'a [usize],
    pub tree: usize,
    pub state: (&'a [f64], &'a [f64]),
}

/// The program's forward dynamics as native code: generated, compiled (or found in the cache)
/// and loaded, in the simulator's state (`quaternion_joins` the joins it integrates as
/// quaternions). A mechanism with loops needs `loops`.
pub fn build(
    mechanism: &Mechanism,
    topology: &Topology,
    quaternion_joins: QuaternionJoins,
    values: &UnknownValues,
    loops: Option<LoopRows>,
) -> Result<NativeDynamics, Unavailable> {
    let generated = symbolic::generate_in_state(mechanism, topology, quaternion_joins);
    let mut equations = generated.map_err(|refused| {
        let why = refused.first().map_or("", |d| d.message.as_str());
        Unavailable::Unsupported(format!("the equations of motion cannot be written: {why}"))
    })?;
    if !equations.variables.functions.is_empty() {
        return Err(Unavailable::Unsupported(
            "it applies unknown functions".into(),
        ));
    }
    let parameters = parameter_values(&equations, values)?;
    let (kept_rows, held) = match loops {
        Some(loops) if equations.constraint_rows() > 0 => {
            on_kept_rows(&mut equations, &loops, &parameters)?;
            (Some(loops.rows.to_vec()), loops.held.to_vec())
        }
        _ => (None, Vec::new()),
    };
    supported(&equations)?;
    let source = symbolic::emit::c(&equations, "simulate --compiled");
    let path = library_for(&source)?;
    // SAFETY: loading runs the library's initialisers; it is the C emitter's code (math.h
    // only), compiled here, with none.
    let library = unsafe { libloading::Library::new(&path) }
        .map_err(|e| Unavailable::NotLoaded(e.to_string()))?;
    // SAFETY: the emitter writes `forward_dynamics` with the signature `ForwardDynamics`.
    let forward = unsafe { library.get::<ForwardDynamics>(b"forward_dynamics\0") }
        .map(|symbol| *symbol)
        .map_err(|e| Unavailable::NotLoaded(e.to_string()))?;
    Ok(NativeDynamics {
        _library: library,
        forward,
        parameters,
        positions: equations.variables.positions.len(),
        dimension: equations.dimension(),
        kept_rows,
        held,
        path,
    })
}

/// `equations` with their accelerations written on the kept rows of `loops`
/// (`kept_rows_solve`), and their constraint rows then left out: the accelerations are the
/// whole forward dynamics.
fn on_kept_rows(
    equations: &mut Equations,
    loops: &LoopRows,
    parameters: &[f64],
) -> Result<(), Unavailable> {
    let variables = &equations.variables;
    let (positions, rates) = loops.state;
    if positions.len() != variables.positions.len() || rates.len() != variables.rates.len() {
        return Err(Unavailable::Unsupported(
            "its coordinates are not the joints' own".into(),
        ));
    }
    let mut symbols = vec![f64::NAN; equations.pool.symbol_count()];
    let mut put = |id, value| {
        if let Some(i) = equations.pool.symbol_index(id) {
            symbols[i] = value;
        }
    };
    put(variables.time, 0.0);
    for (v, &x) in variables.positions.iter().zip(positions) {
        put(v.symbol, x);
    }
    for (v, &x) in variables.rates.iter().zip(rates) {
        put(v.symbol, x);
    }
    for (v, &x) in variables.parameters.iter().zip(parameters) {
        put(v.symbol, x);
    }
    let kept = KeptRows {
        rows: loops.rows,
        at_rest: loops.at_rest,
        held: loops.held,
        tree: loops.tree,
        symbols: &symbols,
    };
    solve_on_kept_rows(equations, &kept).map_err(|why| {
        Unavailable::Unsupported(format!("the loops' accelerations cannot be written: {why}"))
    })?;
    equations.constraints.clear();
    equations.constraint_bias.clear();
    equations.constraint_names.clear();
    Ok(())
}

/// Whether the emitted forward dynamics is the whole right-hand side: accelerations written out
/// (for a tree by the articulated-body recursion, for loops on their kept rows), with no
/// constraint rows left to solve.
fn supported(equations: &Equations) -> Result<(), Unavailable> {
    let unsupported = |why: &str| Err(Unavailable::Unsupported(why.into()));
    if equations.constraint_rows() > 0 {
        return unsupported("the mechanism has loops, and no rows were given to solve them on");
    }
    if equations.accelerations.is_none() {
        return unsupported("its accelerations are not written by the recursion");
    }
    Ok(())
}

/// The values of the equations' parameters (the program's unknowns), from the run's.
fn parameter_values(
    equations: &Equations,
    values: &UnknownValues,
) -> Result<Vec<f64>, Unavailable> {
    equations
        .variables
        .parameters
        .iter()
        .map(|parameter| {
            let value = parameter.unknown.and_then(|id| values.get(&id).copied());
            value.or(parameter.given).ok_or_else(|| {
                Unavailable::Unsupported(format!("the parameter {} has no value", parameter.name))
            })
        })
        .collect()
}

/// The shared library of `source`: from the cache when it holds this very source, otherwise
/// compiled into it.
fn library_for(source: &str) -> Result<PathBuf, Unavailable> {
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let directory = cache_directory();
    std::fs::create_dir_all(&directory)
        .map_err(|e| Unavailable::NotLoaded(format!("{}: {e}", directory.display())))?;
    let key = format!(
        "{:016x}",
        content_hash(&[source, &compiler, FLAGS.join(" ").as_str()])
    );
    let (c_file, library) = (
        directory.join(format!("{key}.c")),
        directory.join(format!("{key}.{}", std::env::consts::DLL_EXTENSION)),
    );
    // The hash only names the files: the library is used when the source beside it is this
    // one, so a collision can never load the wrong code.
    let cached = std::fs::read_to_string(&c_file).is_ok_and(|held| held == source);
    if cached && library.exists() {
        return Ok(library);
    }
    std::fs::write(&c_file, source)
        .map_err(|e| Unavailable::NotLoaded(format!("{}: {e}", c_file.display())))?;
    compile(&compiler, &c_file, &library)?;
    Ok(library)
}

const FLAGS: [&str; 3] = ["-O2", "-shared", "-fPIC"];

/// Compiles `c_file` into `library`, written under another name first and renamed, so that a
/// run beside this one never loads half a file.
fn compile(compiler: &str, c_file: &Path, library: &Path) -> Result<(), Unavailable> {
    let partial = library.with_extension(format!("{}.part", std::process::id()));
    let output = Command::new(compiler)
        .args(FLAGS)
        .arg(c_file)
        .arg("-o")
        .arg(&partial)
        .arg("-lm")
        .output()
        .map_err(|e| Unavailable::NoCompiler {
            compiler: compiler.to_string(),
            error: e.to_string(),
        })?;
    if !output.status.success() {
        let text = String::from_utf8_lossy(&output.stderr);
        return Err(Unavailable::CompileFailed {
            compiler: compiler.to_string(),
            output: text.lines().take(5).collect::<Vec<_>>().join("\n"),
        });
    }
    std::fs::rename(&partial, library)
        .map_err(|e| Unavailable::NotLoaded(format!("{}: {e}", library.display())))
}

/// `LSDC_CACHE_DIR`, else `$XDG_CACHE_HOME/lsdc`, else `$HOME/.cache/lsdc`, else the temporary
/// directory's `lsdc-cache`.
fn cache_directory() -> PathBuf {
    let from = |variable: &str| std::env::var_os(variable).filter(|v| !v.is_empty());
    if let Some(directory) = from("LSDC_CACHE_DIR") {
        return PathBuf::from(directory);
    }
    if let Some(cache) = from("XDG_CACHE_HOME") {
        return PathBuf::from(cache).join("lsdc");
    }
    if let Some(home) = from("HOME") {
        return PathBuf::from(home).join(".cache").join("lsdc");
    }
    std::env::temp_dir().join("lsdc-cache")
}

/// FNV-1a over the parts (each followed by a zero byte): a name for the cache's files that
/// stays the same from one build of lsdc to the next, which the standard library's hasher
/// does not promise. Written here because it is eight lines and names files only (see
/// `library_for`).
fn content_hash(parts: &[&str]) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in parts.iter().flat_map(|p| p.bytes().chain([0])) {
        hash ^= u64::from(byte);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

/// The largest difference between the native accelerations and `expected` (the simulator's) at
/// (t, p, q), relative to 1 + the largest expected one; infinite when the native code refuses.
pub fn disagreement(
    native: &NativeDynamics,
    t: f64,
    p: &[f64],
    q: &[f64],
    expected: &[f64],
) -> f64 {
    let mut accelerations = vec![0.0; expected.len()];
    if !native.accelerations(t, p, q, &mut accelerations) {
        return f64::INFINITY;
    }
    let scale = 1.0 + expected.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    let largest = accelerations
        .iter()
        .zip(expected)
        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    if largest.is_nan() {
        f64::INFINITY
    } else {
        largest / scale
    }
}
