//! The model in the actuated coordinates at one state: the mass matrix, the bias and the
//! gravity efforts that the laws of `actuate` read (`mass_matrix`, `bias`, `gravity_effort`,
//! `inverse_dynamics`).
//!
//! With u the actuated coordinates, the velocities the loops allow are v = X u̇ and their
//! accelerations v̇ = X ü + c, where X and c solve [G; E] X = [0; I] and [G; E] c = [−γ; 0]
//! (G v̇ + γ = 0 the loops' rows, E the rows selecting u). Premultiplying the equations of
//! motion M v̇ + h = Eᵀ τ + Gᵀ λ by Xᵀ (G X = 0, E X = I) leaves the reduced model
//!
//! τ = Mₐ ü + Nₐ,  Mₐ = Xᵀ M X,  Nₐ = Xᵀ (M c + h),
//!
//! with h = RNEA(q, v, 0) less the generalised forces of the program's other efforts, the
//! seed's Z and M, N in its actuated coordinates (notes on the Delta seed, §4.4); the gravity
//! efforts Gₐ = Xᵀ h₀ are the bias at rest (v = 0), what `lsdc statics` holds. For a tree
//! whose every coordinate is actuated, X selects them and c = 0: the mass matrix from CRBA and
//! the bias from RNEA. X and c are the minimum-norm solutions: at the first state from a
//! singular value decomposition of [G; E], which also finds the motions it leaves free, and
//! these must move no mass (a Delta's rods spinning about their axes): otherwise the actuated
//! coordinates do not determine the motion, and the model has no value. At the later states
//! from a QR factorisation of [G; E]ᵀ with column pivoting (its independent rows), several
//! times cheaper, the decomposition taken again where that solve does not hold; or, cheaper
//! still, from the loops' own solve at the same state when the run has it
//! ([`LoopSolution`]): with N a basis of the velocities the loops allow and a₀ their least-norm
//! particular acceleration, X = N (E N)⁺ and c = a₀ − X E a₀ solve the same equations, and any
//! two solutions differ by free motions, which move no mass, so the model is the same.

use nalgebra::{DMatrix, DMatrixView, DVector, DVectorView};

use super::algorithms::{crba_after_kinematics, forward_kinematics, rnea_after_kinematics, Data};
use super::compiled::ModelReads;
use super::efforts::{evaluate_into, Declared, Efforts};
use super::loops::{constraints_into, Constraints, Extent};
use super::model::Model;
use crate::kinematics::eval::EvalError;
use crate::linalg::MinimumNormRows;

/// Why the model has no value in the actuated coordinates at a state.
#[derive(Clone, Debug, PartialEq)]
pub enum ReducedError {
    Evaluation(EvalError),
    /// The actuated coordinates leave a motion with mass free, or the loops fix a combination
    /// of them (too few actuated coordinates, or a singular configuration).
    Undetermined,
}

impl From<EvalError> for ReducedError {
    fn from(error: EvalError) -> Self {
        ReducedError::Evaluation(error)
    }
}

/// The model's scratch, kept from one evaluation to the next, and its values: `values` holds
/// Mₐ by rows (m² entries), then Nₐ (m), then Gₐ (m), for m actuated coordinates.
pub struct ReducedScratch {
    pub values: Vec<f64>,
    mass: DMatrix<f64>,
    bias: DVector<f64>,
    /// The state's velocities' generalised forces: h, then h₀.
    full: DVector<f64>,
    /// M x over the state's velocities for a column x of [X | c] (zero off the tree's).
    product: DVector<f64>,
    constraints: Option<Constraints>,
    /// The gravity efforts' own forward kinematics at rest, and efforts at rest.
    at_rest: Option<(Data, Efforts)>,
    zero_velocities: Vec<f64>,
    zero_rates: Vec<f64>,
    /// Whether the free motions were found massless (at the first state).
    checked_free: bool,
    /// The rows of [G; E] found independent at the last state solved by them.
    independent_rows: Vec<usize>,
}

impl ReducedScratch {
    pub fn new(model: &Model, actuated: usize) -> ReducedScratch {
        ReducedScratch {
            values: vec![0.0; actuated * actuated + 2 * actuated],
            mass: DMatrix::zeros(model.nv, model.nv),
            bias: DVector::zeros(model.nv),
            full: DVector::zeros(model.velocities()),
            product: DVector::zeros(model.velocities()),
            constraints: model.has_loops().then(|| Constraints::new(model)),
            at_rest: None,
            zero_velocities: vec![0.0; model.velocities()],
            zero_rates: vec![0.0; model.declared_count],
            checked_free: false,
            independent_rows: Vec::new(),
        }
    }
}

/// The state the model is evaluated at: positions and velocities of the whole state, the
/// declared coordinates and rates, the time, the efforts of the program (the actuators'
/// excluded) at that state; `data` holds its forward kinematics.
pub struct ReducedState<'a> {
    pub q: &'a [f64],
    pub v: &'a [f64],
    pub coordinates: &'a [f64],
    /// The program's states' values (`state(x0)`), which the other efforts may read.
    pub states: &'a [f64],
    pub time: f64,
    pub efforts: &'a Efforts,
}

/// The loops' own solve at the state the model is evaluated at (`dynamics::loops::
/// allowed_motions`, with the rows' bias alone in γ): a basis N of the velocities they allow,
/// over the state's velocities, and the least-norm particular acceleration a₀ (G a₀ = −γ).
pub struct LoopSolution<'a> {
    pub motions: DMatrixView<'a, f64>,
    pub particular: &'a [f64],
}

/// Writes the model in the actuated coordinates (`velocities`, indices of the state's
/// velocities) into `scratch.values`, the quantities `reads` asks for; `loops`, the loops'
/// solve at the state when the caller has it.
pub fn reduced_model(
    model: &Model,
    data: &mut Data,
    state: &ReducedState<'_>,
    velocities: &[usize],
    reads: ModelReads,
    (scratch, loops): (&mut ReducedScratch, Option<LoopSolution<'_>>),
) -> Result<(), ReducedError> {
    let m = velocities.len();
    crba_after_kinematics(model, data, &mut scratch.mass);
    let known = loops
        .filter(|_| scratch.checked_free)
        .and_then(|loops| from_loop_solution(&loops, velocities));
    let solution = match known {
        Some(solution) => solution,
        None => stacked_solution(model, data, state, velocities, scratch)?,
    };
    let motions = solution.columns(0, m);
    let nv = model.nv;
    let ReducedScratch {
        values,
        mass,
        bias,
        full,
        product,
        zero_velocities,
        ..
    } = scratch;
    // M x on the tree's rows, zero on the others (the declared coordinates').
    let mass_times = |x: DVectorView<'_, f64>, product: &mut DVector<f64>| {
        mass.mul_to(&x.rows(0, nv), &mut product.rows_mut(0, nv));
        product.rows_mut(nv, product.nrows() - nv).fill(0.0);
    };
    if reads.mass {
        for i in 0..m {
            mass_times(motions.column(i), product);
            for j in 0..m {
                values[j * m + i] = motions.column(j).dot(product);
            }
        }
    }
    if reads.bias {
        let zero_accelerations = &zero_velocities[..nv];
        let external = &state.efforts.external;
        rnea_after_kinematics(model, data, zero_accelerations, external, bias);
        generalised(model, bias, state.efforts, full);
        mass_times(solution.column(m), product);
        *product += &*full;
        for k in 0..m {
            values[m * m + k] = motions.column(k).dot(product);
        }
    }
    if reads.gravity {
        let (rest, efforts) = scratch
            .at_rest
            .get_or_insert_with(|| (Data::new(model), Efforts::none(model)));
        forward_kinematics(model, rest, state.q, &scratch.zero_velocities)?;
        let declared = Declared {
            model,
            coordinates: state.coordinates,
            rates: &scratch.zero_rates,
            states: state.states,
        };
        evaluate_into(model, rest, &declared, state.time, efforts)?;
        rnea_after_kinematics(
            model,
            rest,
            &scratch.zero_velocities[..model.nv],
            &efforts.external,
            &mut scratch.bias,
        );
        generalised(model, &scratch.bias, efforts, &mut scratch.full);
        for k in 0..m {
            scratch.values[m * m + m + k] = motions.column(k).dot(&scratch.full);
        }
    }
    Ok(())
}

/// [X | c] from [G; E] [X | c] = [0 | −γ; I | 0] formed at the state (`solve_stacked`).
fn stacked_solution(
    model: &Model,
    data: &mut Data,
    state: &ReducedState<'_>,
    velocities: &[usize],
    scratch: &mut ReducedScratch,
) -> Result<DMatrix<f64>, ReducedError> {
    let (m, n) = (velocities.len(), model.velocities());
    // [G; E] and its right-hand sides [0 | −γ; I | 0].
    let rows = scratch
        .constraints
        .as_ref()
        .map_or(0, |c| c.jacobian.nrows());
    let mut stacked = DMatrix::zeros(rows + m, n);
    let mut sides = DMatrix::zeros(rows + m, m + 1);
    if let Some(constraints) = scratch.constraints.as_mut() {
        constraints_into(model, data, state.q, state.v, Extent::Motion, constraints)?;
        stacked
            .view_mut((0, 0), (rows, n))
            .copy_from(&constraints.jacobian.dense());
        sides
            .view_mut((0, m), (rows, 1))
            .copy_from(&(-&constraints.bias));
    }
    for (k, &velocity) in velocities.iter().enumerate() {
        stacked[(rows + k, velocity)] = 1.0;
        sides[(rows + k, k)] = 1.0;
    }
    // Which motions the actuated coordinates leave free is decided by the structure, once, at
    // the first state (a closed one): an integrator's stages off the loops by their truncation
    // error would give the rods' spins a share of mass.
    let solution = solve_stacked(
        stacked,
        &sides,
        &scratch.mass,
        !scratch.checked_free,
        &mut scratch.independent_rows,
    )?;
    scratch.checked_free = true;
    Ok(solution)
}

/// [X | c] from the loops' solve: X = N (E N)⁺ and c = a₀ − X E a₀, where E N, the actuated
/// rates of the allowed motions, is m × k with k ≥ m (the allowed motions of the actuated
/// coordinates alone, or with others that move no mass). `None` where E N does not have rank m
/// (the loops fix a combination of the actuated coordinates here, or an actuated coordinate's
/// motion was not among those solved on): [G; E] then decides.
fn from_loop_solution(loops: &LoopSolution<'_>, velocities: &[usize]) -> Option<DMatrix<f64>> {
    let (m, k) = (velocities.len(), loops.motions.ncols());
    if k < m {
        return None;
    }
    let actuated = loops.motions.select_rows(velocities);
    let inverse = match clearly_invertible(&actuated) {
        Some(inverse) => inverse,
        None => {
            // (E N)⁺ from the small matrix's singular value decomposition, which also says
            // its rank.
            let svd = crate::linalg::svd(actuated, true, true)?;
            let largest = svd.singular_values.max();
            if svd.singular_values.min() <= RANK_FLOOR * largest {
                return None;
            }
            svd.pseudo_inverse(0.0).ok()?
        }
    };
    let mut solution = DMatrix::zeros(loops.motions.nrows(), m + 1);
    let x = loops.motions * inverse;
    let particular = DVector::from_column_slice(loops.particular);
    let actuated_particular = DVector::from_iterator(m, velocities.iter().map(|&i| particular[i]));
    solution.columns_mut(0, m).copy_from(&x);
    let c = particular - &x * actuated_particular;
    solution.column_mut(m).copy_from(&c);
    solution.iter().all(|x| x.is_finite()).then_some(solution)
}

/// The inverse of a square E N (the actuated rates of as many allowed motions as actuated
/// coordinates, a run's usual case) from its LU factorisation with partial pivoting, where its
/// condition number in the 1-norm κ₁ shows its singular values all above `RANK_FLOOR` times the
/// largest: for an m × m matrix κ₂ ≤ m κ₁ (‖A‖₂ ≤ √m ‖A‖₁; Golub and Van Loan, "Matrix
/// Computations", 4th ed., §2.3.2), so the decomposition's test passes and its pseudo-inverse
/// is this inverse, at a fraction of its cost. `None` where that is not shown (a wide E N, a
/// condition near the floor, a singular one): the decomposition decides, as before.
fn clearly_invertible(actuated: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let m = actuated.nrows();
    if actuated.ncols() != m || m == 0 {
        return None;
    }
    let inverse = actuated.clone().lu().try_inverse()?;
    let norm_1 = |a: &DMatrix<f64>| {
        (a.column_iter())
            .map(|column| column.iter().map(|x| x.abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let condition = norm_1(actuated) * norm_1(&inverse);
    // Half the floor's bound: the decomposition's singular values carry round-off too.
    (condition.is_finite() && m as f64 * condition < 0.5 / RANK_FLOOR).then_some(inverse)
}

/// h on the state's velocities: RNEA's on the tree's (`tree`), less the link efforts' τ.
fn generalised(model: &Model, tree: &DVector<f64>, efforts: &Efforts, full: &mut DVector<f64>) {
    full.fill(0.0);
    full.rows_mut(0, model.nv).copy_from(tree);
    *full -= &efforts.tau;
}

/// The minimum-norm solution of `stacked` x = `sides`, refused when it does not solve it or
/// (`check_free`) leaves free a motion with mass: the null space of `stacked` must move no
/// mass. Once the free motions are checked, the rows' QR factorisation solves on the rows
/// found independent (`rows`, kept from state to state); where it does not hold (a
/// configuration where the rows lose rank) the decomposition decides.
fn solve_stacked(
    stacked: DMatrix<f64>,
    sides: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    check_free: bool,
    rows: &mut Vec<usize>,
) -> Result<DMatrix<f64>, ReducedError> {
    if !check_free {
        if let Some(solution) = solve_on_independent_rows(&stacked, sides, rows) {
            return Ok(solution);
        }
    }
    solve_by_decomposition(stacked, sides, mass, check_free)
}

/// The minimum-norm solution of `stacked` x = `sides` on its independent rows
/// ([`MinimumNormRows`]: a QR factorisation of `stacked`ᵀ), refined on the residual of every
/// row as the decomposition's solution is. The rows found independent at the last state
/// (`rows`) are tried first, without pivoting, then the pivoting finds them again; `None`
/// where the residual stays above `SOLVED` (a row not a combination of the independent ones)
/// or an entry is not finite.
fn solve_on_independent_rows(
    stacked: &DMatrix<f64>,
    sides: &DMatrix<f64>,
    rows: &mut Vec<usize>,
) -> Option<DMatrix<f64>> {
    let refined = |factors: MinimumNormRows| {
        let mut solution = factors.solve(sides);
        let mut residual = sides - stacked * &solution;
        // A residual at round-off already (the usual case) has nothing to refine.
        let round_off = ROUND_OFF * (1.0 + sides.amax());
        for _ in 0..REFINEMENTS {
            if residual.amax() <= round_off {
                break;
            }
            let refined = &solution + factors.solve(&residual);
            let refined_residual = sides - stacked * &refined;
            if refined_residual.amax() >= residual.amax() {
                break;
            }
            (solution, residual) = (refined, refined_residual);
        }
        let solved = residual.amax() <= SOLVED * (1.0 + sides.amax());
        (solved && solution.iter().all(|x| x.is_finite())).then_some(solution)
    };
    let kept = (!rows.is_empty())
        .then(|| MinimumNormRows::on_rows(stacked, rows, RANK_FLOOR))
        .flatten();
    if let Some(solution) = kept.and_then(refined) {
        return Some(solution);
    }
    let factors = MinimumNormRows::new(stacked, RANK_FLOOR)?;
    *rows = factors.independent_rows().to_vec();
    refined(factors)
}

/// [`solve_stacked`] by a singular value decomposition of `stacked`.
fn solve_by_decomposition(
    stacked: DMatrix<f64>,
    sides: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    check_free: bool,
) -> Result<DMatrix<f64>, ReducedError> {
    let nv = mass.nrows();
    let svd = crate::linalg::svd(stacked.clone(), true, true)
        .ok_or(ReducedError::Evaluation(EvalError::NotFinite))?;
    let largest = svd.singular_values.max();
    let floor = largest * RANK_FLOOR;
    let solve = |right: &DMatrix<f64>| {
        svd.solve(right, floor)
            .map_err(|_| ReducedError::Evaluation(EvalError::NotFinite))
    };
    // The decomposition's solution can leave a residual far above round-off (8.8e-8 on the
    // Delta's 33 x 39 rows, consistent to 1e-16): iterative refinement on the residual
    // (Wilkinson; Higham, "Accuracy and Stability of Numerical Algorithms", 2002, ch. 12)
    // brings it down, a few steps while it decreases.
    let mut solution = solve(sides)?;
    let mut residual = sides - &stacked * &solution;
    for _ in 0..REFINEMENTS {
        let refined = &solution + solve(&residual)?;
        let refined_residual = sides - &stacked * &refined;
        if refined_residual.amax() >= residual.amax() {
            break;
        }
        (solution, residual) = (refined, refined_residual);
    }
    if residual.amax() > SOLVED * (1.0 + sides.amax()) {
        return Err(ReducedError::Undetermined);
    }
    if !check_free {
        return Ok(solution);
    }
    // The free motions: the projector I − Σ vₖvₖᵀ off the rows' space (σₖ above the floor).
    let v_t = svd.v_t.as_ref().expect("asked for");
    let n = stacked.ncols();
    let mut free = DMatrix::identity(n, n);
    for (k, &value) in svd.singular_values.iter().enumerate() {
        if value > floor {
            let row = v_t.row(k);
            free -= row.transpose() * row;
        }
    }
    // The kinetic energy of the free motions, over an orthonormal basis of them: trace(Pᵀ M P).
    // Quadratic in the motions, it stays at round-off for the massless ones however far an
    // integrator's stage is off the loops.
    let tree = free.rows(0, nv);
    let free_kinetic = tree.component_mul(&(mass * tree)).sum();
    if free_kinetic > MASSLESS * mass.trace().max(f64::MIN_POSITIVE) {
        return Err(ReducedError::Undetermined);
    }
    Ok(solution)
}

/// Singular values below this fraction of the largest are taken as zero.
const RANK_FLOOR: f64 = 1e-9;
/// How many steps of iterative refinement the solve of [G; E] X = [0; I] takes at most.
const REFINEMENTS: usize = 3;
/// A residual of [G; E] X = [0; I] at round-off, relative to the right-hand side: the QR
/// solve's usual one (a few units of ε times the entries), which refinement cannot lower.
const ROUND_OFF: f64 = 16.0 * f64::EPSILON;
/// The largest residual of [G; E] X = [0; I] accepted, relative to the right-hand side.
const SOLVED: f64 = 1e-8;
/// The free motions move no mass when their kinetic metric's trace is below this fraction of
/// M's (a Delta's spinning rods: 1e-30 at its start); a motion the actuated coordinates leave
/// free has a share of the whole.
const MASSLESS: f64 = 1e-9;
