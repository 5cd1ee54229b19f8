//! Efforts written with the state of frames (`position`, `velocity`, `distance`, `orientation`,
//! `angular_velocity`) against the same efforts written with joint coordinates: the elastic
//! pendulum of `examples/elastic_pendulum.lsd`, whose spring, damper and torsion spring are,
//! in its coordinates, −k(r − l0) − c r' along the stretch and kt sin a − ct a' on the swing.

use crate::common::symbolic::Sequence;

use lsdc::driver::compile_text;
use lsdc::dynamics::algorithms::{forward_kinematics, rnea, Data};
use lsdc::dynamics::efforts::{self, Declared};
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};

const IN_COORDINATES: &str = "let k = 200 ; let l0 = 0.5 ; let c = 3 ; let kt = 0.7 ; let ct = 0.2 ;
    let rod = body mass = 0, inertia = 0 end ;
    let bob = body mass = 1.5, iframe = 0, inertia = [0.01, 0.02, 0.03] end ;
    join earth and rod.frame with link(a) dof = a || [0,1,0], torque = [0, kt * sin(a) - ct * a', 0] end as swing ;
    join rod.frame and bob.frame with link(r) dof = [0,0,-r], force = [0, 0, k * (r - l0) + c * r'] end as stretch ;
    apply force value = [0, 0, -9.81 * bob.mass], body = earth end on bob.frame ;";

/// S + F of a program at (coordinates, rates): −RNEA(q, v, 0) with the applied efforts, plus
/// the links' efforts.
fn right_hand_side(text: &str, coordinates: &[f64], rates: &[f64]) -> Vec<f64> {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("program.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("a mechanism");
    let model = prepare(&mechanism, &[], &Settings::default())
        .expect("prepares")
        .model;
    let mut data = Data::new(&model);
    forward_kinematics(&model, &mut data, coordinates, rates).expect("kinematics");
    let declared = Declared {
        model: &model,
        coordinates,
        rates,
        states: &[],
    };
    let efforts = efforts::evaluate(&model, &mut data, &declared, 0.0).expect("efforts");
    let bias = rnea(
        &model,
        &mut data,
        coordinates,
        rates,
        &[0.0, 0.0],
        &efforts.external,
    )
    .expect("RNEA");
    (0..2).map(|k| efforts.tau[k] - bias[k]).collect()
}

#[test]
fn frame_states_give_the_efforts_written_in_coordinates() {
    let with_frames = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/elastic_pendulum.lsd"
    ))
    .expect("example");
    let mut random = Sequence(23);
    for _ in 0..20 {
        let coordinates = [1.5 * random.next(), 0.6 + 0.3 * random.next()];
        let rates = [2.0 * random.next(), 2.0 * random.next()];
        let expected = right_hand_side(IN_COORDINATES, &coordinates, &rates);
        let actual = right_hand_side(&with_frames, &coordinates, &rates);
        for k in 0..2 {
            assert!(
                (actual[k] - expected[k]).abs() < 1e-12 * (1.0 + expected[k].abs()),
                "{k}: {} ≠ {}",
                actual[k],
                expected[k]
            );
        }
    }
}

#[test]
fn frame_states_are_refused_where_the_geometry_must_be_constant() {
    let text = "let b = body mass = 1, iframe = 0, inertia = [1, 1, 1] end ;
        join earth and b.frame with link(x) dof = distance(earth, b) || [0, 0, 1] end ;";
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("geometry.lsd", text, None, &options);
    let mechanism = compilation.mechanism.expect("a mechanism");
    let errors = prepare(&mechanism, &[], &Settings::default())
        .err()
        .expect("refused");
    let message = format!("{errors:?}");
    assert!(message.contains("the state of a frame"), "{message}");
}
