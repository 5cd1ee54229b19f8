//! The shared library an FMI unit carries (`lsdc export-fmu`): the one given by `--library`
//! or LSDC_FMI_LIBRARY, else the repository's `fmi/` crate built by Cargo in the repository's
//! `target/` (its `dev` profile, lsdc's build flags: the dependencies lsdc's own build
//! compiled are reused; lsdc, a dependency of another workspace there, is compiled once more;
//! BENCHMARKS.md, "FMI units").

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository this lsdc was built from (its `fmi/` crate, when it has one).
const REPOSITORY: &str = env!("CARGO_MANIFEST_DIR");

/// The shared library to put in a unit: `given`, else LSDC_FMI_LIBRARY, else the `fmi/`
/// crate's, built now (a second or less when it is up to date).
pub fn locate(given: Option<&Path>) -> Result<PathBuf, String> {
    let named = given
        .map(Path::to_path_buf)
        .or_else(|| std::env::var_os("LSDC_FMI_LIBRARY").map(PathBuf::from));
    if let Some(path) = named {
        return if path.is_file() {
            Ok(path)
        } else {
            Err(format!(
                "no shared library at `{}` (from --library or LSDC_FMI_LIBRARY)",
                path.display()
            ))
        };
    }
    let repository = Path::new(REPOSITORY);
    let manifest = repository.join("fmi").join("Cargo.toml");
    if !manifest.is_file() {
        return Err("no FMI shared library: this lsdc was not built in a checkout with `fmi/Cargo.toml`; give one with --library PATH or LSDC_FMI_LIBRARY (built by `cargo build --manifest-path fmi/Cargo.toml` in lsdc's repository)".to_string());
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| repository.join("target"));
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    super::shared::err(
        "building the unit's shared library (cargo build --manifest-path fmi/Cargo.toml)\n",
    );
    // From the repository's root, so that its `.cargo/config.toml` gives the build lsdc's flags.
    let status = Command::new(&cargo)
        .args(["build", "--locked", "--quiet", "--lib", "--manifest-path"])
        .arg(&manifest)
        .env("CARGO_TARGET_DIR", &target)
        .current_dir(repository)
        .status()
        .map_err(|e| format!("cannot run `{}`: {e}", Path::new(&cargo).display()))?;
    if !status.success() {
        return Err(format!(
            "building the FMI shared library failed ({status}); give one with --library PATH"
        ));
    }
    let name = format!(
        "{}lsdc_fmi{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    );
    let library = target.join("debug").join(name);
    if library.is_file() {
        Ok(library)
    } else {
        Err(format!("Cargo built no `{}`", library.display()))
    }
}
