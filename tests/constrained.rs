//! First steps of closed-loop dynamics: the null-space accelerations of a four-bar under gravity
//! satisfy the constraints, and integrating them (RK4 with the state projected back onto the
//! constraints after each step) conserves the energy.

use lsdc::driver::compile_text;
use lsdc::dynamics::algorithms::{forward_kinematics, Data};
use lsdc::dynamics::constrained::constrained_accelerations;
use lsdc::dynamics::energy::{conservative_forces, kinetic_energy, potential_energy};
use lsdc::dynamics::model::{self, Model};
use lsdc::dynamics::spatial::Force;
use lsdc::kinematics::assembly::{assemble, AssemblyOptions};
use lsdc::kinematics::closure::closure;
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::initial_coordinates;
use lsdc::kinematics::model::{self as kinematic_model, KinematicModel};
use lsdc::load::LoadOptions;
use nalgebra::DVector;

const FOUR_BAR: &str = "import joints; import gravity;\n\
    let crank = body mass = 1, iframe = [0.5, 0, 0] ++ 1, inertia = [0.01, 0.1, 0.1] end;\n\
    let coupler = body mass = 2, iframe = [1.75, 0, 0] ++ 1, inertia = [0.02, 2, 2] end;\n\
    let rocker = body mass = 1.5, iframe = [1.5, 0, 0] ++ 1, inertia = [0.01, 1, 1] end;\n\
    join earth and crank with revolute([0, 0, 1]) as a;\n\
    join [1, 0, 0] ++ 1 @ crank and coupler with revolute([0, 0, 1]) as b;\n\
    join [4, 0, 0] ++ 1 @ earth and rocker with revolute([0, 0, 1]) as d;\n\
    join [3.5, 0, 0] ++ 1 @ coupler and [3, 0, 0] ++ 1 @ rocker with revolute([0, 0, 1]) as c;\n\
    apply weight_in(crank, [0, -9.81, 0]) on crank.iframe;\n\
    apply weight_in(coupler, [0, -9.81, 0]) on coupler.iframe;\n\
    apply weight_in(rocker, [0, -9.81, 0]) on rocker.iframe;\n\
    initial a.q = 1.0, b.q = -0.8, d.q = 1.6, c.q = 0.5;\n";

fn models() -> (lsdc::elab::Mechanism, KinematicModel, Model) {
    let options = LoadOptions { library_dirs: Vec::new(), use_environment: false };
    let compilation = compile_text("four_bar.lsd", FOUR_BAR, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let topology = lsdc::topology::build(&mechanism).expect("connected");
    let kinematics = kinematic_model::build(&mechanism, topology.clone(), UnknownValues::new()).expect("numeric");
    // The tree's dynamic model: the same mechanism with its complementary link left out.
    let tree_kinematics = KinematicModel { joints: kinematics.principal().to_vec(), coordinate_count: kinematics.tree_coordinate_count(), topology: lsdc::topology::Topology { complementary: Vec::new(), ..topology }, unknowns: UnknownValues::new() };
    let model = model::build(&mechanism, &tree_kinematics).expect("tree model");
    (mechanism, kinematics, model)
}

fn external_forces(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) -> Vec<Force> {
    forward_kinematics(model, data, q, v).expect("evaluates");
    let declared = lsdc::dynamics::efforts::Declared { model, coordinates: q, rates: v };
    lsdc::dynamics::efforts::evaluate(model, data, &declared, 0.0).expect("efforts").external
}

fn derivative(model: &Model, kinematics: &KinematicModel, data: &mut Data, q: &[f64], v: &[f64]) -> DVector<f64> {
    let nt = model.nv;
    let external = external_forces(model, data, &q[..nt], &v[..nt]);
    constrained_accelerations(model, kinematics, data, q, v, &vec![0.0; nt], &external).expect("regular").accelerations
}

fn energy(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) -> f64 {
    let nt = model.nv;
    forward_kinematics(model, data, &q[..nt], &v[..nt]).expect("evaluates");
    kinetic_energy(model, data) + potential_energy(&conservative_forces(model).expect("gravity only"), data)
}

#[test]
fn accelerations_satisfy_the_constraints() {
    let (mechanism, kinematics, model) = models();
    let mut data = Data::new(&model);
    let (start, fixed) = initial_coordinates(&mechanism, &kinematics).expect("initial");
    let q = assemble(&kinematics, &start, &fixed, &AssemblyOptions::default()).expect("assembles").q;
    let j = closure(&kinematics, &q).expect("closure").jacobian;
    // A velocity compatible with the loop.
    let svd = {
        let mut square = nalgebra::DMatrix::zeros(j.ncols().max(j.nrows()), j.ncols());
        square.rows_mut(0, j.nrows()).copy_from(&j);
        square.svd(false, true)
    };
    let smallest = (0..svd.singular_values.len()).min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b])).expect("values");
    let v: Vec<f64> = svd.v_t.expect("vectors").row(smallest).iter().map(|x| 2.0 * x).collect();
    assert!((&j * DVector::from_column_slice(&v)).amax() < 1e-10);
    let a = derivative(&model, &kinematics, &mut data, &q, &v);
    // d²/dt² of the closure residual: J a + J̇ v, the latter by differences along the motion.
    let h = 1e-5;
    let at = |t: f64| {
        let moved: Vec<f64> = (0..q.len()).map(|i| q[i] + t * v[i] + 0.5 * t * t * a[i]).collect();
        closure(&kinematics, &moved).expect("closure").residual
    };
    let second = (at(h) - 2.0 * at(0.0) + at(-h)) / (h * h);
    assert!(second.amax() < 1e-4, "closure acceleration {}", second.amax());
}

#[test]
fn projected_integration_conserves_the_energy() {
    let (mechanism, kinematics, model) = models();
    let mut data = Data::new(&model);
    let (start, fixed) = initial_coordinates(&mechanism, &kinematics).expect("initial");
    let mut q = assemble(&kinematics, &start, &fixed, &AssemblyOptions::default()).expect("assembles").q;
    let mut v = vec![0.0; q.len()];
    let free = vec![false; q.len()];
    let e0 = energy(&model, &mut data, &q, &v);
    let h = 1e-3;
    let mut worst: f64 = 0.0;
    let mut moved: f64 = 0.0;
    for _ in 0..2000 {
        let add = |x: &[f64], dx: &DVector<f64>, s: f64| -> Vec<f64> { x.iter().zip(dx.iter()).map(|(a, b)| a + s * b).collect() };
        let (q0, v0) = (DVector::from_column_slice(&q), DVector::from_column_slice(&v));
        let k1v = derivative(&model, &kinematics, &mut data, &q, &v);
        let k1q = v0.clone();
        let (q2, v2) = (add(&q, &k1q, h / 2.0), add(&v, &k1v, h / 2.0));
        let k2v = derivative(&model, &kinematics, &mut data, &q2, &v2);
        let k2q = DVector::from_column_slice(&v2);
        let (q3, v3) = (add(&q, &k2q, h / 2.0), add(&v, &k2v, h / 2.0));
        let k3v = derivative(&model, &kinematics, &mut data, &q3, &v3);
        let k3q = DVector::from_column_slice(&v3);
        let (q4, v4) = (add(&q, &k3q, h), add(&v, &k3v, h));
        let k4v = derivative(&model, &kinematics, &mut data, &q4, &v4);
        let k4q = DVector::from_column_slice(&v4);
        let q_next = q0 + (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (h / 6.0);
        let v_next = v0 + (k1v + k2v * 2.0 + k3v * 2.0 + k4v) * (h / 6.0);
        // Projection onto the constraints: positions by assembly, velocities onto the null space.
        q = assemble(&kinematics, q_next.as_slice(), &free, &AssemblyOptions::default()).expect("stays assembled").q;
        let j = closure(&kinematics, &q).expect("closure").jacobian;
        let v_vector = v_next.clone();
        let correction = j.clone().pseudo_inverse(1e-12).expect("pseudo-inverse") * (&j * &v_vector);
        v = (v_vector - correction).as_slice().to_vec();
        worst = worst.max((energy(&model, &mut data, &q, &v) - e0).abs());
        moved = moved.max((q[0] - start[0]).abs());
    }
    assert!(moved > 0.3, "the crank falls: moved {moved}");
    assert!(worst < 1e-6 * e0.abs().max(1.0), "energy error {worst:e} (E0 = {e0})");
}
