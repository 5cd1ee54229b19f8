//! The mass matrix by Llibre's Mampey recursion (notes/seed-llibre.md §2.4, corrected form,
//! generalised to trees as in §2.6) as an independent check: against the columns of the seed's
//! Newton–Euler recursion with q̈ = e_j, gravity and velocities zero (§2.3), on a geared two-link
//! arm, and against lsdc's CRBA and RNEA (rotors included) on the URDF fixtures and on
//! `examples/geared_arm.lsd`.

use lsdc::dynamics::algorithms::{crba, forward_kinematics, rnea, Data};
use lsdc::dynamics::model::Model;
use lsdc::spatial::Force;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// A tree in the seed's data model at one configuration: body i (1..=n) hangs from `parent[i]`
/// (0 the base) by a one-coordinate joint along `u[i]` (the same components in both bases).
/// `s[i]` carries components in B_i to B_parent, `lam[i]` is O_parent O_i in B_parent (q
/// included); `d[i]` the centre of mass and `inertia[i]` the inertia about it (rotor of the
/// children's actuators included), both in B_i. Actuator i: ratio `alpha[i]`, rotor axis
/// `eps[i]` (in B_parent), rotor moment `jm[i]` about it and `im[i]` across.
#[derive(Clone, Default)]
struct Tree {
    parent: Vec<usize>,
    revolute: Vec<bool>,
    u: Vec<Vector3<f64>>,
    s: Vec<Matrix3<f64>>,
    lam: Vec<Vector3<f64>>,
    m: Vec<f64>,
    d: Vec<Vector3<f64>>,
    inertia: Vec<Matrix3<f64>>,
    alpha: Vec<f64>,
    eps: Vec<Vector3<f64>>,
    jm: Vec<f64>,
    im: Vec<f64>,
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    v.cross_matrix()
}

impl Tree {
    fn n(&self) -> usize {
        self.parent.len() - 1
    }

    fn flags(&self, i: usize) -> (f64, f64) {
        match self.revolute[i] {
            true => (0.0, 1.0),
            false => (1.0, 0.0),
        }
    }

    fn rotor_inertia(&self, i: usize) -> Matrix3<f64> {
        let e = self.eps[i];
        self.jm[i] * e * e.transpose() - self.im[i] * skew(&e) * skew(&e)
    }

    /// Mampey: subtree mass M_k, first moment p_k and inertia K_k about O_k, and the entries
    /// a_kk, a_{k,i} for the ancestors k of i, walking each joint's ancestor path (§2.6).
    fn mampey(&self) -> DMatrix<f64> {
        let n = self.n();
        let mut mass = vec![0.0; n + 1];
        let mut p = vec![Vector3::zeros(); n + 1];
        let mut k_inertia = vec![Matrix3::zeros(); n + 1];
        for k in 1..=n {
            let d = skew(&self.d[k]);
            mass[k] = self.m[k];
            p[k] = -self.m[k] * self.d[k];
            k_inertia[k] = self.inertia[k] - self.m[k] * d * d;
        }
        let mut a = DMatrix::zeros(n, n);
        for k in (1..=n).rev() {
            let (tau, rho) = self.flags(k);
            let u = self.u[k];
            a[(k - 1, k - 1)] = self.alpha[k].powi(2) * self.jm[k]
                + tau * mass[k]
                + rho * u.dot(&(k_inertia[k] * u));
            // The column of joint k seen from its parent's basis, then up the ancestors.
            let parent = self.parent[k];
            if parent == 0 {
                continue;
            }
            let (sk, lam) = (self.s[k], self.lam[k]);
            let pk = sk * p[k];
            let kk = sk * k_inertia[k] * sk.transpose();
            let uk = sk * u;
            let mut r = tau * mass[k] * uk + rho * pk.cross(&uk);
            let mut h = self.alpha[k] * self.jm[k] * self.eps[k]
                + tau * (mass[k] * lam - pk).cross(&uk)
                + rho * (kk * uk + lam.cross(&r));
            let mut i = parent;
            loop {
                let (tau_i, rho_i) = self.flags(i);
                let value = self.u[i].dot(&(tau_i * r + rho_i * h));
                a[(i - 1, k - 1)] = value;
                a[(k - 1, i - 1)] = value;
                let up = self.parent[i];
                if up == 0 {
                    break;
                }
                r = self.s[i] * r;
                h = self.s[i] * h + self.lam[i].cross(&r);
                i = up;
            }
            // Fold subtree k into its parent: K, p, M about O_parent in B_parent.
            let l = skew(&lam);
            let pt = skew(&pk);
            k_inertia[parent] += kk - mass[k] * l * l + l * pt + (l * pt).transpose();
            p[parent] += pk - mass[k] * lam;
            mass[parent] += mass[k];
        }
        a
    }

    /// The seed's Newton–Euler (§2.3, matrix form, corrected) with velocities and gravity zero:
    /// the joint efforts of the accelerations `qdd`. The body inertias here exclude the rotors'
    /// (ℐ' = ℐ − ℐ_m of each child actuator), which enter through M_a.
    fn newton_euler(&self, qdd: &[f64]) -> Vec<f64> {
        let n = self.n();
        let mut omd = vec![Vector3::zeros(); n + 1];
        let mut wd = vec![Vector3::zeros(); n + 1];
        let mut fnet = vec![Vector3::zeros(); n + 1];
        let mut mc = vec![Vector3::zeros(); n + 1];
        let mut ma = vec![Vector3::zeros(); n + 1];
        for i in 1..=n {
            let (tau, rho) = self.flags(i);
            let parent = self.parent[i];
            let st = self.s[i].transpose();
            // The axis in the parent's basis.
            let u = self.s[i] * self.u[i];
            let ommd = omd[parent] + self.alpha[i] * qdd[i - 1] * self.eps[i];
            ma[i] = -(self.rotor_inertia(i) * ommd);
            wd[i] = st * (wd[parent] + omd[parent].cross(&self.lam[i]) + tau * qdd[i - 1] * u);
            omd[i] = st * (omd[parent] + rho * qdd[i - 1] * u);
            let vd = wd[i] + omd[i].cross(&self.d[i]);
            fnet[i] = self.m[i] * vd;
            let own = self.inertia[i] - self.child_rotors(i);
            mc[i] = -(own * omd[i]);
        }
        let mut force = vec![Vector3::zeros(); n + 1];
        let mut moment = vec![Vector3::zeros(); n + 1];
        let mut q = vec![0.0; n];
        for i in (1..=n).rev() {
            let (tau, rho) = self.flags(i);
            // Children's wrenches arrive already in B_i (accumulated below).
            let m_local = moment[i] + self.d[i].cross(&fnet[i]) - mc[i];
            let f_local = force[i] + fnet[i];
            let m_parent = self.s[i] * m_local;
            let f_parent = self.s[i] * f_local;
            q[i - 1] = (tau * f_parent + rho * m_parent).dot(&(self.s[i] * self.u[i]))
                - self.alpha[i] * ma[i].dot(&self.eps[i]);
            let parent = self.parent[i];
            if parent != 0 {
                force[parent] += f_parent;
                moment[parent] += m_parent + self.lam[i].cross(&f_parent) - ma[i];
            }
        }
        q
    }

    /// The rotors mounted on body i (those of its children's actuators), in B_i.
    fn child_rotors(&self, i: usize) -> Matrix3<f64> {
        (1..=self.n())
            .filter(|&c| self.parent[c] == i)
            .map(|c| self.rotor_inertia(c))
            .sum()
    }

    fn newton_euler_columns(&self) -> DMatrix<f64> {
        let n = self.n();
        DMatrix::from_fn(n, n, |row, column| {
            let mut qdd = vec![0.0; n];
            qdd[column] = 1.0;
            self.newton_euler(&qdd)[row]
        })
    }
}

fn rotation(axis: Vector3<f64>, angle: f64) -> Matrix3<f64> {
    nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle).into_inner()
}

/// A two-link arm (shoulder about z, elbow about y) with geared rotors: the elbow's motor
/// on the upper arm (ratio 50), the shoulder's on the base (ratio 100).
fn geared_arm(q: [f64; 2]) -> Tree {
    let (z, y) = (Vector3::z(), Vector3::y());
    let upper_rotor_on_upper = {
        let e = y;
        0.002 * e * e.transpose() - 0.0005 * skew(&e) * skew(&e)
    };
    Tree {
        parent: vec![0, 0, 1],
        revolute: vec![true, true, true],
        u: vec![Vector3::zeros(), z, y],
        s: vec![Matrix3::identity(), rotation(z, q[0]), rotation(y, q[1])],
        lam: vec![
            Vector3::zeros(),
            Vector3::new(0.0, 0.0, 0.3),
            Vector3::new(0.4, 0.05, 0.0),
        ],
        m: vec![0.0, 3.0, 1.5],
        d: vec![
            Vector3::zeros(),
            Vector3::new(0.2, 0.01, 0.02),
            Vector3::new(0.25, 0.0, -0.01),
        ],
        inertia: vec![
            Matrix3::zeros(),
            Matrix3::from_diagonal(&Vector3::new(0.01, 0.05, 0.05)) + upper_rotor_on_upper,
            Matrix3::from_diagonal(&Vector3::new(0.004, 0.02, 0.021)),
        ],
        alpha: vec![0.0, 100.0, 50.0],
        eps: vec![Vector3::zeros(), z, y],
        jm: vec![0.0, 3e-5, 0.002],
        im: vec![0.0, 1e-5, 0.0005],
    }
}

fn largest_difference(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax()
}

#[test]
fn mampey_equals_newton_euler_columns_on_a_geared_arm() {
    for q in [[0.0, 0.0], [0.7, -1.2], [2.5, 0.4]] {
        let arm = geared_arm(q);
        let mampey = arm.mampey();
        let columns = arm.newton_euler_columns();
        let scale = mampey.amax();
        assert!(
            largest_difference(&mampey, &columns) <= 1e-12 * scale,
            "{mampey}{columns}"
        );
        // The reflected inertias α² j_m sit on the diagonal: 100² × 3e-5 on the shoulder,
        // 50² × 0.002 on the elbow.
        let bare = Tree {
            alpha: vec![0.0; 3],
            ..arm.clone()
        }
        .mampey();
        assert!((mampey[(0, 0)] - bare[(0, 0)] - 0.3).abs() < 1e-12);
        assert!((mampey[(1, 1)] - bare[(1, 1)] - 5.0).abs() < 1e-12);
    }
}

/// The seed's data of lsdc's model at q (a tree of one-coordinate joints whose child frame's
/// origin lies on the joint axis), its geared rotors included.
fn tree_of(model: &Model, data: &Data) -> Tree {
    let n = model.nv;
    let mut tree = Tree {
        parent: vec![0],
        revolute: vec![true],
        u: vec![Vector3::zeros()],
        s: vec![Matrix3::identity()],
        lam: vec![Vector3::zeros()],
        m: vec![0.0],
        d: vec![Vector3::zeros()],
        inertia: vec![Matrix3::zeros()],
        alpha: vec![0.0; n + 1],
        eps: vec![Vector3::zeros(); n + 1],
        jm: vec![0.0; n + 1],
        im: vec![0.0; n + 1],
    };
    let mut number = vec![0usize; model.body_count() + 1];
    let mut index = 0;
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        if joint.nv() == 0 && number[joint.dynamic_parent] == 0 {
            // A body welded to the base moves with it: it is part of the base.
            continue;
        }
        assert_eq!(joint.nv(), 1, "one-coordinate joints only");
        assert_eq!(joint.v_offset, index, "velocities in joint order");
        number[joint.child] = index + 1;
        let state = &data.states[k];
        let column = state.subspace.column(0);
        let (angular, linear) = (
            column.fixed_rows::<3>(0).into_owned(),
            column.fixed_rows::<3>(3).into_owned(),
        );
        let revolute = angular.norm() > 0.5;
        if revolute {
            assert!(
                linear.norm() < 1e-12,
                "the axis must pass through the child's origin"
            );
        }
        tree.parent.push(number[joint.dynamic_parent]);
        tree.revolute.push(revolute);
        tree.u.push(if revolute { angular } else { linear });
        tree.s.push(state.transform.rotation);
        tree.lam.push(state.transform.translation);
        let body = &model.dynamic_bodies[joint.child - 1];
        let c = body.com;
        tree.m.push(body.mass);
        tree.d.push(c);
        let about_origin = body.rigid.rotational;
        tree.inertia
            .push(about_origin + body.mass * skew(&c) * skew(&c));
        index += 1;
    }
    // Geared rotors carried by the parent: actuator i's ratio, axis in B_parent, moment; the
    // parent's full inertia includes the rotor's, as the seed's bookkeeping has it.
    for rotor in &model.rotors {
        let i = number[model.joints[rotor.joint].child];
        let parent = tree.parent[i];
        assert_eq!(number[rotor.carrier], parent, "a rotor on the parent");
        tree.alpha[i] = rotor.ratio;
        tree.eps[i] = rotor.axis;
        tree.jm[i] = rotor.inertia;
        if parent != 0 {
            tree.inertia[parent] += rotor.inertia * rotor.axis * rotor.axis.transpose();
        }
    }
    tree
}

fn check_against_crba_and_rnea(model: &Model, q: &[f64], what: &str) {
    let mut data = Data::new(model);
    let mass = crba(model, &mut data, q).expect("crba");
    forward_kinematics(model, &mut data, q, &vec![0.0; model.nv]).expect("kinematics");
    let tree = tree_of(model, &data);
    let mampey = tree.mampey();
    let external = vec![Force::zeros(); model.body_count() + 1];
    let mut no_gravity = model.clone();
    no_gravity.gravity = Vector3::zeros();
    let columns = DMatrix::from_fn(model.nv, model.nv, |row, column| {
        let mut a = vec![0.0; model.nv];
        a[column] = 1.0;
        rnea(
            &no_gravity,
            &mut Data::new(&no_gravity),
            q,
            &vec![0.0; model.nv],
            &a,
            &external,
        )
        .expect("rnea")[row]
    });
    let scale = mass.amax();
    let against_crba = largest_difference(&mampey, &mass) / scale;
    let against_rnea = largest_difference(&mampey, &columns) / scale;
    assert!(
        against_crba <= 1e-12,
        "{what}: Mampey − CRBA {against_crba:e}\n{mampey}{mass}{columns}"
    );
    assert!(
        against_rnea <= 1e-12,
        "{what}: Mampey − RNEA columns {against_rnea:e}"
    );
    let newton_euler = tree.newton_euler_columns();
    assert!(
        largest_difference(&newton_euler, &mass) / scale <= 1e-12,
        "{what}: seed NE"
    );
}

#[test]
fn mampey_equals_crba_and_rnea_columns_on_the_urdf_fixtures_and_a_geared_arm() {
    let paths = ["ur5", "panda", "kinova", "double_pendulum"]
        .map(|robot| format!("tests/fixtures/urdf/{robot}.urdf"));
    for path in paths.iter().chain([&"examples/geared_arm.lsd".to_string()]) {
        let robot = path.as_str();
        let prepared = crate::common::programs::prepared_file(robot);
        let model = &prepared.model;
        for seed in 0..3 {
            let q: Vec<f64> = (0..model.nq)
                .map(|i| ((i * 7 + seed * 13) as f64 * 0.37).sin())
                .collect();
            check_against_crba_and_rnea(model, &q, robot);
        }
    }
}

/// The rotors' inverse dynamics (their torques, gyroscopic ones included) is consistent with
/// their kinetic energy ½ J (ε·ω_B + n q̇)²: the geared arm under gravity conserves energy.
#[test]
fn the_geared_arm_conserves_its_energy_rotors_included() {
    let compilation = lsdc::driver::compile_files(
        &[std::path::PathBuf::from("examples/geared_arm.lsd")],
        &lsdc::load::LoadOptions {
            library_dirs: Vec::new(),
            use_environment: false,
            scene: None,
        },
    )
    .expect("loads");
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = lsdc::prepare::prepare(&mechanism, &[], &Default::default())
        .unwrap_or_else(|d| panic!("{d:?}"));
    let simulation = lsdc::simulate::run::run(&prepared, &mut |_| {});
    assert!(simulation.report.failure.is_none());
    let drift = simulation.report.energy_drift.expect("conservative");
    assert!(drift < 1e-9, "energy drift {drift:e}");
    // Without the gyroscopic and coupling terms the drift would be of the order of the
    // rotors' share of the kinetic energy; the run is not trivially at rest either.
    let last = simulation.samples.last().expect("samples");
    assert!(last.kinetic_energy > 0.1, "{}", last.kinetic_energy);
}
