//! `lsdc compile FILE --emit WHAT`: the notation table, the equations of motion, or source code
//! that evaluates them.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;

use super::shared::{analysed, usage_error, write_output, Format, LibraryArgs};
use lsdc::elab::Mechanism;

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Emit {
    Notation,
    Equations,
    Rust,
    C,
}

/// How `--emit equations` writes them.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum EquationsFormat {
    Text,
    Latex,
    Sympy,
    Maple,
    Json,
}

/// The level of detail (Papegay 1992, §3.1.1).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum LevelArg {
    Vector,
    Scalar,
}

/// The formalism `--emit equations` derives them by.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum FormArg {
    Lagrange,
    Kane,
    NewtonEuler,
}

impl FormArg {
    fn form(self) -> lsdc::symbolic::Form {
        match self {
            FormArg::Lagrange => lsdc::symbolic::Form::Lagrange,
            FormArg::Kane => lsdc::symbolic::Form::Kane,
            FormArg::NewtonEuler => lsdc::symbolic::Form::NewtonEuler,
        }
    }
}

#[derive(clap::Args)]
pub struct CompileArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// `notation`: the thesis-style notation table (structure, variables, declared and
    /// deduced assignments). `equations`: the equations of motion M q' = S + F + Δᵀ Λ,
    /// Δ q' + Δ̇q = 0 in the `--format` given. `rust`, `c`: source code that evaluates them
    /// and the forward dynamics.
    #[arg(long, value_enum)]
    emit: Emit,
    /// Format of `--emit equations` (default text).
    #[arg(long, value_enum)]
    format: Option<EquationsFormat>,
    /// The formalism of `--emit equations` (default lagrange): `kane`, Kane's equations from
    /// partial velocities; `newton-euler`, the recursive Newton–Euler form. The same equations
    /// by another derivation.
    #[arg(long, value_enum)]
    form: Option<FormArg>,
    /// The level of detail. `equations`: `scalar` (the default) writes every entry in the
    /// coordinates; `vector` the block-matrix equations of the free bodies and their projection
    /// (text only). `notation`: `vector` adds the mass matrix's blocks `MMassMax_i`, `scalar`
    /// also the scalar assignments (`MOR_0_i` as a Bryant matrix).
    #[arg(long, value_enum)]
    level: Option<LevelArg>,
    /// The thesis's own concatenated indices in the notation (`V4T_4_45`, `V1T_1_12`) rather
    /// than the separated ones (`V4T_4_G`, `V1T_1_2`).
    #[arg(long)]
    thesis_indices: bool,
    /// Simplify the equations before writing them (`equations`, `rust`, `c`): like terms
    /// collected, cancellations, sin² + cos² = 1 and the angle sums, common factors taken out.
    #[arg(long)]
    simplify: bool,
    /// Write to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

pub fn run(args: &CompileArgs) -> ExitCode {
    let (emit, format) = (args.emit, args.format);
    if format.is_some() && emit != Emit::Equations {
        return usage_error("`--format` applies to `--emit equations` only");
    }
    if args.form.is_some() && emit != Emit::Equations {
        return usage_error("`--form` applies to `--emit equations` only");
    }
    if (args.level.is_some() || args.thesis_indices)
        && !matches!(emit, Emit::Notation | Emit::Equations)
    {
        return usage_error(
            "`--level` and `--thesis-indices` apply to `--emit notation` and `equations` only",
        );
    }
    let vector_equations = emit == Emit::Equations && args.level == Some(LevelArg::Vector);
    if vector_equations
        && (args.simplify
            || args.form.is_some()
            || format.is_some_and(|f| f != EquationsFormat::Text))
    {
        return usage_error(
            "`--level vector` writes the block-matrix equations as text, without `--form`, `--simplify` or another `--format`",
        );
    }
    if args.thesis_indices && emit == Emit::Equations && !vector_equations {
        return usage_error("`--thesis-indices` applies to the notation and to `--level vector`");
    }
    if args.simplify && emit == Emit::Notation {
        return usage_error("`--simplify` applies to `--emit equations`, `rust` and `c` only");
    }
    let source = args.file.display().to_string();
    let analyse = |mechanism: &Mechanism| {
        let topology = lsdc::topology::build(mechanism)?;
        use lsdc::topology::notation::{notation_with, vector_equations as blocks, Level, Options};
        let options = Options {
            level: match args.level {
                None => Level::Table,
                Some(LevelArg::Vector) => Level::Vector,
                Some(LevelArg::Scalar) => Level::Scalar,
            },
            thesis_indices: args.thesis_indices,
        };
        if emit == Emit::Notation {
            return Ok((notation_with(mechanism, &topology, options), Vec::new()));
        }
        if vector_equations {
            return Ok((blocks(mechanism, &topology, options), Vec::new()));
        }
        let form = args
            .form
            .map_or(lsdc::symbolic::Form::Lagrange, FormArg::form);
        let mut equations = lsdc::symbolic::generate_in(mechanism, &topology, form)?;
        if args.simplify {
            equations = lsdc::symbolic::simplify::simplify_equations(&equations);
        }
        use lsdc::symbolic::emit;
        let text = match (emit, format.unwrap_or(EquationsFormat::Text)) {
            (Emit::Rust, _) => emit::rust(&equations, &source),
            (Emit::C, _) => emit::c(&equations, &source),
            (_, EquationsFormat::Text) => emit::text(&equations, &source),
            (_, EquationsFormat::Latex) => emit::latex(&equations, &source),
            (_, EquationsFormat::Sympy) => emit::sympy(&equations, &source),
            (_, EquationsFormat::Maple) => emit::maple(&equations, &source),
            (_, EquationsFormat::Json) => emit::json(&equations, &source),
        };
        Ok((text, Vec::new()))
    };
    let options = args.libraries.options();
    match analysed(&args.file, &options, Format::Text, analyse) {
        Ok(text) => write_output(args.out.as_deref(), &text),
        Err(code) => code,
    }
}
