//! The constrained equations `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0`, solved on the rows the loops'
//! `Structure` keeps, by the null-space method on the sparse factorisation of their normal
//! matrix A = GₛGₛᵀ (`Factored`). Then
//!
//! - the particular acceleration a₀ = −GₛᵀA⁻¹γₛ, the smallest with Gₛa₀ = −γₛ;
//! - the allowed motions N, one per free coordinate of the structure (the allowed part of its
//!   unit motion), and a = a₀ + Nz with (NᵀMN) z = Nᵀ(f − Ma₀) by Cholesky;
//! - the multipliers λₛ = A⁻¹Gₛ(Ma − f).
//!
//! The kept rows are fixed along the run and independent wherever the mechanism is regular, so
//! the accelerations are a smooth function of the state there; they do not depend on the basis
//! N of the allowed motions, only on the space it spans. Motions that move no mass
//! (their number is part of the structure) are left at rest.
//!
//! Where the allowed motions outnumber the kept rows, the same equations are solved on the rows
//! instead (`range_space`, `solve_range_space`): the factorisation is taken as here, the
//! allowed motions only when a caller asks for them (`LoopScratch::ensure_motions`).

use nalgebra::{Cholesky, DMatrix, DVector};

use super::factored::{projector_block_quality, Envelope, Factored, RowChoice, Singular, DAMPING};
use super::inertia::{Reduced, ReducedInertia};
use super::project::ProjectionScratch;
use super::range_space::{Failure, Method, RangeSpace, Tree};
use super::rows::Constraints;
use super::structure::Structure;
use crate::dynamics::algorithms::Data;
use crate::dynamics::dense::dense_cholesky;
use crate::dynamics::model::Model;
use crate::dynamics::planar::{PlanarData, PlanarModel};

/// How the constraints are kept: by projecting the state after each step (exact), by Baumgarte's
/// feedback in the accelerations (with this rate, in 1/s, critically damped), by the integrator's
/// own equations (the symplectic integrator's RATTLE steps), or not at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stabilisation {
    Projection,
    Baumgarte(f64),
    Integrator,
    None,
}

/// What the constrained solve keeps from one evaluation to the next, so that it allocates
/// nothing once sized: the constraint rows (filled by the caller, `rows::constraints_into`),
/// their factorisation, the solve's vectors, and its results.
pub struct LoopScratch {
    pub constraints: Constraints,
    pub factored: Factored,
    /// The damped factor's storage between evaluations.
    factor: Envelope,
    /// Vectors over the kept rows, over all the rows, over the state's velocities.
    kept: Vec<f64>,
    /// A free coordinate's column of the kept rows, solved beside the particular acceleration's.
    motion_rows: Vec<f64>,
    gamma: DVector<f64>,
    particular: DVector<f64>,
    /// The allowed motions N, NᵀMN (and its factor), and Nᵀ(f − Ma₀), then z.
    null: DMatrix<f64>,
    reduced_mass: DMatrix<f64>,
    reduced_factor: DMatrix<f64>,
    reduced_force: DVector<f64>,
    /// The motions kept when some carry no mass.
    massive: Massive,
    /// Whether the next evaluation measures how well the free coordinates parametrise the
    /// allowed motions (once per step, see `refresh`), the block it measures that on, and the
    /// measure (`take_free_quality`).
    quality_due: bool,
    quality_block: DMatrix<f64>,
    free_quality: Option<f64>,
    quality_of: Vec<usize>,
    /// How many of `null`'s columns `allowed_motions` found (every free coordinate's, or the
    /// massive ones and those checked), and how many the last solve moved along.
    found_motions: usize,
    solved_motions: usize,
    /// The massive motions of a solve that chose them (`Massive::choose`): `null` is then in
    /// the order of the free coordinates, the massive ones not first, so they are copied here
    /// (empty otherwise: `null`'s first columns are the massive ones).
    chosen_motions: DMatrix<f64>,
    /// How the reduced equations are formed, and their scratch.
    inertia: ReducedInertia,
    /// The method of the next evaluations (`range_space::method_for`), the range-space
    /// method's storage, and whether its last evaluation left the allowed motions to be found
    /// on demand (`ensure_motions`).
    method: Method,
    forced: Option<Method>,
    /// Whether the range-space method applies to the model (`range_space::applies_to`).
    range_applies: bool,
    range: RangeSpace,
    motions_due: bool,
    /// Accelerations of every state velocity.
    pub accelerations: DVector<f64>,
    /// Constraint wrench of each loop on its second body, at the loop point in fixed axes:
    /// moment, then force (6 per loop).
    pub multipliers: DVector<f64>,
}

impl LoopScratch {
    pub fn new(model: &Model) -> LoopScratch {
        let constraints = Constraints::new(model);
        let (rows, columns) = (constraints.residual.len(), model.velocities());
        LoopScratch {
            factored: Factored::new(&constraints.jacobian, &RowChoice::NONE),
            constraints,
            factor: Envelope::default(),
            kept: Vec::new(),
            motion_rows: Vec::new(),
            gamma: DVector::zeros(rows),
            particular: DVector::zeros(columns),
            null: DMatrix::zeros(columns, 0),
            reduced_mass: DMatrix::zeros(0, 0),
            reduced_factor: DMatrix::zeros(0, 0),
            reduced_force: DVector::zeros(0),
            massive: Massive::default(),
            quality_due: false,
            quality_block: DMatrix::zeros(0, 0),
            free_quality: None,
            quality_of: Vec::new(),
            found_motions: 0,
            solved_motions: 0,
            chosen_motions: DMatrix::zeros(columns, 0),
            inertia: ReducedInertia::new(model),
            method: Method::NullSpace,
            forced: None,
            range_applies: super::range_space::applies_to(model),
            range: RangeSpace::default(),
            motions_due: false,
            accelerations: DVector::zeros(columns),
            multipliers: DVector::zeros(rows),
        }
    }

    /// Takes between steps the decisions the last evaluations found stale (the motions kept when
    /// some carry no mass): the next evaluation takes them again, and checks that no force acts
    /// on the motions left out.
    pub fn refresh(&mut self) {
        if self.massive.stale {
            self.massive = Massive::default();
        }
        self.massive.check_due = true;
        self.quality_due = true;
        self.free_quality = None;
    }

    /// How well the free coordinates `free` parametrised the allowed motions at the first
    /// evaluation since the last `refresh` (the measure of `Damped::free_quality_into`), if it
    /// was taken for them.
    pub fn take_free_quality(&mut self, free: &[usize]) -> Option<f64> {
        self.free_quality.take().filter(|_| self.quality_of == free)
    }

    /// Hands the rows of the last evaluation, their factorisation and its factor (damped by
    /// `DAMPING`) to a projection of the same state (`ProjectionScratch::adopt`), if they are
    /// `choice`'s rows; this scratch fills the projection's storage anew at the next evaluation.
    pub fn hand_over(&mut self, projection: &mut ProjectionScratch, choice: &RowChoice) {
        self.motions_due = false;
        if self.factored.holds(choice) {
            projection.adopt(&mut self.constraints, &mut self.factored, &mut self.factor);
        }
    }

    /// The method of the next evaluations for `structure` (`range_space::method_for`), or the
    /// one forced (`force_method`).
    pub fn choose_method(&mut self, structure: &Structure) {
        let chosen = super::range_space::method_for(structure, self.range_applies);
        self.method = self.forced.unwrap_or(chosen);
    }

    /// Forces one method wherever it applies (None: the rule of `range_space::method_for`),
    /// to compare the two on one mechanism.
    pub fn force_method(&mut self, method: Option<Method>) {
        self.forced = method;
    }

    pub fn forced_method(&self) -> Option<Method> {
        self.forced
    }

    pub fn method(&self) -> Method {
        self.method
    }

    /// The free coordinates the solve leaves at rest because their motions carry no mass
    /// (`Massive`: the rods' spins), once chosen for `structure`'s free coordinates; empty
    /// before the choice and where every allowed motion carries mass.
    pub fn left_at_rest(&self, structure: &Structure) -> &[usize] {
        match structure.massless > 0 && self.massive.holds(structure) {
            true => &self.massive.dropped_coordinates,
            false => &[],
        }
    }

    /// After a range-space evaluation, which finds no allowed motions, finds them at the same
    /// state from its factorisation (one sparse solve per free coordinate, as the null-space
    /// method does), for the callers that work on them: the response X of the constraint
    /// stack's other rows, the implicit integrator's tangent space. Nothing after a null-space
    /// evaluation. Must follow the evaluation, before its rows are handed to a projection
    /// (`hand_over`).
    pub fn ensure_motions(&mut self, structure: &Structure) {
        if !std::mem::take(&mut self.motions_due) {
            return;
        }
        self.size_for(structure.free.len());
        let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
        damped.allowed_motions_into(&structure.free, &mut self.motion_rows, &mut self.null, 0);
        self.factor = damped.into_storage();
        self.found_motions = structure.free.len();
        self.solved_motions = structure.free.len();
        self.chosen_motions = DMatrix::zeros(self.null.nrows(), 0);
        // The motions are on the free coordinates: how well they parametrise them is measured
        // as at a null-space evaluation, so that the run chooses them again when they do not.
        if std::mem::take(&mut self.quality_due) {
            let quality =
                free_quality_of(&self.null, &structure.free, None, &mut self.quality_block);
            self.free_quality = Some(quality);
            self.quality_of.clone_from(&structure.free);
        }
    }

    /// The particular acceleration a₀ `allowed_motions` found, over the state's velocities.
    pub fn particular(&self) -> &[f64] {
        self.particular.as_slice()
    }

    /// The allowed motions `allowed_motions` found (one column per free coordinate, or per
    /// massive one when the others carry no mass, before the solve chooses among them), over
    /// the state's velocities.
    pub fn found_motions(&self) -> nalgebra::DMatrixView<'_, f64> {
        self.null.columns(0, self.found_motions)
    }

    /// The allowed motions the last solve moved along (one column per free coordinate that
    /// carries mass, over the state's velocities): a basis of the velocities the loops allow.
    pub fn solved_motions(&self) -> nalgebra::DMatrixView<'_, f64> {
        match self.chosen_motions.ncols() {
            0 => self.null.columns(0, self.solved_motions),
            kept => self.chosen_motions.columns(0, kept),
        }
    }

    /// Sizes the allowed motions' matrices for `free` coordinates (allocates only when their
    /// number changes, with the structure).
    fn size_for(&mut self, free: usize) {
        if self.null.ncols() != free {
            self.quality_block = DMatrix::zeros(free, free);
            self.null = DMatrix::zeros(self.null.nrows(), free);
            self.reduced_mass = DMatrix::zeros(free, free);
            self.reduced_factor = DMatrix::zeros(free, free);
            self.reduced_force = DVector::zeros(free);
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum LoopError {
    /// An effort acts on a motion that moves no mass: its acceleration would be infinite. The
    /// state velocity that motion moves most.
    MasslessMotion { velocity: usize },
    /// The kept rows are dependent here: the mechanism is exactly at a singular configuration.
    /// The row (among the 6 per loop) that lost its independence.
    Singular { row: usize },
}

/// A force on a motion without mass stops the run above this fraction of the largest force on
/// the motions: it is a model that forgot a mass, not the residue (1e-6 relative seen on the
/// Delta's rod spins) of evaluating forces that balance exactly.
const MASSLESS_FORCE: f64 = 1e-3;

/// The first half of the solve of `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0` on the kept rows (γ with
/// Baumgarte's terms when asked for) at the constraints in `scratch`: the factorisation, the
/// particular acceleration a₀ (`LoopScratch::particular`) and the allowed motions N. The caller
/// then takes inverse dynamics' pass out at a₀ (`rnea_forward`) for `solve_reduced`.
pub fn allowed_motions(
    structure: &Structure,
    stabilisation: Stabilisation,
    scratch: &mut LoopScratch,
) -> Result<(), LoopError> {
    scratch.size_for(structure.free.len());
    let LoopScratch {
        constraints: c,
        factored,
        factor,
        kept,
        gamma,
        particular,
        motion_rows,
        null,
        massive,
        quality_due,
        quality_block,
        free_quality,
        quality_of,
        found_motions,
        solved_motions,
        method,
        motions_due,
        ..
    } = scratch;
    gamma.copy_from(&c.bias);
    if let Stabilisation::Baumgarte(rate) = stabilisation {
        gamma.axpy(2.0 * rate, &c.velocity, 1.0);
        gamma.axpy(rate * rate, &c.residual, 1.0);
    }
    factored.refill(&c.jacobian, &structure.choice);
    let damped = factored
        .damped_in(DAMPING, std::mem::take(factor))
        .map_err(singular)?;
    factored.kept_into(gamma.as_slice(), kept);
    kept.iter_mut().for_each(|x| *x = -*x);
    if *method == Method::RangeSpace {
        // The factor serves the watch on singular configurations, the multipliers, the
        // projection that adopts it and the motions found on demand; the solve is on the rows.
        *factor = damped.into_storage();
        *found_motions = 0;
        *solved_motions = 0;
        *motions_due = true;
        return Ok(());
    }
    // The motions solved on: every free coordinate's, or only the massive ones kept when the
    // others carry no mass (their choice made); those left out are then checked after the
    // solve, once per step (`check_due`).
    let (every, checking) = massive.plan(structure);
    let motions: &[usize] = if every {
        &structure.free
    } else {
        &massive.coordinates
    };
    let m = motions.len();
    let particular = particular.as_mut_slice();
    damped.least_norm_and_allowed_motions_into(kept, particular, motions, motion_rows, null);
    *found_motions = m;
    if checking {
        damped.allowed_motions_into(&massive.dropped_coordinates, kept, null, m);
        *found_motions += massive.dropped_coordinates.len();
    }
    if *quality_due && (every || checking) {
        let columns = if every {
            None
        } else {
            Some(&massive.column_of_free[..])
        };
        let quality = free_quality_of(null, &structure.free, columns, quality_block);
        *free_quality = Some(quality);
        quality_of.clone_from(&structure.free);
        *quality_due = false;
    }
    *factor = damped.into_storage();
    Ok(())
}

/// The second half of the solve (after `allowed_motions`) by the range-space method
/// (`range_space`): the accelerations into `scratch`, from the efforts' generalised forces
/// `tau` over the state's velocities and the tree's kinematics at the state.
pub fn solve_range_space(
    model: &Model,
    tree: Tree<'_>,
    tau: &DVector<f64>,
    structure: &Structure,
    scratch: &mut LoopScratch,
) -> Result<(), LoopError> {
    idle_check(structure, tau)?;
    let LoopScratch {
        factored,
        kept,
        range,
        accelerations,
        ..
    } = scratch;
    let solved = range.solve(model, tree, structure, factored, kept, tau, accelerations);
    solved.map_err(|failure| match failure {
        Failure::MasslessMotion { velocity } => LoopError::MasslessMotion { velocity },
        Failure::Singular { row } => LoopError::Singular { row },
    })
}

/// The second half of the solve (after `allowed_motions`): a = a₀ + Nz with
/// (NᵀMN) z = Nᵀ(f − Ma₀), formed on the tree (`ReducedInertia`) from `tau`, the efforts'
/// generalised forces over the state's velocities, with `data` holding the forward kinematics
/// and inverse dynamics' pass out at a₀ (`rnea_forward`), or with `planar` their planar form
/// in its scratch. The accelerations are left in `scratch`.
pub fn solve_reduced(
    model: &Model,
    data: &mut Data,
    tau: &DVector<f64>,
    (structure, planar): (&Structure, Option<(&PlanarModel, &mut PlanarData)>),
    scratch: &mut LoopScratch,
) -> Result<(), LoopError> {
    let LoopScratch {
        particular,
        null,
        reduced_mass,
        reduced_factor,
        reduced_force,
        massive,
        inertia,
        accelerations,
        solved_motions,
        chosen_motions,
        ..
    } = scratch;
    let (every, checking) = massive.plan(structure);
    let m = if every {
        structure.free.len()
    } else {
        massive.coordinates.len()
    };
    // The motions left out are solved with the kept ones when checked: their rows of the
    // reduced equations give their imbalance.
    let count = m + if checking { structure.massless } else { 0 };
    let reduced = Reduced {
        mass: reduced_mass,
        force: reduced_force,
    };
    inertia.reduced_into(model, data, null, (count, m), tau, reduced, planar);
    // An idle coordinate's motion is its unit motion (no mass, no kept row): its share of the
    // reduced forces is the effort on it.
    // The generalised forces themselves count in the scale: held in balance (a computed torque
    // at rest), the reduced forces vanish while the residue on the massless motions does not.
    let idle_force = structure.idle.iter().map(|&c| tau[c].abs());
    let scale = idle_force
        .fold(reduced_force.rows(0, count).amax(), f64::max)
        .max(tau.amax())
        .max(f64::MIN_POSITIVE);
    if let Some(&velocity) = structure
        .idle
        .iter()
        .find(|&&c| tau[c].abs() > MASSLESS_FORCE * scale)
    {
        return Err(LoopError::MasslessMotion { velocity });
    }
    let solved = if structure.massless == 0 {
        massive_solve(reduced_mass, reduced_factor, reduced_force, scale)
    } else if every {
        if !massive.holds(structure) {
            massive.choose(reduced_mass, &structure.free, structure.massless);
        }
        massive.solve(reduced_mass, reduced_factor, reduced_force, scale)
    } else {
        massive.solve_kept(reduced_mass, reduced_factor, reduced_force, checking, scale)
    };
    solved.map_err(|k| LoopError::MasslessMotion {
        velocity: null.column(k).iamax(),
    })?;
    let z = reduced_force.rows(0, m);
    *solved_motions = m;
    // A solve that chose the massive motions solved along them only: the others are left at
    // rest, and a response over every column would be singular along them.
    *chosen_motions = match every && structure.massless > 0 {
        true => null.select_columns(&massive.kept),
        false => DMatrix::zeros(null.nrows(), 0),
    };
    accelerations.copy_from(particular);
    accelerations.gemv(1.0, &null.columns(0, m), &z, 1.0);
    Ok(())
}

/// The multipliers λₛ = (A + μ²E)⁻¹Gₛ(Ma − f) into `scratch.multipliers` (6 per loop, zero on
/// the rows not kept), from `reaction` = Ma − f over the state's velocities (inverse dynamics
/// at the accelerations `solve_reduced` found, less the efforts), at the factorisation
/// `allowed_motions` took.
pub fn multipliers(reaction: &DVector<f64>, scratch: &mut LoopScratch) {
    let LoopScratch {
        factored,
        factor,
        kept,
        multipliers,
        ..
    } = scratch;
    let damped = factored.with_factor(std::mem::take(factor));
    damped.multipliers_into(reaction.as_slice(), kept, multipliers.as_mut_slice());
    *factor = damped.into_storage();
}

/// The free coordinates' quality (`Damped::free_quality_into`) from their allowed motions N:
/// the block of the projector P = I − Gₛᵀ(A + μ²E)⁻¹Gₛ over them is N's rows of the free
/// coordinates, so the measure costs one small Cholesky factorisation of it. `work` is n × n.
/// The motion of free coordinate j is column j of N, or column `columns[j]` when given.
fn free_quality_of(
    null: &DMatrix<f64>,
    free: &[usize],
    columns: Option<&[usize]>,
    work: &mut DMatrix<f64>,
) -> f64 {
    let n = free.len();
    for j in 0..n {
        let column = columns.map_or(j, |columns| columns[j]);
        for i in j..n {
            work[(i, j)] = null[(free[i], column)];
        }
    }
    projector_block_quality(work, n)
}

/// An effort on an idle coordinate (a complementary link's own that no kept row touches) acts
/// on a motion without mass: the run stops above `MASSLESS_FORCE` of the largest effort.
fn idle_check(structure: &Structure, tau: &DVector<f64>) -> Result<(), LoopError> {
    let scale = tau.amax().max(f64::MIN_POSITIVE);
    match structure
        .idle
        .iter()
        .find(|&&c| tau[c].abs() > MASSLESS_FORCE * scale)
    {
        Some(&velocity) => Err(LoopError::MasslessMotion { velocity }),
        None => Ok(()),
    }
}

fn singular(lost: Singular) -> LoopError {
    LoopError::Singular { row: lost.row }
}

/// The allowed motions the solve keeps when some carry no mass (the structure counts them): those
/// of the free coordinates a Cholesky factorisation of NᵀMN pivoted on its diagonal takes first,
/// decided at the first evaluation after the free coordinates change and then kept, since
/// choosing inside every evaluation would make the accelerations jump where two pivots swap. The
/// motions left out are, up to motions of the kept ones, those without mass: they are left at
/// rest. When the kept block's smallest pivot falls under a tenth of its value at the choice,
/// the choice is marked stale and taken again between steps (`LoopScratch::refresh`).
///
/// Between two checks the solve computes the kept motions only: that no force acts on the
/// motions left out (which would give them an infinite acceleration) is checked at the choice
/// and at the first evaluation after each step (`check_due`), from the allowed motions of the
/// ones left out and the accelerations found without them.
#[derive(Clone, Debug, Default)]
struct Massive {
    /// The free coordinates the choice was made for.
    free: Vec<usize>,
    /// Positions among them: kept (pivot order), left out.
    kept: Vec<usize>,
    dropped: Vec<usize>,
    /// The kept free coordinates, in pivot order, and those left out.
    coordinates: Vec<usize>,
    dropped_coordinates: Vec<usize>,
    /// Per free coordinate, the column of its motion when the kept ones are followed by those
    /// left out.
    column_of_free: Vec<usize>,
    /// Whether the next evaluation checks the motions left out.
    check_due: bool,
    /// The kept block's smallest pivot over its largest, when chosen.
    quality: f64,
    stale: bool,
    /// The kept block's right-hand side, then its solution.
    rhs: Vec<f64>,
}

impl Massive {
    /// Chooses the kept motions for the reduced mass matrix `a` of `free`, `massless` of which
    /// carry no mass.
    fn choose(&mut self, a: &DMatrix<f64>, free: &[usize], massless: usize) {
        let n = a.nrows();
        let mut order: Vec<usize> = (0..n).collect();
        let mut schur = a.clone();
        let mut pivots = Vec::with_capacity(n);
        for k in 0..n {
            // The largest diagonal entry of what is left: the most massive motion next.
            let best = (k..n)
                .max_by(|&i, &j| {
                    schur[(order[i], order[i])].total_cmp(&schur[(order[j], order[j])])
                })
                .expect("not empty");
            order.swap(k, best);
            let p = order[k];
            let pivot = schur[(p, p)].max(0.0).sqrt();
            pivots.push(pivot);
            if pivot == 0.0 {
                break;
            }
            for &i in &order[k + 1..] {
                for &j in &order[k + 1..] {
                    schur[(i, j)] -= schur[(i, p)] * schur[(j, p)] / (pivot * pivot);
                }
            }
        }
        let kept = n - massless;
        self.free = free.to_vec();
        self.kept = order[..kept].to_vec();
        self.dropped = order[kept..].to_vec();
        self.quality = pivot_ratio(&pivots[..kept.min(pivots.len())]);
        self.stale = false;
        self.coordinates = self.kept.iter().map(|&p| free[p]).collect();
        self.dropped_coordinates = self.dropped.iter().map(|&p| free[p]).collect();
        self.column_of_free = vec![0; n];
        for (column, &p) in self.kept.iter().chain(&self.dropped).enumerate() {
            self.column_of_free[p] = column;
        }
    }

    /// Whether the choice holds for the structure's free coordinates.
    fn holds(&self, structure: &Structure) -> bool {
        self.free == structure.free && self.dropped.len() == structure.massless
    }

    /// Factors the kept block of NᵀMN in the leading r × r lower triangle of `work` (filled by
    /// the caller), marking the choice stale when it is not positive definite or has fallen
    /// under a tenth of its quality at the choice; false when it cannot be factored.
    fn factor_kept(&mut self, work: &mut DMatrix<f64>) -> bool {
        let r = self.kept.len();
        let Some((smallest, largest)) = dense_cholesky(work, r) else {
            self.stale = true;
            return false;
        };
        let quality = if r == 0 {
            1.0
        } else {
            smallest.sqrt() / largest.sqrt()
        };
        if quality < 0.1 * self.quality {
            self.stale = true;
        }
        true
    }

    /// Whether the solve takes every free coordinate's motion (no motion without mass, or no
    /// choice of the massive ones yet for these free coordinates), and, if not, whether it
    /// checks the motions left out at this evaluation.
    fn plan(&self, structure: &Structure) -> (bool, bool) {
        let every = structure.massless == 0 || !self.holds(structure);
        (every, !every && self.check_due)
    }

    /// z of `a z = b` for the reduced mass matrix `a` of the kept motions alone (in the order
    /// of `coordinates`), into `b`; `work` is scratch of a's size. When `checking`, `a` and `b`
    /// go on over the motions left out, in the order of `dropped_coordinates`, and no force
    /// may act on them: their reduced equations' imbalance, b_d − Σ a_dk z_k, is checked against
    /// `MASSLESS_FORCE` of `scale`. The position of the motion that lost its mass, or of the
    /// one a force acts on, if any.
    fn solve_kept(
        &mut self,
        a: &DMatrix<f64>,
        work: &mut DMatrix<f64>,
        b: &mut DVector<f64>,
        checking: bool,
        scale: f64,
    ) -> Result<(), usize> {
        let r = self.kept.len();
        for i in 0..r {
            for j in 0..=i {
                work[(i, j)] = a[(i, j)];
            }
        }
        if !self.factor_kept(work) {
            return Err(r - 1);
        }
        cholesky_solve(work, r, &mut b.as_mut_slice()[..r]);
        if checking {
            for d in r..r + self.dropped.len() {
                let unbalanced = b[d] - (0..r).map(|k| a[(d, k)] * b[k]).sum::<f64>();
                if unbalanced.abs() > MASSLESS_FORCE * scale {
                    return Err(d);
                }
            }
            self.check_due = false;
        }
        Ok(())
    }

    /// z of `a z = b` on the kept motions (z zero on the others) into `b`; `work` is scratch of
    /// a's size. The position (among the free coordinates) of a motion without mass that a
    /// force acts on (above `MASSLESS_FORCE` of `scale`), if any: its acceleration would be
    /// infinite.
    fn solve(
        &mut self,
        a: &DMatrix<f64>,
        work: &mut DMatrix<f64>,
        b: &mut DVector<f64>,
        scale: f64,
    ) -> Result<(), usize> {
        let r = self.kept.len();
        for (i, &p) in self.kept.iter().enumerate() {
            for (j, &q) in self.kept.iter().enumerate().take(i + 1) {
                work[(i, j)] = a[(p, q)];
            }
        }
        if !self.factor_kept(work) {
            return Err(self.kept[r - 1]);
        }
        self.check_due = false;
        self.rhs.clear();
        self.rhs.extend(self.kept.iter().map(|&p| b[p]));
        cholesky_solve(work, r, &mut self.rhs);
        for &d in &self.dropped {
            let unbalanced: f64 = b[d]
                - self
                    .kept
                    .iter()
                    .zip(&self.rhs)
                    .map(|(&p, z)| a[(d, p)] * z)
                    .sum::<f64>();
            if unbalanced.abs() > MASSLESS_FORCE * scale {
                return Err(d);
            }
        }
        b.fill(0.0);
        for (&p, z) in self.kept.iter().zip(&self.rhs) {
            b[p] = *z;
        }
        Ok(())
    }
}

/// The smallest of positive pivots over the largest (0 for none).
fn pivot_ratio(pivots: &[f64]) -> f64 {
    let largest = pivots.iter().copied().fold(0.0, f64::max);
    let smallest = pivots.iter().copied().fold(f64::INFINITY, f64::min);
    if largest > 0.0 {
        smallest / largest
    } else {
        0.0
    }
}

/// x ← (LLᵀ)⁻¹ x for the factor L in the leading r × r lower triangle of `l`.
fn cholesky_solve(l: &DMatrix<f64>, r: usize, x: &mut [f64]) {
    for i in 0..r {
        let dot: f64 = (0..i).map(|k| l[(i, k)] * x[k]).sum();
        x[i] = (x[i] - dot) / l[(i, i)];
    }
    for i in (0..r).rev() {
        let dot: f64 = (i + 1..r).map(|k| l[(k, i)] * x[k]).sum();
        x[i] = (x[i] - dot) / l[(i, i)];
    }
}

/// Solves the symmetric positive definite system `a z = b` (z into `b`) by Cholesky; `work` is
/// scratch of a's size. A matrix that is not positive definite (a motion of no mass the
/// structure did not count) is solved in the span of its eigenvectors of positive eigenvalue,
/// which allocates; a force on the others (above `MASSLESS_FORCE` of `scale`) is the error (the
/// free coordinate its eigenvector moves most).
fn massive_solve(
    a: &DMatrix<f64>,
    work: &mut DMatrix<f64>,
    b: &mut DVector<f64>,
    scale: f64,
) -> Result<(), usize> {
    if a.nrows() == 0 {
        return Ok(());
    }
    work.copy_from(a);
    // The factorisation takes the buffer and gives it back: no allocation.
    if let Some(cholesky) = Cholesky::new(std::mem::take(work)) {
        cholesky.solve_mut(b);
        *work = cholesky.unpack_dirty();
        return Ok(());
    }
    *work = a.clone();
    let eigen = a.clone().symmetric_eigen();
    let mut z = DVector::zeros(b.len());
    for (k, &value) in eigen.eigenvalues.iter().enumerate() {
        let vector = eigen.eigenvectors.column(k);
        let component = vector.dot(b);
        if value > 0.0 {
            z += vector * (component / value);
        } else if component.abs() > MASSLESS_FORCE * scale {
            return Err(vector.iamax());
        }
    }
    b.copy_from(&z);
    Ok(())
}
