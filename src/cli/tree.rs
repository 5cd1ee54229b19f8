//! `lsdc tree FILE`: the breadth-first numbering, principal and complementary links, joint
//! kinds and the mobility; with `--exact`, the exact rank of the loops' constraints at a closed
//! configuration, the kernel Ψ and the reduced equations.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{report, usage_error, Format, LibraryArgs};
use lsdc::elab::Mechanism;
use lsdc::kinematics::exact::Given;

#[derive(clap::Args)]
pub struct TreeArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
    /// The rank of the loops' constraints computed exactly at a closed configuration, with the
    /// kernel Ψ and the reduced equations (see docs/commands.md, `tree --exact`).
    #[arg(long)]
    exact: bool,
    /// With `--exact`: a coordinate's exact value, held by the assembly: `crank.q=t:1/2` (an
    /// angle by the tangent of its half), `crank.q=deg:120`, `slider.x=3/4` (a length; decimals
    /// are exact), `crank.q=0`; `*=0` for every coordinate not given by name.
    #[arg(long = "at", value_name = "NAME=VALUE", requires = "exact")]
    at: Vec<String>,
}

pub fn run(args: &TreeArgs) -> ExitCode {
    let options = args.libraries.options();
    if args.exact {
        let given = match args.at.iter().map(|a| Given::parse(a)).collect() {
            Ok(given) => given,
            Err(message) => return usage_error(&format!("--at {message}")),
        };
        let given: Vec<Given> = given;
        let analyse = |mechanism: &Mechanism| {
            lsdc::studies::exact_mobility::exact_tree(mechanism, &given).map(|r| (r, Vec::new()))
        };
        return report(
            &args.file,
            &options,
            args.format,
            analyse,
            lsdc::output::exact_mobility::exact_tree,
        );
    }
    let analyse = |mechanism: &Mechanism| {
        lsdc::studies::analysis::tree(mechanism).map(|mut report| {
            let warnings = std::mem::take(&mut report.warnings);
            (report, warnings)
        })
    };
    report(
        &args.file,
        &options,
        args.format,
        analyse,
        lsdc::output::text::tree,
    )
}
