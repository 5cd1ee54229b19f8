//! Unit tests of `src/integrate/`: the coefficients of the Dormand–Prince and RODAS3 methods.
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
    //! Checks the coefficients against the order conditions of Rosenbrock methods (Hairer and
    //! Wanner, Solving ODEs II, IV.7, Table 7.1), after converting them back from the transformed
    //! form: Γ = (I/γ − C)⁻¹, α = A Γ, b = M Γ.

    use lsdc::integrate::rosenbrock::*;
    use nalgebra::{DMatrix, DVector};

    fn matrix(rows: &[[f64; STAGES]; STAGES]) -> DMatrix<f64> {
        DMatrix::from_fn(STAGES, STAGES, |i, j| rows[i][j])
    }

    fn gamma_matrix() -> DMatrix<f64> {
        let inverse = DMatrix::identity(STAGES, STAGES) / GAMMA - matrix(&C);
        inverse
            .try_inverse()
            .expect("I/γ − C is triangular with a nonzero diagonal")
    }

    /// Σ b_i, Σ b_i β'_i, Σ b_i α_i², Σ b_i β_ij β'_j for weights `weights` (in the transformed form).
    fn order_sums(weights: &[f64; STAGES]) -> [f64; 4] {
        let gamma = gamma_matrix();
        let alpha = matrix(&A) * &gamma;
        let b = DVector::from_row_slice(weights).transpose() * &gamma;
        let beta = &alpha + &gamma - DMatrix::identity(STAGES, STAGES) * GAMMA;
        let beta_row: DVector<f64> = DVector::from_fn(STAGES, |i, _| beta.row(i).sum());
        let alpha_row: DVector<f64> = DVector::from_fn(STAGES, |i, _| alpha.row(i).sum());
        [
            b.sum(),
            (&b * &beta_row)[0],
            (0..STAGES).map(|i| b[i] * alpha_row[i].powi(2)).sum(),
            (&b * &beta * &beta_row)[0],
        ]
    }

    #[test]
    fn the_solution_has_order_three() {
        let [one, two, three_a, three_b] = order_sums(&M);
        assert!((one - 1.0).abs() < 1e-14);
        assert!((two - (0.5 - GAMMA)).abs() < 1e-14);
        assert!((three_a - 1.0 / 3.0).abs() < 1e-14);
        assert!((three_b - (1.0 / 6.0 - GAMMA + GAMMA * GAMMA)).abs() < 1e-14);
    }

    #[test]
    fn the_embedded_solution_has_order_two() {
        let embedded: [f64; STAGES] = std::array::from_fn(|i| M[i] - E[i]);
        let [one, two, ..] = order_sums(&embedded);
        assert!((one - 1.0).abs() < 1e-14);
        assert!((two - (0.5 - GAMMA)).abs() < 1e-14);
    }

    #[test]
    fn time_fractions_and_gamma_sums_match_the_matrices() {
        let gamma = gamma_matrix();
        let alpha = matrix(&A) * &gamma;
        for i in 0..STAGES {
            assert!((alpha.row(i).sum() - ALPHA[i]).abs() < 1e-14);
            assert!((gamma.row(i).sum() - GAMMA_SUM[i]).abs() < 1e-14);
        }
    }
}
