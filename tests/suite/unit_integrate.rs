//! Unit tests of `src/integrate/`: the coefficients of the Dormand–Prince and ROS34PW2 methods.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod dopri5 {
    use lsdc::integrate::dopri5::*;

    #[test]
    fn each_stage_sits_at_the_sum_of_its_weights() {
        for (row, c) in A.iter().zip(C) {
            assert!((row.iter().sum::<f64>() - c).abs() < 1e-14);
        }
    }

    #[test]
    fn error_and_dense_weights_vanish_for_constant_derivatives() {
        // The error weights are a difference of two sets of weights summing to one each.
        assert!(ERROR.iter().sum::<f64>().abs() < 1e-14);
        // The dense output's last coefficient must vanish for constant derivatives, where the
        // interpolant is the straight line.
        assert!(DENSE.iter().sum::<f64>().abs() < 1e-14);
    }
}

mod rosenbrock {
    //! Checks ROS34PW2's coefficients against the order conditions of Rosenbrock methods up to
    //! order 3 and of W-methods up to order 2 (Hairer and Wanner, Solving ODEs II, IV.7, Table
    //! 7.1 and (7.24)), its stiff accuracy, and the transformed coefficients the steps use. Its
    //! order 3 with any matrix in place of the Jacobian is measured in `tests/suite/integrators.rs`.

    use lsdc::integrate::rosenbrock::*;
    use nalgebra::{DMatrix, DVector};

    fn matrix(rows: &[[f64; STAGES]; STAGES]) -> DMatrix<f64> {
        DMatrix::from_fn(STAGES, STAGES, |i, j| rows[i][j])
    }

    fn row_sums(m: &DMatrix<f64>) -> DVector<f64> {
        DVector::from_fn(STAGES, |i, _| m.row(i).sum())
    }

    /// Σ b_i, Σ b_i β'_i, Σ b_i α_i², Σ b_i β_ij β'_j, with β = α + Γ less its diagonal.
    fn order_sums(weights: &[f64; STAGES]) -> [f64; 4] {
        let alpha = matrix(&ALPHA);
        let beta = &alpha + matrix(&GAMMA_MATRIX) - DMatrix::identity(STAGES, STAGES) * GAMMA;
        let b = DVector::from_row_slice(weights);
        let (alpha_row, beta_row) = (row_sums(&alpha), row_sums(&beta));
        [
            b.sum(),
            b.dot(&beta_row),
            (0..STAGES).map(|i| b[i] * alpha_row[i].powi(2)).sum(),
            b.dot(&(&beta * &beta_row)),
        ]
    }

    #[test]
    fn the_solution_has_order_three() {
        let [one, two, three_a, three_b] = order_sums(&B);
        assert!((one - 1.0).abs() < 1e-14);
        assert!((two - (0.5 - GAMMA)).abs() < 1e-14);
        assert!((three_a - 1.0 / 3.0).abs() < 1e-14);
        assert!((three_b - (1.0 / 6.0 - GAMMA + GAMMA * GAMMA)).abs() < 1e-14);
    }

    #[test]
    fn the_embedded_solution_has_order_two() {
        let [one, two, ..] = order_sums(&B_EMBEDDED);
        assert!((one - 1.0).abs() < 1e-14);
        assert!((two - (0.5 - GAMMA)).abs() < 1e-14);
    }

    #[test]
    fn both_solutions_keep_order_two_with_any_jacobian() {
        // The W-method's condition of order 2: the terms in J cancel by themselves,
        // Σ b_i α_i = 1/2 and Σ b_i γ_i = 0 (γ_i the row sums of Γ).
        let (alpha, gamma) = (row_sums(&matrix(&ALPHA)), row_sums(&matrix(&GAMMA_MATRIX)));
        for weights in [B, B_EMBEDDED] {
            let b = DVector::from_row_slice(&weights);
            assert!((b.dot(&alpha) - 0.5).abs() < 1e-14);
            assert!(b.dot(&gamma).abs() < 1e-14);
        }
    }

    #[test]
    fn the_method_is_stiffly_accurate() {
        // b is the last row of α + Γ: the solution is the last stage's, and R(∞) = 0.
        for (j, b) in B.iter().enumerate() {
            assert!((b - (ALPHA[STAGES - 1][j] + GAMMA_MATRIX[STAGES - 1][j])).abs() < 1e-14);
        }
    }

    #[test]
    fn the_transformed_coefficients_reproduce_the_standard_form() {
        // With u = Γ k: a = αΓ⁻¹, m = bᵀΓ⁻¹, c = diag(1/γ) − Γ⁻¹.
        let t = Transformed::new();
        let gamma = matrix(&GAMMA_MATRIX);
        let inverse = gamma
            .clone()
            .try_inverse()
            .expect("triangular, nonzero diagonal");
        let a = matrix(&ALPHA) * &inverse;
        let m = DVector::from_row_slice(&B).transpose() * &inverse;
        for i in 0..STAGES {
            assert!((t.m[i] - m[i]).abs() < 1e-13);
            for j in 0..STAGES {
                assert!((t.a[i][j] - a[(i, j)]).abs() < 1e-13);
                let c = if i == j { 1.0 / GAMMA } else { 0.0 } - inverse[(i, j)];
                assert!((t.c[i][j] - c).abs() < 1e-13);
            }
        }
        let error: f64 = (0..STAGES).map(|i| t.e[i] * gamma[(i, 0)]).sum();
        assert!((error - (B[0] - B_EMBEDDED[0])).abs() < 1e-13);
    }
}

mod radau {
    //! Checks Radau IIA's transformation: T⁻¹ is T's inverse, and T⁻¹ A⁻¹ T is the block of
    //! A⁻¹'s real eigenvalue γ and its complex pair α ± iβ that the steps solve with, A being the
    //! method's matrix written from its closed form (Hairer and Wanner, IV.5, Table 5.6).
    use lsdc::integrate::radau::*;
    use nalgebra::Matrix3;

    fn butcher_matrix() -> Matrix3<f64> {
        let s = 6f64.sqrt();
        Matrix3::new(
            (88.0 - 7.0 * s) / 360.0,
            (296.0 - 169.0 * s) / 1800.0,
            (-2.0 + 3.0 * s) / 225.0,
            (296.0 + 169.0 * s) / 1800.0,
            (88.0 + 7.0 * s) / 360.0,
            (-2.0 - 3.0 * s) / 225.0,
            (16.0 - s) / 36.0,
            (16.0 + s) / 36.0,
            1.0 / 9.0,
        )
    }

    fn matrix(rows: &[[f64; 3]; 3]) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| rows[i][j])
    }

    #[test]
    fn the_dense_outputs_quintic_reproduces_a_quintic() {
        use lsdc::integrate::radau::hermite::{divided_differences, newton_form};
        let p = |t: f64| 1.0 - 2.0 * t + 0.5 * t.powi(3) - 3.0 * t.powi(4) + 0.7 * t.powi(5);
        let dp = |t: f64| -2.0 + 1.5 * t * t - 12.0 * t.powi(3) + 3.5 * t.powi(4);
        let times = [0.1, 0.35, 0.5];
        let nodes = [times[0], times[0], times[1], times[1], times[2], times[2]];
        let d = divided_differences(&nodes, times.map(p), times.map(dp));
        for t in [0.0, 0.2, 0.4, 0.45, 0.6] {
            let value = newton_form(&d, &nodes, t);
            assert!(
                (value - p(t)).abs() < 1e-12,
                "{t}: {value} against {}",
                p(t)
            );
        }
    }

    #[test]
    fn the_inverse_transform_inverts_the_transform() {
        let product = matrix(&TRANSFORM_INVERSE) * matrix(&TRANSFORM);
        assert!(
            (product - Matrix3::identity()).abs().max() < 1e-14,
            "{product}"
        );
    }

    #[test]
    fn the_transform_splits_the_inverse_of_a_by_its_eigenvalues() {
        let inverse = butcher_matrix().try_inverse().unwrap();
        let block = matrix(&TRANSFORM_INVERSE) * inverse * matrix(&TRANSFORM);
        let (gamma, sigma) = (real_eigenvalue(), complex_eigenvalue());
        // The steps solve for W₁ + i W₂ with σ = complex_eigenvalue(): the 2 × 2 block is
        // multiplication by σ written on (real, imaginary) parts.
        let expected = Matrix3::new(
            gamma, 0.0, 0.0, 0.0, sigma.re, -sigma.im, 0.0, sigma.im, sigma.re,
        );
        assert!((block - expected).abs().max() < 1e-12, "{block}");
    }
}
