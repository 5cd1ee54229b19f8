//! Unit tests of `src/dynamics/`: spatial algebra and the angles of spherical joints.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod angles {
    use lsdc::dynamics::angles::*;
    use nalgebra::Vector3;

    fn check(axes: [Vector3<f64>; 3], angles: [f64; 3]) {
        let r = rotation_from_angles(&axes, &angles);
        let recovered = angles_from_rotation(&axes, &r, &angles.map(|a| a + 0.01));
        let back = rotation_from_angles(&axes, &recovered);
        assert!(r.angle_to(&back) < 1e-12, "{angles:?} → {recovered:?}");
        for k in 0..3 {
            assert!(
                (recovered[k] - angles[k]).abs() < 1e-9,
                "{angles:?} → {recovered:?}"
            );
        }
    }

    #[test]
    fn euler_and_bryant_angles_round_trip() {
        let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
        check([z, x, z], [0.3, 1.1, -2.0]);
        check([x, y, z], [0.3, -1.1, 2.5]);
        check([z, y, x], [-2.9, 0.4, 0.1]);
    }

    #[test]
    fn at_gimbal_lock_the_rotation_is_still_exact() {
        let (x, z) = (Vector3::x(), Vector3::z());
        let axes = [z, x, z];
        let r = rotation_from_angles(&axes, &[0.7, 0.0, 0.2]);
        let recovered = angles_from_rotation(&axes, &r, &[0.6, 0.01, 0.3]);
        assert!(
            r.angle_to(&rotation_from_angles(&axes, &recovered)) < 1e-12,
            "{recovered:?}"
        );
        assert!((recovered[0] + recovered[2] - 0.9).abs() < 1e-9);
    }
}

mod spatial {
    use lsdc::spatial::*;
    use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};

    fn pose() -> Pose {
        Isometry3::from_parts(
            Translation3::new(0.3, -1.2, 0.7),
            UnitQuaternion::from_euler_angles(0.4, -0.9, 2.1),
        )
    }

    #[test]
    fn power_is_invariant_under_change_of_frame() {
        let m = Motion::new(0.1, 0.2, -0.3, 1.0, -2.0, 0.5);
        let f = Force::new(-0.7, 0.4, 0.9, 2.0, 1.5, -1.0);
        let p = pose();
        let power_child = m.dot(&f);
        let power_parent = motion_to_parent(&p, &m).dot(&force_to_parent(&p, &f));
        assert!((power_child - power_parent).abs() < 1e-12);
        assert!((motion_to_child(&p, &motion_to_parent(&p, &m)) - m).amax() < 1e-12);
        assert!((force_to_child(&p, &force_to_parent(&p, &f)) - f).amax() < 1e-12);
        assert!((motion_matrix_to_child(&p) * motion_to_parent(&p, &m) - m).amax() < 1e-12);
    }

    #[test]
    fn transforms_agree_with_poses() {
        let p = pose();
        let t = Transform::from_pose(&p);
        let m = Motion::new(0.1, 0.2, -0.3, 1.0, -2.0, 0.5);
        let f = Force::new(-0.7, 0.4, 0.9, 2.0, 1.5, -1.0);
        assert!((t.motion_to_child(&m) - motion_to_child(&p, &m)).amax() < 1e-14);
        assert!((t.motion_to_parent(&m) - motion_to_parent(&p, &m)).amax() < 1e-14);
        assert!((t.force_to_parent(&f) - force_to_parent(&p, &f)).amax() < 1e-14);
        let central = Matrix3::new(0.3, 0.01, -0.02, 0.01, 0.5, 0.03, -0.02, 0.03, 0.4);
        let i = inertia(2.5, &Vector3::new(0.1, -0.4, 0.8), &central);
        assert!((t.inertia_to_parent(&i) - inertia_to_parent(&p, &i)).amax() < 1e-13);
    }

    #[test]
    fn articulated_inertias_move_as_with_matrices() {
        // An articulated inertia (a body's less U D⁻¹ Uᵀ for one joint column S, U = I S):
        // symmetric, with a block B that is no longer skew, as ABA hands it to the parent.
        let p = pose();
        let central = Matrix3::new(0.3, 0.01, -0.02, 0.01, 0.5, 0.03, -0.02, 0.03, 0.4);
        let i = inertia(2.5, &Vector3::new(0.1, -0.4, 0.8), &central);
        let s = Motion::new(0.6, 0.0, -0.8, 0.2, 0.1, 0.0);
        let u = i * s;
        let articulated = i - u * u.transpose() / s.dot(&u);
        let moved = Transform::from_pose(&p).inertia_to_parent(&articulated);
        // X*ᵀ I X with 6 × 6 matrices (entries of about 2).
        assert!((moved - inertia_to_parent(&p, &articulated)).amax() < 1e-13);
        assert_eq!(moved, moved.transpose());
    }

    #[test]
    fn compact_inertias_agree_with_matrices() {
        let t = Transform::from_pose(&pose());
        let central = Matrix3::new(0.3, 0.01, -0.02, 0.01, 0.5, 0.03, -0.02, 0.03, 0.4);
        let i = inertia(2.5, &Vector3::new(0.1, -0.4, 0.8), &central);
        let compact = RigidInertia::from_matrix(&i);
        let m = Motion::new(0.1, 0.2, -0.3, 1.0, -2.0, 0.5);
        assert!((compact.times(&m) - i * m).amax() < 1e-14);
        assert!((compact.matrix() - i).amax() < 1e-15);
        let moved = compact.to_parent(&t);
        assert!((moved.times(&m) - t.inertia_to_parent(&i) * m).amax() < 1e-13);
        // The split form against X*ᵀ I X with 6 × 6 matrices (scale of the entries: about 2).
        let split = compact.to_parent_by_split(&t);
        assert!((split.matrix() - inertia_to_parent(&pose(), &i)).amax() < 1e-14);
        assert!((split.matrix() - moved.matrix()).amax() < 1e-14);
        let composed = t * t;
        let twice = t.motion_to_parent(&t.motion_to_parent(&m));
        assert!((composed.motion_to_parent(&m) - twice).amax() < 1e-13);
    }

    #[test]
    fn kinetic_energy_of_a_point_mass() {
        let com = Vector3::new(0.0, 0.0, 2.0);
        let i = inertia(3.0, &com, &Matrix3::zeros());
        let m = Motion::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        // Rotation about x through the origin: the point moves at speed 2.
        assert!((0.5 * m.dot(&(i * m)) - 0.5 * 3.0 * 4.0).abs() < 1e-12);
    }
}
