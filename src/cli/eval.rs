//! `lsdc eval FILE --states states.json`: inverse dynamics, mass matrix, forward dynamics and
//! the bodies' poses at a list of states, as JSON; `--derivatives` adds their derivatives.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{
    err, json, out, prepare_file, refuse_imposed_motion, usage_error, warn, Format, LibraryArgs,
};
use lsdc::api::{evaluate, evaluate_with_derivatives, parse_states};

#[derive(clap::Args)]
pub struct EvalArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// JSON file of states: {"states": [{"q": [..], "v": [..], "a": [..], "tau": [..]}]}.
    #[arg(long)]
    states: PathBuf,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Adds the analytical derivatives of RNEA and ABA with respect to q, v and tau, and of the
    /// mass matrix with respect to q.
    #[arg(long)]
    derivatives: bool,
}

pub fn run(args: &EvalArgs) -> ExitCode {
    let inputs = match std::fs::read_to_string(&args.states)
        .map_err(|e| e.to_string())
        .and_then(|text| parse_states(&text).map_err(|e| e.to_string()))
    {
        Ok(inputs) => inputs,
        Err(message) => {
            return usage_error(&format!(
                "cannot read states from `{}`: {message}",
                args.states.display()
            ))
        }
    };
    let (program, prepared) =
        match prepare_file(&args.file, &args.libraries, &args.sets, Format::Text) {
            Ok(prepared) => prepared,
            Err(code) => return code,
        };
    let help = "its forward dynamics would leave the drives' rows out: `lsdc simulate` integrates the driven mechanism and `lsdc inverse` gives the efforts that impose the motion";
    if let Err(code) = refuse_imposed_motion(&program, "`lsdc eval`", help, Format::Text) {
        return code;
    }
    let evaluation = match args.derivatives {
        true => evaluate_with_derivatives(&prepared, &inputs),
        false => evaluate(&prepared, &inputs),
    };
    match evaluation {
        Ok(evaluation) => {
            let failed = evaluation.states.iter().enumerate();
            for (index, state) in failed.filter(|(_, s)| !s.errors.is_empty()) {
                let errors: Vec<String> = (state.errors.iter())
                    .map(|(quantity, message)| format!("{quantity}: {message}"))
                    .collect();
                warn(&format!("state {index}: {}", errors.join("; ")));
            }
            out(&json(&evaluation));
            ExitCode::SUCCESS
        }
        Err(error) => {
            err(&format!("error: {error}\n"));
            ExitCode::from(1)
        }
    }
}
