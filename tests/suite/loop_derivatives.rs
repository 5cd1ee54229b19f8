//! The derivatives of the constrained forward dynamics (`loops::derivatives`) against two
//! oracles that share none of their algebra:
//!
//! - central differences of the simulator's own constrained solve (the null-space method on the
//!   kept rows, `allowed_motions` then `solve_reduced`, without stabilisation), in all the
//!   state's velocities and, through the linearisation's chart (`Chart::state`: the loops
//!   closed at given independent coordinates, the dependent rates solved from G v = 0), in
//!   the independent coordinates; accepted at 1e-6 of the largest entry (`mismatch`);
//! - dual numbers through a dense saddle-point solve written here, M from RNEA's columns
//!   (M eⱼ = RNEA(q, 0, eⱼ) − RNEA(q, 0, 0)), G and γ from the loops' rows, all in `Dual64`,
//!   one direction per velocity; in the independent coordinates the positions move along T eₖ
//!   (exact to first order, all that dual numbers see) and the rates solve [Eᵀ; G(q)] v = [ż; 0]
//!   in dual numbers. Accepted at 1e-12.
//!
//! On the random four-bars and Bennett linkages of `loop_properties` and on the examples with
//! loops whose rows evaluate in dual numbers (`dual_numbers::loop_examples`), at their assembled
//! states, with generalised forces on every velocity and external forces on every body.

use lsdc::dynamics::algorithms::{forward_kinematics, rnea, rnea_forward, Data};
use lsdc::dynamics::loops::derivatives::{
    ConstrainedDerivativeError, ConstrainedDerivatives, IndependentDerivatives,
};
use lsdc::dynamics::loops::{
    allowed_motions, constraints_into, solve_reduced, Constraints, Extent, LoopScratch, Method,
    Stabilisation, Structure,
};
use lsdc::dynamics::model::Model;
use lsdc::prepare::Prepared;
use lsdc::spatial::Force;
use lsdc::studies::linearize::chart::Chart;
use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;
use proptest::prelude::*;

use crate::derivatives::mismatch;
use crate::dual_numbers::{
    assembled, constant, loop_examples, parts, position_rate, seeded, tangent,
};
use crate::loop_properties::{bennett, bennett_draws, four_bar, four_bar_draws};

const DIFFERENCES: f64 = 1e-6;
const DUAL_NUMBERS: f64 = 1e-12;
/// The central differences' step: truncation h² |q̈'''| / 6 and rounding ε |q̈| / h both near
/// 1e-11 of the accelerations' scale.
const STEP: f64 = 1e-5;

/// A state of a mechanism with loops and the efforts on it.
struct Case<'m> {
    model: &'m Model,
    structure: Structure,
    q: Vec<f64>,
    v: Vec<f64>,
    tau: Vec<f64>,
    external: Vec<Force>,
}

impl Case<'_> {
    /// The case at the prepared mechanism's assembled state, with efforts from `numbers`;
    /// `Err` names why it is left out (motions without mass, idle angles).
    fn new<'m>(prepared: &'m Prepared, numbers: &[f64]) -> Result<Case<'m>, String> {
        let model = &prepared.model;
        let (q, v) = assembled(prepared);
        let structure = Structure::decide(model, &mut Data::new(model), &q)
            .map_err(|e| format!("structure: {e:?}"))?;
        if structure.massless > 0 || !structure.idle.is_empty() {
            return Err(format!(
                "{} motions without mass, {} idle coordinates",
                structure.massless,
                structure.idle.len()
            ));
        }
        let value = |k: usize| numbers[k % numbers.len()];
        Ok(Case {
            model,
            structure,
            tau: (0..model.velocities()).map(|i| value(7 * i + 3)).collect(),
            external: (0..=model.body_count())
                .map(|i| Force::from_fn(|r, _| value(13 * i + r) * 0.3))
                .collect(),
            q,
            v,
        })
    }

    fn kept(&self) -> &[usize] {
        &self.structure.choice.rows
    }

    /// The analytical derivatives.
    fn analytical(&self) -> Result<ConstrainedDerivatives, String> {
        let model = self.model;
        let mut derivatives = ConstrainedDerivatives::new(model);
        derivatives
            .compute(
                model,
                &mut Data::new(model),
                &self.structure,
                &self.q,
                &self.v,
                &self.tau,
                &self.external,
            )
            .map_err(|e| e.to_string())?;
        Ok(derivatives)
    }

    /// The simulator's constrained accelerations at (q, v, τ): the null-space method.
    fn accelerations(&self, q: &[f64], v: &[f64], tau: &[f64]) -> DVector<f64> {
        let model = self.model;
        let mut data = Data::new(model);
        let mut scratch = LoopScratch::new(model);
        forward_kinematics(model, &mut data, q, v).expect("kinematics");
        constraints_into(
            model,
            &mut data,
            q,
            v,
            Extent::Motion,
            &mut scratch.constraints,
        )
        .expect("rows");
        scratch.force_method(Some(Method::NullSpace));
        scratch.choose_method(&self.structure);
        allowed_motions(&self.structure, Stabilisation::None, &mut scratch).expect("motions");
        rnea_forward(
            model,
            &mut data,
            &scratch.particular()[..model.nv],
            &self.external,
        );
        let tau = DVector::from_column_slice(tau);
        solve_reduced(
            model,
            &mut data,
            &tau,
            (&self.structure, None),
            &mut scratch,
        )
        .expect("solve");
        scratch.accelerations.clone()
    }

    /// ∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ by central differences of `accelerations`.
    fn differences(&self) -> [DMatrix<f64>; 3] {
        let n = self.model.velocities();
        let mut by = [(); 3].map(|_| DMatrix::zeros(n, n));
        for j in 0..n {
            let mut step = vec![0.0; n];
            let (mut q_plus, mut q_minus) = (self.q.clone(), self.q.clone());
            step[j] = STEP;
            self.model.retract(&mut q_plus, &step);
            step[j] = -STEP;
            self.model.retract(&mut q_minus, &step);
            let central =
                |plus: DVector<f64>, minus: DVector<f64>, h: f64| (plus - minus) / (2.0 * h);
            by[0].set_column(
                j,
                &central(
                    self.accelerations(&q_plus, &self.v, &self.tau),
                    self.accelerations(&q_minus, &self.v, &self.tau),
                    STEP,
                ),
            );
            let moved = |x: &[f64], h: f64| {
                let mut x = x.to_vec();
                x[j] += h;
                x
            };
            by[1].set_column(
                j,
                &central(
                    self.accelerations(&self.q, &moved(&self.v, STEP), &self.tau),
                    self.accelerations(&self.q, &moved(&self.v, -STEP), &self.tau),
                    STEP,
                ),
            );
            // Affine in τ: a unit step is exact to rounding.
            by[2].set_column(
                j,
                &central(
                    self.accelerations(&self.q, &self.v, &moved(&self.tau, 1.0)),
                    self.accelerations(&self.q, &self.v, &moved(&self.tau, -1.0)),
                    1.0,
                ),
            );
        }
        by
    }

    /// ∂z̈/∂z, ∂z̈/∂ż by central differences through the linearisation's chart on the free
    /// coordinates.
    fn chart_differences(&self) -> [DMatrix<f64>; 2] {
        let model = self.model;
        let free = &self.structure.free;
        let chart = Chart::with_loops(model, free.clone(), Vec::new(), &self.q);
        let z = chart.coordinates(&self.q);
        let rates: Vec<f64> = free.iter().map(|&i| self.v[i]).collect();
        let mut data = Data::new(model);
        let mut at = |z: &[f64], rates: &[f64]| {
            let (q, v) = chart.state(model, &mut data, z, rates).expect("chart");
            self.accelerations(&q, &v, &self.tau).select_rows(free)
        };
        let m = free.len();
        let mut by = [(); 2].map(|_| DMatrix::zeros(m, m));
        for k in 0..m {
            let moved = |x: &[f64], h: f64| {
                let mut x = x.to_vec();
                x[k] += h;
                x
            };
            let by_z =
                (at(&moved(&z, STEP), &rates) - at(&moved(&z, -STEP), &rates)) / (2.0 * STEP);
            by[0].set_column(k, &by_z);
            let by_rates =
                (at(&z, &moved(&rates, STEP)) - at(&z, &moved(&rates, -STEP))) / (2.0 * STEP);
            by[1].set_column(k, &by_rates);
        }
        by
    }

    /// q̈ by a dense saddle-point solve in dual numbers at the dual state (q, v, τ).
    fn dual_accelerations(&self, q: &[Dual64], v: &[Dual64], tau: &[Dual64]) -> DVector<Dual64> {
        let model = self.model;
        let (n, nv) = (model.velocities(), model.nv);
        let kept = self.kept();
        let r = kept.len();
        let (g, gamma) = self.dual_rows(q, v);
        let mut data = Data::<Dual64>::with_scalar(model);
        let none = vec![Force::<Dual64>::zeros(); model.body_count() + 1];
        let external: Vec<Force<Dual64>> = self
            .external
            .iter()
            .map(|f| f.map(Dual64::from_re))
            .collect();
        let rest = constant(&vec![0.0; n]);
        let zero = constant(&vec![0.0; nv]);
        let gravity = rnea(model, &mut data, q, &rest, &zero, &none).expect("rnea");
        let mut saddle = DMatrix::<Dual64>::zeros(n + r, n + r);
        for j in 0..nv {
            let mut unit = zero.clone();
            unit[j] = Dual64::from_re(1.0);
            let column = rnea(model, &mut data, q, &rest, &unit, &none).expect("rnea") - &gravity;
            saddle.view_mut((0, j), (nv, 1)).copy_from(&column);
        }
        saddle.view_mut((0, n), (n, r)).copy_from(&(-g.transpose()));
        saddle.view_mut((n, 0), (r, n)).copy_from(&g);
        let bias = rnea(model, &mut data, q, v, &zero, &external).expect("rnea");
        let mut right = DVector::<Dual64>::zeros(n + r);
        right.rows_mut(0, n).copy_from_slice(tau);
        let mut top = right.rows_mut(0, nv);
        top -= &bias;
        right.rows_mut(n, r).copy_from(&(-gamma));
        let solution = saddle.lu().solve(&right).expect("saddle-point solve");
        solution.rows(0, n).into_owned()
    }

    /// The kept rows of G and γ at the dual state (q, v).
    fn dual_rows(&self, q: &[Dual64], v: &[Dual64]) -> (DMatrix<Dual64>, DVector<Dual64>) {
        let model = self.model;
        let mut data = Data::<Dual64>::with_scalar(model);
        let mut rows = Constraints::<Dual64>::with_scalar(model);
        forward_kinematics(model, &mut data, q, v).expect("kinematics");
        constraints_into(model, &mut data, q, v, Extent::Motion, &mut rows).expect("rows");
        (
            rows.jacobian.dense().select_rows(self.kept()),
            rows.bias.select_rows(self.kept()),
        )
    }

    /// ∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ by dual numbers, checking on the way that the values are the
    /// analytical accelerations.
    fn dual_numbers(&self, accelerations: &DVector<f64>, what: &str) -> [DMatrix<f64>; 3] {
        let n = self.model.velocities();
        let (q, v, tau) = (constant(&self.q), constant(&self.v), constant(&self.tau));
        let unit = |j: usize| {
            (0..n)
                .map(|i| if i == j { 1.0 } else { 0.0 })
                .collect::<Vec<_>>()
        };
        let mut by = [(); 3].map(|_| DMatrix::zeros(n, n));
        for j in 0..n {
            let along = [
                self.dual_accelerations(
                    &seeded(&self.q, &tangent(self.model, &self.q, j)),
                    &v,
                    &tau,
                ),
                self.dual_accelerations(&q, &seeded(&self.v, &unit(j)), &tau),
                self.dual_accelerations(&q, &v, &seeded(&self.tau, &unit(j))),
            ];
            for (matrix, a) in by.iter_mut().zip(along) {
                let (value, derivative) = parts(&a);
                same_accelerations(&value, accelerations, what);
                matrix.set_column(j, &derivative);
            }
        }
        by
    }

    /// ∂z̈/∂z and ∂z̈/∂ż by dual numbers: the positions along T eₖ, the rates from the rows.
    fn dual_independent(&self, tangent_basis: &DMatrix<f64>) -> [DMatrix<f64>; 2] {
        let model = self.model;
        let free = &self.structure.free;
        let (n, m, r) = (model.velocities(), free.len(), self.kept().len());
        let rates: Vec<f64> = free.iter().map(|&i| self.v[i]).collect();
        let tau = constant(&self.tau);
        let mut by = [(); 2].map(|_| DMatrix::zeros(m, m));
        for k in 0..m {
            let direction: Vec<f64> = tangent_basis.column(k).iter().copied().collect();
            let q = seeded(&self.q, &position_rate(model, &self.q, &direction));
            // [Eᵀ; G(q)] v = [ż; 0] in dual numbers.
            let (g, _) = self.dual_rows(&q, &constant(&self.v));
            let mut chart = DMatrix::<Dual64>::zeros(n, n);
            for (row, &i) in free.iter().enumerate() {
                chart[(row, i)] = Dual64::from_re(1.0);
            }
            chart.view_mut((m, 0), (r, n)).copy_from(&g);
            let mut right = DVector::<Dual64>::zeros(n);
            for (row, &rate) in rates.iter().enumerate() {
                right[row] = Dual64::from_re(rate);
            }
            let v = chart.lu().solve(&right).expect("chart's rates");
            let a = self.dual_accelerations(&q, v.as_slice(), &tau);
            by[0].set_column(k, &parts(&a.select_rows(free)).1);
            let v = seeded(&self.v, &direction);
            let a = self.dual_accelerations(&constant(&self.q), &v, &tau);
            by[1].set_column(k, &parts(&a.select_rows(free)).1);
        }
        by
    }
}

/// The saddle-point solve in dual numbers gives the analytical accelerations' values, to the
/// round-off of a solve (1e-12 of their scale).
fn same_accelerations(dual: &DVector<f64>, analytical: &DVector<f64>, what: &str) {
    let difference = (dual - analytical).amax();
    assert!(
        difference <= 1e-12 * analytical.amax().max(1.0),
        "{what}: the dense solve gives {dual}, the analytical one {analytical}"
    );
}

/// Every check at `case`; the worst measures against central differences and dual numbers.
fn check(case: &Case, what: &str) -> (f64, f64) {
    let derivatives = case.analytical().unwrap_or_else(|e| panic!("{what}: {e}"));
    let simulated = case.accelerations(&case.q, &case.v, &case.tau);
    let scale = simulated.amax().max(1.0);
    let solved = (&derivatives.acceleration - &simulated).amax();
    assert!(
        solved <= 1e-10 * scale,
        "{what}: the saddle-point accelerations {} are not the simulator's {simulated}",
        derivatives.acceleration
    );
    let independent: IndependentDerivatives = derivatives
        .in_independent_coordinates(&case.structure.free)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let analytic = [
        &derivatives.dacceleration_dq,
        &derivatives.dacceleration_dv,
        &derivatives.dacceleration_dtau,
    ];
    let names = ["∂q̈/∂q", "∂q̈/∂v", "∂q̈/∂τ", "∂z̈/∂z", "∂z̈/∂ż"];
    let chart = [
        &independent.dacceleration_dz,
        &independent.dacceleration_drates,
    ];
    let differenced = case.differences();
    let charted = case.chart_differences();
    let by_differences: Vec<f64> = (analytic.iter().zip(&differenced))
        .chain(chart.iter().zip(&charted))
        .map(|(a, d)| mismatch(a, d))
        .collect();
    let dual = case.dual_numbers(&derivatives.acceleration, what);
    let dual_chart = case.dual_independent(&independent.tangent);
    let by_dual: Vec<f64> = (analytic.iter().zip(&dual))
        .chain(chart.iter().zip(&dual_chart))
        .map(|(a, d)| mismatch(a, d))
        .collect();
    let worst = |m: &[f64]| m.iter().copied().fold(0.0, f64::max);
    let labelled = |m: &[f64]| {
        names
            .iter()
            .zip(m)
            .map(|(n, m)| format!("{n} {m:.1e}"))
            .collect::<Vec<_>>()
    };
    eprintln!(
        "{what}: differences {:?}; dual numbers {:?}",
        labelled(&by_differences),
        labelled(&by_dual)
    );
    assert!(
        worst(&by_differences) <= DIFFERENCES,
        "{what}: against central differences {:?} above {DIFFERENCES:e}",
        labelled(&by_differences)
    );
    assert!(
        worst(&by_dual) <= DUAL_NUMBERS,
        "{what}: against dual numbers {:?} above {DUAL_NUMBERS:e}",
        labelled(&by_dual)
    );
    (worst(&by_differences), worst(&by_dual))
}

const NUMBERS: [f64; 11] = [0.3, -1.1, 0.7, 1.9, -0.4, 0.05, -1.6, 1.2, 0.9, -0.8, 0.45];

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn loop_derivatives_agree_on_random_four_bars((l, crank, rate) in four_bar_draws()) {
        let Some(p) = four_bar(l, crank, rate) else {
            return Err(TestCaseError::reject("does not close at this crank angle"));
        };
        let case = Case::new(&p, &NUMBERS).expect("a four-bar moves mass");
        check(&case, &format!("four-bar {l:?} at {crank}"));
    }

    #[test]
    fn loop_derivatives_agree_on_random_bennett_linkages(
        (a1, alpha1, alpha2, crank, rate) in bennett_draws(),
    ) {
        let p = bennett(a1, alpha1, alpha2, crank, rate);
        let case = Case::new(&p, &NUMBERS).expect("a Bennett linkage moves mass");
        check(&case, &format!("Bennett {a1}, {alpha1}, {alpha2}, at {crank}"));
    }
}

/// The examples with loops whose rows evaluate in dual numbers; those with motions without
/// mass (the Delta's rods between ball joints), rows that close only at second order
/// (`maille1`), or joints the tree's derivatives do not cover are refused by the derivatives
/// and left out, named with the refusal.
#[test]
fn loop_derivatives_agree_on_the_examples() {
    let (examples, mut left_out) = loop_examples();
    let mut covered = Vec::new();
    for (name, prepared) in &examples {
        let case = match Case::new(prepared, &NUMBERS) {
            Ok(case) => case,
            Err(why) => {
                left_out.push(format!("{name}: {why}"));
                continue;
            }
        };
        if let Err(why) = case.analytical() {
            left_out.push(format!("{name}: {why}"));
            continue;
        }
        let (differences, dual) = check(&case, name);
        covered.push(format!(
            "{name} (differences {differences:.1e}, dual {dual:.1e})"
        ));
    }
    eprintln!("covered: {covered:#?}\nleft out: {left_out:#?}");
    assert!(
        covered.len() >= 6,
        "only {} covered: {left_out:#?}",
        covered.len()
    );
}

/// A mechanism whose loops allow a motion without mass has no unique constrained
/// accelerations' derivatives: refused with an error naming how many, not a panic.
#[test]
fn loop_derivatives_refuse_singular_equations() {
    let (examples, _) = loop_examples();
    let massless = examples.iter().find(|(_, p)| {
        let q = assembled(p).0;
        Structure::decide(&p.model, &mut Data::new(&p.model), &q)
            .is_ok_and(|s| s.massless > 0 || !s.idle.is_empty())
    });
    let Some((name, prepared)) = massless else {
        panic!("no example with a motion without mass or idle coordinates");
    };
    let model = &prepared.model;
    let (q, v) = assembled(prepared);
    let structure = Structure::decide(model, &mut Data::new(model), &q).expect("structure");
    let mut derivatives = ConstrainedDerivatives::new(model);
    let tau = vec![0.0; model.velocities()];
    let external = vec![Force::zeros(); model.body_count() + 1];
    let result = derivatives.compute(
        model,
        &mut Data::new(model),
        &structure,
        &q,
        &v,
        &tau,
        &external,
    );
    let Err(ConstrainedDerivativeError::WithoutMass { motions }) = result else {
        panic!("{name}: {result:?} where motions without mass should be refused");
    };
    assert_eq!(motions, structure.massless + structure.idle.len(), "{name}");
}
