//! The `lsdc` command line: parses the arguments and hands them to the command's file in
//! `cli/` (a module of the library, so that the binary needs nothing else of it), which calls
//! the library and prints the result.
//! Exit codes: 0 clean, 1 errors in the program, 2 usage errors (bad flags, unreadable files).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use cli::shared::{asks_for_json, exit_code, rejected_arguments, set_modes};
use cli::*;
use lsdc::cli;

#[derive(Parser)]
#[command(
    name = "lsdc",
    version,
    about = "Compiler and simulator for LSD mechanism descriptions"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print no warnings (errors are still printed, and JSON results keep theirs).
    #[arg(short, long, global = true)]
    quiet: bool,
}

// Each command's arguments are built only when it is the one invoked (or its help is asked
// for): building all of them was most of a start-up's work (`lsdc --version` ran 0.75 M of its
// 1.31 M instructions building and dropping every command's arguments; BENCHMARKS.md,
// "Start-up: what `lsdc --version` costs").
#[derive(Subcommand)]
#[command(defer = true)]
enum Command {
    /// Check programs and print a summary of the mechanism each describes.
    Check(check::CheckArgs),
    /// Show the breadth-first numbering, principal and complementary links, joint kinds and
    /// the mobility.
    Tree(tree::TreeArgs),
    /// Assemble the mechanism from its `initial` values and print the coordinates.
    Assemble(assemble::AssembleArgs),
    /// Simulate a mechanism (tree or closed loops) from its `initial` values; write the samples
    /// (CSV or JSON) and a run report.
    Simulate(simulate::SimulateArgs),
    /// Run the program many times in one process on every core: over a grid, a list or a
    /// sample (Monte Carlo, Latin hypercube, Sobol) of initial values and values of the
    /// program; a row per run (CSV or Parquet), shards for a job array, `--resume` after an
    /// interruption. `lsdc sweep gather` merges the shards' files.
    Sweep(sweep::SweepArgs),
    /// Speed against error: simulate with several integrators and tolerances (or fixed steps),
    /// compare each run with a tight reference at the outputs, and print the work-precision
    /// table (errors, closure, energy drift, steps, evaluations, CPU time).
    Precision(precision::PrecisionArgs),
    /// Drag a point of a body along a path of targets, quasi-statically: the configuration at
    /// each target, the distance left, the loops' residual or the joints' gap, the energy.
    Drag(drag::DragArgs),
    /// Show the mechanism in 3D in a web page: served on 127.0.0.1 (simulations on demand,
    /// bodies dragged with the mouse), or exported as one standalone HTML file.
    View(view::ViewArgs),
    /// The efforts actuators must apply along the given coordinates to hold the mechanism at
    /// rest in its initial (assembled) configuration.
    Statics(statics::StaticsArgs),
    /// Inverse dynamics along the program's drives (`drive crank.q = law;`, every degree of
    /// freedom driven): the efforts that impose them, the power and, with `--reactions`, every
    /// join's reaction; CSV or JSON.
    Inverse(inverse::InverseArgs),
    /// Estimate bodies' inertial parameters and joints' friction from measured coordinates and
    /// efforts (least squares on the base parameters of the inverse dynamics' regressor).
    Identify(identify::IdentifyArgs),
    /// The linear model (A, B, C, D) of the mechanism about its initial state, a run's state
    /// at a time or an equilibrium, in independent coordinates; eigenvalues and modes.
    Linearize(linearize::LinearizeArgs),
    /// The derivatives of a run's coordinates, rates, states and outputs with respect to
    /// initial values and values of the program, along the run, by the forward sensitivity
    /// equations integrated with it; CSV (`d(swing.q)/d(L)`) or JSON, and a plot.
    Sensitivity(sensitivity::SensitivityArgs),
    /// The velocity and acceleration models from actuated coordinates to a frame (direct and
    /// inverse), their conditioning and singularities, at configurations or along a run.
    Kinematics(kinematics::KinematicsArgs),
    /// The workspace of a point sampled over the actuated coordinates: its volume, boundary,
    /// singular loci and dexterity, as CSV or JSON.
    Workspace(workspace::WorkspaceArgs),
    /// Compile a program and print what `--emit` asks for.
    Compile(compile::CompileArgs),
    /// Evaluate inverse dynamics (RNEA), the mass matrix (CRBA), forward dynamics (ABA) and the
    /// bodies' poses at a list of states; print JSON. A quantity that cannot be computed at a
    /// state (ABA with a singular mass matrix) is null, with the reason in the state's `errors`
    /// and a warning on standard error.
    Eval(eval::EvalArgs),
    /// Write a tree mechanism as a URDF robot description: a link per body, a joint per join.
    ExportUrdf(export_urdf::ExportUrdfArgs),
    /// Write the program as an FMI unit for co-simulation (FMI 3.0, or 2.0 with `--fmi 2`):
    /// lsdc's integrator inside, the coordinates and outputs as outputs, efforts as inputs.
    ExportFmu(export_fmu::ExportFmuArgs),
    /// Translate a URDF robot description into an LSD program (standard output, or `-o`).
    ImportUrdf(import_urdf::ImportUrdfArgs),
    /// Print the syntax tree of a file (for debugging the parser).
    Parse(parse::ParseArgs),
    /// Run the regression cases of test manifests (`lsdtest.toml`): simulate each program,
    /// compare its outputs with a reference within per-variable tolerances, make its checks.
    /// Exit code 0 when every case passes, 1 when one fails, 2 for a manifest that cannot be
    /// read.
    Test(test::TestArgs),
    /// Format LSD files in place (`docs/formatting.md`); directories are searched for `.lsd`
    /// files. Only whitespace changes: every token and comment is kept.
    Fmt(fmt::FmtArgs),
    /// Run the language server on standard input and output (`docs/editors.md`).
    Lsp,
}

fn main() -> ExitCode {
    let arguments: Vec<String> = std::env::args_os()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let json_asked = asks_for_json(&arguments);
    set_modes(false, json_asked);
    let cli = match Cli::try_parse_from(&arguments) {
        Ok(cli) => cli,
        Err(error) => return rejected_arguments(error),
    };
    set_modes(cli.quiet, json_asked);
    let command_code = match cli.command {
        Command::Check(args) => check::run(&args),
        Command::Tree(args) => tree::run(&args),
        Command::Assemble(args) => assemble::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Precision(args) => precision::run(&args),
        Command::Drag(args) => drag::run(&args),
        Command::View(args) => view::run(&args),
        Command::Statics(args) => statics::run(&args),
        Command::Inverse(args) => inverse::run(&args),
        Command::Identify(args) => identify::run(&args),
        Command::Linearize(args) => linearize::run(&args),
        Command::Sensitivity(args) => sensitivity::run(&args),
        Command::Kinematics(args) => kinematics::run(&args),
        Command::Workspace(args) => workspace::run(&args),
        Command::Compile(args) => compile::run(&args),
        Command::Eval(args) => eval::run(&args),
        Command::ExportUrdf(args) => export_urdf::run(&args),
        Command::ExportFmu(args) => export_fmu::run(&args),
        Command::ImportUrdf(args) => import_urdf::run(&args),
        Command::Parse(args) => parse::run(&args),
        Command::Test(args) => test::run(&args),
        Command::Fmt(args) => fmt::run(&args),
        Command::Lsp => lsp::run(),
    };
    exit_code(command_code)
}
