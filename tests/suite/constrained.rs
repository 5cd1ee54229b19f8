//! A second, independent formulation of closed-loop dynamics, as an oracle for the simulator's:
//! here the constraints are the kinematic closure residual on the declared coordinates (the
//! `lsdc assemble` formulation, not the simulator's velocity-space rows), J̇ v comes from central
//! differences of its exact Jacobian, and the equations are solved by the null-space method. Its
//! accelerations satisfy the constraints, conserve energy when integrated with a projection, and
//! agree with the simulator's right-hand side.

use lsdc::driver::compile_text;
use lsdc::dynamics::algorithms::{crba, rnea};
use lsdc::dynamics::algorithms::{forward_kinematics, Data};
use lsdc::dynamics::energy::{conservative_forces, constant_potential, kinetic_energy};
use lsdc::dynamics::model::{self, Model};
use lsdc::kinematics::assembly::{assemble, AssemblyOptions};
use lsdc::kinematics::closure::closure;
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::initial_coordinates;
use lsdc::kinematics::model::{self as kinematic_model, KinematicModel};
use lsdc::load::LoadOptions;
use lsdc::spatial::Force;
use nalgebra::{DMatrix, DVector};

// ---------------------------------------------------------------------------------------------
// The reference formulation.

/// Relative tolerance below which a singular value of J counts as zero.
const TOLERANCE: f64 = 1e-9;

struct ConstrainedAccelerations {
    /// Accelerations of every coordinate (tree, then complementary links).
    accelerations: DVector<f64>,
    /// Constraint forces, one per closure row (6 per complementary link).
    #[allow(dead_code)]
    multipliers: DVector<f64>,
}

/// J̇ q̇ by a central difference of the closure Jacobian along q̇.
fn jacobian_rate_times_velocity(
    kinematics: &KinematicModel,
    q: &[f64],
    v: &[f64],
) -> Result<DVector<f64>, String> {
    let speed = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let step = 1e-6 / (1.0 + speed);
    let shifted = |sign: f64| -> Result<DMatrix<f64>, String> {
        let moved: Vec<f64> = q.iter().zip(v).map(|(x, r)| x + sign * step * r).collect();
        closure(kinematics, &moved)
            .map(|c| c.jacobian.dense())
            .map_err(|e| format!("{e:?}"))
    };
    let derivative = (shifted(1.0)? - shifted(-1.0)?) / (2.0 * step);
    Ok(derivative * DVector::from_column_slice(v))
}

/// Splits the right singular vectors of `j` into a null-space basis and the pseudo-inverse.
fn null_space_and_pseudo_inverse(j: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = j.ncols();
    let rows = j.nrows().max(n);
    let mut square = DMatrix::zeros(rows, n);
    square.rows_mut(0, j.nrows()).copy_from(j);
    let svd = square.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return (DMatrix::identity(n, n), DMatrix::zeros(n, j.nrows()));
    };
    let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let mut null = Vec::new();
    let mut pseudo = DMatrix::zeros(n, rows);
    for (k, &sigma) in svd.singular_values.iter().enumerate() {
        if sigma <= TOLERANCE * largest || largest == 0.0 {
            null.push(v_t.row(k).transpose());
        } else {
            pseudo += v_t.row(k).transpose() * u.column(k).transpose() / sigma;
        }
    }
    let basis = if null.is_empty() {
        DMatrix::zeros(n, 0)
    } else {
        DMatrix::from_columns(&null)
    };
    (basis, pseudo.columns(0, j.nrows()).into_owned())
}

/// Accelerations and constraint forces of a mechanism with loops at (q, v), under generalised
/// forces `tau` on the tree's coordinates and external forces on the bodies.
fn constrained_accelerations(
    model: &Model,
    kinematics: &KinematicModel,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    external: &[Force],
) -> Result<ConstrainedAccelerations, String> {
    let (nt, n) = (model.nv, kinematics.coordinate_count);
    if model.nq != model.nv {
        return Err(
            "closed loops need joints in their own coordinates (no quaternion joints)".to_string(),
        );
    }
    let mass_tree = crba(model, data, &q[..nt]).map_err(|e| format!("{e:?}"))?;
    let bias = rnea(model, data, &q[..nt], &v[..nt], &vec![0.0; nt], external)
        .map_err(|e| format!("{e:?}"))?;
    let mut mass = DMatrix::zeros(n, n);
    mass.view_mut((0, 0), (nt, nt)).copy_from(&mass_tree);
    let mut force = DVector::zeros(n);
    force
        .rows_mut(0, nt)
        .copy_from(&(DVector::from_column_slice(tau) - bias));
    let jacobian = closure(kinematics, q)
        .map_err(|e| format!("{e:?}"))?
        .jacobian
        .dense();
    let rate = jacobian_rate_times_velocity(kinematics, q, v)?;
    let (null, pseudo_inverse) = null_space_and_pseudo_inverse(&jacobian);
    let particular = -(&pseudo_inverse * &rate);
    let reduced_mass = null.transpose() * &mass * &null;
    let reduced_force = null.transpose() * (&force - &mass * &particular);
    let z = reduced_mass
        .cholesky()
        .ok_or_else(|| {
            "the mechanism has a motion that moves no mass: the constrained mass matrix is singular"
                .to_string()
        })?
        .solve(&reduced_force);
    let accelerations = particular + &null * z;
    let residual_force = &mass * &accelerations - &force;
    let multipliers = pseudo_inverse.transpose() * residual_force;
    Ok(ConstrainedAccelerations {
        accelerations,
        multipliers,
    })
}

// ---------------------------------------------------------------------------------------------

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
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("four_bar.lsd", FOUR_BAR, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let topology = lsdc::topology::build(&mechanism).expect("connected");
    let kinematics = kinematic_model::build(&mechanism, topology.clone(), UnknownValues::new())
        .expect("numeric");
    // The tree's dynamic model: the same mechanism with its complementary link left out.
    let tree_kinematics = KinematicModel {
        joints: kinematics.principal().to_vec(),
        coordinate_count: kinematics.tree_coordinate_count(),
        topology: lsdc::topology::Topology {
            complementary: Vec::new(),
            ..topology
        },
        unknowns: UnknownValues::new(),
    };
    let model = model::build(&mechanism, &tree_kinematics).expect("tree model");
    (mechanism, kinematics, model)
}

fn external_forces(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) -> Vec<Force> {
    forward_kinematics(model, data, q, v).expect("evaluates");
    let declared = lsdc::dynamics::efforts::Declared {
        model,
        coordinates: q,
        rates: v,
        states: &[],
    };
    lsdc::dynamics::efforts::evaluate(model, data, &declared, 0.0)
        .expect("efforts")
        .external
}

fn derivative(
    model: &Model,
    kinematics: &KinematicModel,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> DVector<f64> {
    let nt = model.nv;
    let external = external_forces(model, data, &q[..nt], &v[..nt]);
    constrained_accelerations(model, kinematics, data, q, v, &vec![0.0; nt], &external)
        .expect("regular")
        .accelerations
}

fn energy(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) -> f64 {
    let nt = model.nv;
    forward_kinematics(model, data, &q[..nt], &v[..nt]).expect("evaluates");
    let conservative = conservative_forces(model);
    assert!(conservative.complete, "gravity only");
    kinetic_energy(model, data) + constant_potential(&conservative.constant, data)
}

#[test]
fn accelerations_satisfy_the_constraints() {
    let (mechanism, kinematics, model) = models();
    let mut data = Data::new(&model);
    let (start, fixed) = initial_coordinates(&mechanism, &kinematics).expect("initial");
    let q = assemble(&kinematics, &start, &fixed, &AssemblyOptions::default())
        .expect("assembles")
        .q;
    let j = closure(&kinematics, &q).expect("closure").jacobian.dense();
    // A velocity compatible with the loop.
    let svd = {
        let mut square = nalgebra::DMatrix::zeros(j.ncols().max(j.nrows()), j.ncols());
        square.rows_mut(0, j.nrows()).copy_from(&j);
        square.svd(false, true)
    };
    let smallest = (0..svd.singular_values.len())
        .min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]))
        .expect("values");
    let v: Vec<f64> = svd
        .v_t
        .expect("vectors")
        .row(smallest)
        .iter()
        .map(|x| 2.0 * x)
        .collect();
    assert!((&j * DVector::from_column_slice(&v)).amax() < 1e-10);
    let a = derivative(&model, &kinematics, &mut data, &q, &v);
    // d²/dt² of the closure residual: J a + J̇ v, the latter by differences along the motion.
    let h = 1e-5;
    let at = |t: f64| {
        let moved: Vec<f64> = (0..q.len())
            .map(|i| q[i] + t * v[i] + 0.5 * t * t * a[i])
            .collect();
        closure(&kinematics, &moved).expect("closure").residual
    };
    let second = (at(h) - 2.0 * at(0.0) + at(-h)) / (h * h);
    assert!(
        second.amax() < 1e-4,
        "closure acceleration {}",
        second.amax()
    );
}

#[test]
fn projected_integration_conserves_the_energy() {
    let (mechanism, kinematics, model) = models();
    let mut data = Data::new(&model);
    let (start, fixed) = initial_coordinates(&mechanism, &kinematics).expect("initial");
    let mut q = assemble(&kinematics, &start, &fixed, &AssemblyOptions::default())
        .expect("assembles")
        .q;
    let mut v = vec![0.0; q.len()];
    let free = vec![false; q.len()];
    let e0 = energy(&model, &mut data, &q, &v);
    let h = 1e-3;
    let mut worst: f64 = 0.0;
    let mut moved: f64 = 0.0;
    for _ in 0..2000 {
        let add = |x: &[f64], dx: &DVector<f64>, s: f64| -> Vec<f64> {
            x.iter().zip(dx.iter()).map(|(a, b)| a + s * b).collect()
        };
        let (q0, v0) = (
            DVector::from_column_slice(&q),
            DVector::from_column_slice(&v),
        );
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
        q = assemble(
            &kinematics,
            q_next.as_slice(),
            &free,
            &AssemblyOptions::default(),
        )
        .expect("stays assembled")
        .q;
        let j = closure(&kinematics, &q).expect("closure").jacobian.dense();
        let v_vector = v_next.clone();
        let correction =
            j.clone().pseudo_inverse(1e-12).expect("pseudo-inverse") * (&j * &v_vector);
        v = (v_vector - correction).as_slice().to_vec();
        worst = worst.max((energy(&model, &mut data, &q, &v) - e0).abs());
        moved = moved.max((q[0] - start[0]).abs());
    }
    assert!(moved > 0.3, "the crank falls: moved {moved}");
    assert!(
        worst < 1e-6 * e0.abs().max(1.0),
        "energy error {worst:e} (E0 = {e0})"
    );
}

#[test]
fn the_simulator_agrees_with_the_reference_formulation() {
    let (mechanism, kinematics, tree_model) = models();
    // The simulator's model of the whole mechanism (loops included).
    let topology = lsdc::topology::build(&mechanism).expect("connected");
    let full = model::build(
        &mechanism,
        &kinematic_model::build(&mechanism, topology, UnknownValues::new()).expect("numeric"),
    )
    .expect("model");
    let mut data = Data::new(&tree_model);
    let (start, fixed) = initial_coordinates(&mechanism, &kinematics).expect("initial");
    let reference = start.clone();
    let mut system = lsdc::simulate::system::MechanicalSystem::new(
        &full,
        reference,
        lsdc::dynamics::loops::Stabilisation::Projection,
    );
    for (k, crank) in [0.3, 1.0, 2.2, 4.0].into_iter().enumerate() {
        let mut guess = start.clone();
        guess[0] = crank;
        let q = assemble(&kinematics, &guess, &fixed, &AssemblyOptions::default())
            .expect("assembles")
            .q;
        // A velocity of the loop: the null space of the closure Jacobian, scaled.
        let j = closure(&kinematics, &q).expect("closure").jacobian.dense();
        let svd = j.clone().svd(false, true);
        let smallest = (0..svd.singular_values.len())
            .min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]))
            .expect("values");
        let v: Vec<f64> = svd
            .v_t
            .expect("v")
            .row(smallest)
            .iter()
            .map(|x| (1.0 + k as f64) * x)
            .collect();
        assert!((&j * DVector::from_column_slice(&v)).amax() < 1e-10);
        let expected = derivative(&tree_model, &kinematics, &mut data, &q, &v);
        let mut y = q.clone();
        y.extend_from_slice(&v);
        let mut dydt = vec![0.0; y.len()];
        system.derivative(0.0, &y, &mut dydt).expect("evaluates");
        let actual = &dydt[q.len()..];
        for i in 0..q.len() {
            assert!(
                (actual[i] - expected[i]).abs() < 1e-6 * (1.0 + expected.amax()),
                "crank {crank}: acceleration {i}: {} vs {}",
                actual[i],
                expected[i]
            );
        }
    }
}
