//! The integrator registry (`lsdc::integrators`) and its readers: every name parses back to its
//! integrator wherever names are read (programs, test manifests, the command line), an unknown
//! name is an error that names the known ones, and a refusal names what is not handled and
//! which integrators handle it.

use std::path::Path;

use lsdc::integrators::{Feature, Integrator, INTEGRATORS};
use lsdc::testing::manifest;

use crate::common::lsdc;
use crate::common::programs::refusal_codes;

#[test]
fn every_name_reads_back_as_its_integrator() {
    for entry in INTEGRATORS {
        assert_eq!(
            Integrator::from_name(entry.name),
            Ok(entry.integrator.clone())
        );
        assert_eq!(entry.integrator.name(), entry.name);
        assert!(!entry.description.is_empty());
    }
    assert_eq!(
        Integrator::from_name("dopri5"),
        Ok(Integrator::DormandPrince)
    );
}

#[test]
fn an_unknown_name_is_an_error_naming_the_known_ones() {
    let message = Integrator::from_name("rk5")
        .expect_err("unknown")
        .to_string();
    assert!(message.contains("did you mean `rk4`?"), "{message}");
    for entry in INTEGRATORS {
        assert!(message.contains(entry.name), "{message}");
    }
    let text =
        "[[case]]\nname = \"a\"\nprogram = \"a.lsd\"\nsimulate = { integrator = \"dopri8\" }\n";
    let error = manifest::parse(text, Path::new("lsdtest.toml")).expect_err("unknown");
    assert!(
        error.message.contains("unknown integrator `dopri8`"),
        "{error}"
    );
    assert!(error.message.contains("did you mean `dopri5`?"), "{error}");
    let program = "import joints;\nlet b = body mass = 1 end;\njoin earth and b with revolute([0, 0, 1]) as j;\nsimulate duration = 1, integrator = rk5 end;\n";
    let codes = refusal_codes(program);
    assert!(codes.iter().any(|c| c == "E0420"), "{codes:?}");
}

#[test]
fn the_command_line_lists_and_checks_the_registry() {
    let (code, out, _) = lsdc(&["simulate", "--help"]);
    assert_eq!(code, 0);
    for entry in INTEGRATORS {
        assert!(
            out.contains(entry.name) && out.contains(entry.description),
            "{out}"
        );
    }
    let (code, _, err) = lsdc(&["simulate", "--integrator", "rk5", "examples/pendulum.lsd"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("rk4") && err.contains("symplectic"), "{err}");
}

#[test]
fn a_refusal_names_what_is_not_handled_and_who_handles_it() {
    assert_eq!(
        Integrator::Rk4.refusal(&[Feature::Stops, Feature::Contacts]),
        None
    );
    let refusal = Integrator::Symplectic
        .refusal(&[Feature::Stops, Feature::Friction])
        .expect("refused");
    assert_eq!(
        refusal,
        "the symplectic integrator does not handle stops (links' `lower` and `upper`) nor joint \
         friction: use `rk4`, `dopri5`, `dop853` or `implicit`"
    );
}
