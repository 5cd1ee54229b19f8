//! Moving a state back onto the loops: Gauss–Newton steps on the positions with minimum-norm
//! corrections (the free motions are not disturbed), then the orthogonal projection of the
//! velocities onto G v = 0. Along a run the steps use the rows the `Structure` keeps and their
//! sparse factorisation (`Factored`); before the structure is known (closing the initial configuration, looking
//! at its neighbours), they use every row through a singular value decomposition.

use nalgebra::{DMatrix, DVector};

use super::factored::{
    Damped, Envelope, Factored, RowChoice, Singular, DAMPING, PROJECTION_DAMPING,
};
use super::passes::{passes_up_to, BodyPasses};
use super::planar_closure::PlanarClosure;
use super::rows::{
    complete_rotations, complete_rows, constraints_into, seat_ball_angles_at_poses, Constraints,
    Extent,
};
use crate::corrector::{correct, Acceptance, Correction, Damping, Progress, Settings};
use crate::dynamics::algorithms::{forward_kinematics, mass_rows, Data};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;
use crate::spatial::Pose;

/// Constraint residuals before and after a projection: largest position row (metres or
/// radians) and largest velocity row.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Residuals {
    pub position: f64,
    pub velocity: f64,
}

pub struct Projection {
    pub before: Residuals,
    pub after: Residuals,
    /// The largest kept row left after it, made dimensionless, and that row (among the 6 per
    /// loop).
    pub left: (f64, Option<usize>),
}

const NEWTON_ITERATIONS: usize = 8;

/// Above this conditioning of the kept rows, and when none of them is weak, the factor taken
/// to measure it (damped by `DAMPING`) also serves the projection's first step:
/// `PROJECTION_DAMPING` would change that step by (μ/σ)² ≤ 4e-10 of itself, and the steps after
/// it correct what remains. Weak rows (`RowChoice::weak`) are not damped, but the firm rows'
/// damping enters their pivots, which are about 1e-9: there the two factors differ. Nearer a
/// singular configuration the projection keeps its own damping: with the factor shared from
/// 1e-2 on, a row of two four-bars at 1e-12 passed its flat configurations with an energy drift
/// of 3e-6 instead of 4e-9. From 5e-2 on it is shared by the squeezer (0.07 to 0.09 along its
/// run), and the row keeps its drift.
/// There the factor is also kept for the whole projection (`Held::Earlier`): each later
/// position step and the velocities' projection use the rows where they start with the factor
/// of the rows where the projection started (a chord method). The corrections stay across the
/// current rows (Gᵀy never moves the state along the allowed motions), only their size comes
/// from the older factor, and a step that converges slowly for it is taken again with a fresh
/// one (`ProjectionScratch::refresh`).
const SHARED_FACTOR_ABOVE: f64 = 5e-2;

/// Kept rows' residuals below this (dimensionless: radians, or metres per metre of the
/// mechanism's length) are round-off, or within a few hundred times of it: the residuals are
/// differences of positions a few lengths across, each evaluated to about 1e-16 of itself
/// (steps fail from 1e-16 on the Delta, from some 5e-14 on the squeezer), and 1e-13 is a
/// thousandth of the smallest closure anyone asks of a run (1e-10). Where the rows are well
/// conditioned (`SHARED_FACTOR_ABOVE`), a projection takes no step from there: on the
/// squeezer, a floor of 1e-14 cost it a fifth more. Nearer a singular configuration every
/// projection still steps: how a row of two four-bars passes its flat configurations was
/// measured to depend on such steps (energy drift 9e-9 with them, 1.1e-6 without, rk4 at a
/// step of 1e-4), a sensitivity of the passages themselves that skipping them would expose.
const ROUND_OFF: f64 = 1e-13;

/// A translation row evaluated in the plane (`PlanarClosure`) is within about the unit
/// round-off times its loop's spread (its terms' lengths in quadrature) of its exact value,
/// whatever the chain's extent (measured against the rows' exact values: up to 0.6 of that on
/// necklaces of 100 rods of 1 m and of 30 m); below eight times that, a step would no longer
/// reduce what is left fourfold. On a necklace of 1,000 rods of 1 m that is 5.6e-14 m, where
/// `ROUND_OFF` of the mechanism's length allowed 8e-11 m.
const PLANAR_ROUND_OFF: f64 = 8.0 * f64::EPSILON;

/// A projection factor taken where the kept rows' largest residual (dimensionless) is above
/// this serves only its own step, not the later ones as an earlier factor (`Held::Earlier`).
/// The chord steps converge, and the velocities projected with that factor keep of their rows'
/// residual, about the distance the positions moved since it was taken over the rows'
/// conditioning (at least `SHARED_FACTOR_ABOVE`): from 1e-6, the loops' open limit of a run,
/// that is some 2e-5, while a step that strayed 0.24 m from a five-bar's loops (rk4 at steps
/// far too long) left the chord converging sixfold a step, 2e-8 m open after the eight steps,
/// and 6 % of the velocities' residual. The examples' projections all start below 1e-10.
const CHORD_WITHIN: f64 = 1e-6;

/// What a projection keeps from one call to the next, so that it allocates nothing once sized:
/// the constraints at the current and the trial positions, the kept rows' factorisation, and
/// the vectors of the steps.
pub struct ProjectionScratch {
    pub current: Constraints,
    trial: Constraints,
    pub factored: Factored,
    factor: Envelope,
    /// Which factor of the rows in `factored` `factor` holds.
    held: Held,
    /// Whether the factor held for the conditioning serves the projection too, and is kept
    /// along it (`SHARED_FACTOR_ABOVE`).
    shared: bool,
    /// Whether the projection factor held was taken where the kept rows' residual is within
    /// `CHORD_WITHIN`, so that it may serve the later steps as an earlier one.
    near: bool,
    /// Whether `factored` holds the kept rows of `current` (for the choice it records) and
    /// their normal matrix, so that factoring them with another damping needs no refill.
    rows_of_current: bool,
    /// Whether `factored` holds the values of `current`'s kept rows, its normal matrix perhaps
    /// still that of earlier positions (`Held::Earlier`).
    values_of_current: bool,
    kept: Vec<f64>,
    correction: Vec<f64>,
    trial_q: Vec<f64>,
    rest: Vec<f64>,
    /// G v, the velocity rows.
    velocity: DVector<f64>,
    /// The bodies' poses at the positions `current` belongs to (a rejected trial leaves its
    /// own in `Data`).
    poses: Vec<Pose>,
    /// The kept rows over the free coordinates, through the factor (L⁻¹Gₛ), and the factor of
    /// the projector's block over them (`free_quality`).
    free_columns: DMatrix<f64>,
    block: DMatrix<f64>,
    /// The same measure, when the equations of motion took it at this step's start
    /// (`offer_free_quality`).
    offered_quality: Option<f64>,
    /// Whether `current` and the factor held were adopted from the equations of motion at the
    /// state being projected (`adopt`), so that they need not be computed again.
    adopted: bool,
    /// A row left out and its coefficients on the kept rows (`reproduction`).
    row: Vec<f64>,
    coefficients: Vec<f64>,
    /// The loops' translation rows of a planar mechanism, evaluated so that their round-off
    /// does not grow with the chain's extent (`close_in_plane`).
    plane: Option<PlanarClosure>,
    /// The mass matrix and the rows each of its columns can fill (`mass_rows`), for the
    /// momentum projection of large mechanisms (`project_momentum`); empty until asked for.
    mass: DMatrix<f64>,
    mass_rows: Vec<Vec<usize>>,
    /// `passes_up_to` of the mass matrix's layout, with `mass_rows`.
    passes_up_to: usize,
    /// The bodies' motions under the allowed motions, where they cost less than the mass
    /// matrix (`project_momentum`).
    passes: BodyPasses,
}

/// The factor a `ProjectionScratch` holds.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Held {
    /// None (the rows could not be factored).
    Nothing,
    /// Damped by `DAMPING`, for the conditioning and the free coordinates' quality.
    Conditioning,
    /// Damped by `PROJECTION_DAMPING`, for the position steps and the velocities.
    Projection,
    /// `Projection`'s factor, of the rows at positions a projection has since moved from: it
    /// serves the later steps with the rows where they start (`SHARED_FACTOR_ABOVE`).
    Earlier,
}

impl ProjectionScratch {
    pub fn new(model: &Model) -> ProjectionScratch {
        let current = Constraints::new(model);
        ProjectionScratch {
            trial: Constraints::new(model),
            factored: Factored::new(&current.jacobian, &RowChoice::NONE),
            current,
            factor: Envelope::default(),
            held: Held::Nothing,
            shared: false,
            near: false,
            rows_of_current: false,
            values_of_current: false,
            kept: Vec::new(),
            correction: vec![0.0; model.velocities()],
            trial_q: Vec::new(),
            rest: vec![0.0; model.velocities()],
            velocity: DVector::zeros(6 * model.loops.len()),
            poses: Vec::new(),
            free_columns: DMatrix::zeros(0, 0),
            block: DMatrix::zeros(0, 0),
            offered_quality: None,
            adopted: false,
            row: Vec::new(),
            coefficients: Vec::new(),
            plane: None,
            mass: DMatrix::zeros(0, 0),
            mass_rows: Vec::new(),
            passes_up_to: 0,
            passes: BodyPasses::default(),
        }
    }

    /// The mass matrix's storage (filled by `crba_into` where it writes, zero elsewhere) and
    /// the rows of each column it can fill, sized for `model` on first use.
    pub fn mass_storage(&mut self, model: &Model) -> (&mut DMatrix<f64>, &[Vec<usize>]) {
        self.mass_layout(model);
        if self.mass.nrows() != model.nv {
            self.mass = DMatrix::zeros(model.nv, model.nv);
        }
        (&mut self.mass, &self.mass_rows)
    }

    /// The rows each column of `model`'s mass matrix can fill (`mass_rows`) and up to how many
    /// motions the bodies' passes cost less than the matrix (`passes_up_to`), found on first
    /// use.
    pub fn mass_layout(&mut self, model: &Model) -> (&[Vec<usize>], usize) {
        if self.mass_rows.len() != model.nv {
            self.mass_rows = mass_rows(model);
            self.passes_up_to = passes_up_to(model, &self.mass_rows);
        }
        (&self.mass_rows, self.passes_up_to)
    }

    /// The bodies' passes' storage (`project_momentum`).
    pub fn passes(&mut self) -> &mut BodyPasses {
        &mut self.passes
    }

    /// Evaluates the loops' translation rows in the plane from now on (`PlanarClosure`), or
    /// in the spatial rows with `None`: the residuals the projection steps from and reports.
    pub fn close_in_plane(&mut self, closure: Option<PlanarClosure>) {
        self.plane = closure;
    }

    /// The planar evaluation of the translation rows, if taken (`close_in_plane`).
    pub fn plane_closure(&self) -> Option<&PlanarClosure> {
        self.plane.as_ref()
    }
}

/// Moves (q, v) onto the kept rows of the constraints.
pub fn project(
    model: &Model,
    data: &mut Data,
    choice: &RowChoice,
    q: &mut [f64],
    v: &mut [f64],
) -> Result<Projection, EvalError> {
    let mut scratch = ProjectionScratch::new(model);
    forward_kinematics(model, data, q, v)?;
    scratch.constraints_at(model, data, q, v)?;
    project_from(model, data, choice, q, v, &mut scratch)
}

/// `project` from the constraints at (q, v) already in `scratch.current`: Gauss–Newton on the
/// positions, each step with the kept rows factored where it starts, then the velocities'
/// projection with the factor at the final positions (the last accepted step's). A factor
/// taken once and kept along the steps would cost less, but where rows close their loop only
/// at second order (the meshes) their independence is about 1e-8, the rows turn fast against
/// it, and the minimum-norm corrections of an older factor move the state along the closed set
/// (maille2's error at 1e-10 grew tenfold so). Nothing is allocated once `scratch` is sized.
pub fn project_from(
    model: &Model,
    data: &mut Data,
    choice: &RowChoice,
    q: &mut [f64],
    v: &mut [f64],
    scratch: &mut ProjectionScratch,
) -> Result<Projection, EvalError> {
    let before = Residuals {
        position: scratch.current.residual.amax(),
        velocity: scratch.current.velocity.amax(),
    };
    let closed = |s: &ProjectionScratch| s.at_round_off(choice);
    newton(model, data, q, scratch, closed, |s| s.damped_step(choice))?;
    let velocity = scratch.project_velocities(choice, v);
    data.world.clone_from(&scratch.poses);
    seat_ball_angles_at_poses(model, data, q, v)?;
    let current = &scratch.current;
    Ok(Projection {
        before,
        after: Residuals {
            position: current.residual.amax(),
            velocity,
        },
        left: largest_kept(&current.residual, choice),
    })
}

impl ProjectionScratch {
    /// Takes, for the projection of the state the equations of motion were last evaluated at
    /// (the last stage of a dopri5 step is its end), their constraints, their kept rows'
    /// factorisation and its factor, damped by `DAMPING` as `conditioning` would take it
    /// (`LoopScratch::hand_over`), in exchange for this scratch's storage: the projection then
    /// starts without computing the rows or a factor (`constraints_here`).
    pub fn adopt(
        &mut self,
        constraints: &mut Constraints,
        factored: &mut Factored,
        factor: &mut Envelope,
    ) {
        std::mem::swap(&mut self.current, constraints);
        std::mem::swap(&mut self.factored, factored);
        std::mem::swap(&mut self.factor, factor);
        self.rows_of_current = true;
        self.values_of_current = true;
        self.held = Held::Conditioning;
        self.adopted = true;
    }

    /// The constraints at (q, v) into `current`, unless they were adopted (`adopt`): then only
    /// the rows' rotations, which the equations of motion leave out unless Baumgarte's feedback
    /// reads them. `data` must hold the forward kinematics of (q, v).
    pub fn constraints_here(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), EvalError> {
        if std::mem::take(&mut self.adopted) {
            complete_rotations(model, data, v, &mut self.current);
            if let Some(plane) = &mut self.plane {
                plane.translations_into(model, q, &mut self.current);
            }
            return Ok(());
        }
        self.constraints_at(model, data, q, v)
    }

    /// The constraints at (q, v) into `current`; `data` must hold the forward kinematics of
    /// (q, v).
    pub fn constraints_at(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), EvalError> {
        self.moved_to_current(false);
        constraints_into(model, data, q, v, Extent::Rows, &mut self.current)?;
        if let Some(plane) = &mut self.plane {
            plane.translations_into(model, q, &mut self.current);
        }
        Ok(())
    }

    /// The kept rows of `current` for `choice` into `factored`, unless it holds them already
    /// (then the factor held, if any, is theirs).
    fn fill_rows(&mut self, choice: &RowChoice) {
        if !(self.rows_of_current && self.factored.holds(choice)) {
            self.factored.refill(&self.current.jacobian, choice);
            self.rows_of_current = true;
            self.values_of_current = true;
            self.held = Held::Nothing;
        }
    }

    /// How far the kept rows of the current constraints are from dependent
    /// (`Factored::conditioning`, damped by `DAMPING`).
    pub fn conditioning(&mut self, choice: &RowChoice) -> (f64, Option<usize>) {
        // A factor already taken of these rows (`adopt`) serves as it is.
        let held = self.held == Held::Conditioning && self.rows_of_current;
        let damped = if held && self.factored.holds(choice) {
            Ok(self.factored.with_factor(std::mem::take(&mut self.factor)))
        } else {
            self.fill_rows(choice);
            self.factored
                .damped_in(DAMPING, std::mem::take(&mut self.factor))
        };
        let conditioning = self.factored.conditioning_of(&damped);
        self.shared = conditioning.0 >= SHARED_FACTOR_ABOVE && choice.weak == 0;
        self.held = match damped {
            Ok(damped) => {
                self.factor = damped.into_storage();
                Held::Conditioning
            }
            Err(_) => Held::Nothing,
        };
        conditioning
    }

    /// How well the free coordinates `free` parametrise the allowed motions of the rows
    /// `conditioning` just factored (`Structure::free_quality_at`); None if they could not be.
    /// A quality offered (`offer_free_quality`) is taken instead, once.
    pub fn free_quality(&mut self, free: &[usize]) -> Option<f64> {
        if let Some(offered) = self.offered_quality.take() {
            return Some(offered);
        }
        let factored = self.held == Held::Conditioning;
        if !factored || free.is_empty() {
            return factored.then_some(1.0);
        }
        let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
        let quality = damped.free_quality_into(
            free,
            &mut self.kept,
            &mut self.free_columns,
            &mut self.block,
        );
        self.factor = damped.into_storage();
        Some(quality)
    }

    /// Offers `free_quality` a measure the equations of motion took on the same rows and free
    /// coordinates at the start of the step just made (`LoopScratch::take_free_quality`): it
    /// lags the state by one step, which the margin of the test on it (a tenth of its value
    /// when chosen) allows, and spares its own factorisation. None withdraws an offer.
    pub fn offer_free_quality(&mut self, quality: Option<f64>) {
        self.offered_quality = quality;
    }

    /// How well the rows `conditioning` just factored reproduce the active rows left out
    /// (`Damped::reproduction`); None if they could not be factored.
    pub fn reproduction(&mut self, active: &[bool], lengths: &[f64]) -> Option<f64> {
        if self.held != Held::Conditioning {
            return None;
        }
        let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
        let jacobian = &self.current.jacobian;
        let value = damped.reproduction(
            jacobian,
            active,
            lengths,
            &mut self.row,
            &mut self.coefficients,
        );
        self.factor = damped.into_storage();
        Some(value)
    }

    /// Hands `use_rows` the kept rows of `choice` at the current constraints (where the last
    /// projection ended) and their factorisation damped by `DAMPING`, which is then held as
    /// the conditioning's (`conditioning`). The rows are filled again only if the projection's
    /// last factor was of earlier rows (`Held::Earlier`); their layout is the projection's own.
    pub fn with_final_rows<T>(
        &mut self,
        choice: &RowChoice,
        use_rows: impl FnOnce(&Factored, &Result<Damped<'_>, Singular>) -> T,
    ) -> T {
        self.fill_rows(choice);
        let damped = self
            .factored
            .damped_in(DAMPING, std::mem::take(&mut self.factor));
        let result = use_rows(&self.factored, &damped);
        self.held = match damped {
            Ok(damped) => {
                self.factor = damped.into_storage();
                Held::Conditioning
            }
            Err(_) => Held::Nothing,
        };
        result
    }

    /// Factors the kept rows of the current constraints (damped by `PROJECTION_DAMPING`);
    /// whether they could be factored.
    fn refactor(&mut self, choice: &RowChoice) -> bool {
        self.fill_rows(choice);
        self.near = largest_kept(&self.current.residual, choice).0 <= CHORD_WITHIN;
        if self.held == Held::Conditioning && self.shared {
            self.held = Held::Projection;
            return true;
        }
        let storage = std::mem::take(&mut self.factor);
        self.held = match self.factored.damped_in(PROJECTION_DAMPING, storage) {
            Ok(damped) => {
                self.factor = damped.into_storage();
                Held::Projection
            }
            Err(_) => Held::Nothing,
        };
        self.held == Held::Projection
    }

    /// The damped minimum-norm correction of the kept rows' residual at the current
    /// constraints, into `correction`, with the rows factored there; false if they cannot be.
    fn damped_step(&mut self, choice: &RowChoice) -> bool {
        if self.held == Held::Earlier {
            self.gather_current();
        } else if !self.refactor(choice) {
            return false;
        }
        let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
        self.factored
            .kept_into(self.current.residual.as_slice(), &mut self.kept);
        self.kept.iter_mut().for_each(|x| *x = -*x);
        damped.least_norm_into(&mut self.kept, &mut self.correction);
        self.factor = damped.into_storage();
        true
    }

    /// The velocities' damped projection onto G v = 0 at the current positions, with the
    /// factor taken there (the last position step's, unless a step was accepted after it):
    /// v − Gₛᵀ(A + μ²E)⁻¹Gₛv. With an earlier factor (`Held::Earlier`) the rows are the current
    /// ones and only A is earlier: what its mismatch leaves of Gₛv is of the order of the
    /// position steps since, against the rows' conditioning, times Gₛv; measured on the Delta
    /// and the squeezer it is round-off (1.6e-15 and 1.7e-13 left, a second pass leaving
    /// 1.4e-15 and 3.3e-13). Returns the largest velocity row left.
    fn project_velocities(&mut self, choice: &RowChoice, v: &mut [f64]) -> f64 {
        let factored = match self.held {
            Held::Earlier => {
                self.gather_current();
                true
            }
            Held::Projection => true,
            _ => self.refactor(choice),
        };
        if factored {
            let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
            damped.allowed_part_into(v, &mut self.kept, &mut self.correction);
            self.factor = damped.into_storage();
            v.copy_from_slice(&self.correction);
        }
        self.current.jacobian.mul_into(v, &mut self.velocity);
        self.velocity.amax()
    }

    /// The largest velocity row of v at the current rows (G v), as `project_velocities`
    /// reports it.
    pub fn velocity_residual(&mut self, v: &[f64]) -> f64 {
        self.current.jacobian.mul_into(v, &mut self.velocity);
        self.velocity.amax()
    }

    /// Whether the kept rows are well conditioned and their residual round-off: `ROUND_OFF`
    /// of the mechanism's length, or, for a translation row evaluated in the plane
    /// (`close_in_plane`, loops of long cycles), `PLANAR_ROUND_OFF` times its loop's spread.
    fn at_round_off(&self, choice: &RowChoice) -> bool {
        let residual = &self.current.residual;
        self.shared
            && match &self.plane {
                None => largest_kept(residual, choice).0 <= ROUND_OFF,
                Some(plane) => (choice.rows.iter().zip(&choice.scales)).all(|(&r, scale)| {
                    match plane.spread(r / 6).filter(|_| r % 6 >= 3) {
                        Some(spread) => residual[r].abs() <= PLANAR_ROUND_OFF * spread,
                        None => (residual[r] * scale).abs() <= ROUND_OFF,
                    }
                }),
            }
    }

    /// The values of the current kept rows into `factored`, for a factor of earlier rows.
    fn gather_current(&mut self) {
        if !self.values_of_current {
            self.factored.regather(&self.current.jacobian);
            self.values_of_current = true;
        }
    }

    /// `current` now holds other positions' constraints: the rows in `factored` and the factor
    /// held are no longer theirs. A projection factor kept along the projection
    /// (`SHARED_FACTOR_ABOVE`) stays as an earlier one when `keep_factor`.
    fn moved_to_current(&mut self, keep_factor: bool) {
        self.rows_of_current = false;
        self.values_of_current = false;
        let kept = matches!(self.held, Held::Projection | Held::Earlier);
        self.held = if keep_factor && self.shared && self.near && kept {
            Held::Earlier
        } else {
            Held::Nothing
        };
    }

    /// After a step with an earlier factor that failed, or converged slowly: drops the factor
    /// held, so that the next step factors the rows where it starts.
    fn refresh(&mut self) {
        self.held = Held::Nothing;
    }
}

/// The largest of `choice`'s rows in `residual` (6 per loop), made dimensionless, and that row.
fn largest_kept(residual: &DVector<f64>, choice: &RowChoice) -> (f64, Option<usize>) {
    choice
        .rows
        .iter()
        .zip(&choice.scales)
        .map(|(&r, scale)| ((residual[r] * scale).abs(), r))
        .fold((0.0, None), |(best, row), (value, r)| {
            if row.is_none() || value > best {
                (value, Some(r))
            } else {
                (best, row)
            }
        })
}

/// Moves q onto every row of the constraints (minimum-norm steps on a singular value
/// decomposition, whatever the rank); returns the largest residual left.
pub fn close_configuration(
    model: &Model,
    data: &mut Data,
    q: &mut [f64],
) -> Result<f64, EvalError> {
    let mut scratch = ProjectionScratch::new(model);
    let rest = vec![0.0; model.velocities()];
    forward_kinematics(model, data, q, &rest)?;
    scratch.constraints_at(model, data, q, &rest)?;
    newton(model, data, q, &mut scratch, |_| false, minimum_norm_step)?;
    Ok(scratch.current.residual.amax())
}

/// The minimum-norm correction of every row's residual, on the independent rows picked by a
/// sparse pivoted Gram–Schmidt (`elimination::minimum_norm_step`): what a singular value
/// decomposition's pseudo-inverse gives, at the cost of the loops' sparsity.
fn minimum_norm_step(s: &mut ProjectionScratch) -> bool {
    let c = &s.current;
    let step = super::elimination::minimum_norm_step(&c.jacobian, &c.residual);
    s.correction.copy_from_slice(step.as_slice());
    true
}

/// Gauss–Newton on the positions from the constraints in `scratch.current` (the house's
/// corrector, `corrector::correct`, without damping): `step` writes the correction at them into
/// `scratch.correction` (false to stop); stops when a step no longer reduces the largest
/// residual, or reduces it less than fourfold. Leaves q and `scratch.current` at the best
/// configuration reached, and the bodies' poses there in `scratch.poses` (`data` must hold them
/// at the start); an accepted step leaves no factor held (the one `step` took belongs to the
/// positions before it), unless it is kept along the projection as an earlier one
/// (`Held::Earlier`): a step with it that fails or converges slowly is taken again with a fresh
/// factor (`ProjectionScratch::refresh`). No step is taken from a residual that `round_off`
/// says is round-off.
fn newton(
    model: &Model,
    data: &mut Data,
    q: &mut [f64],
    scratch: &mut ProjectionScratch,
    round_off: impl Fn(&ProjectionScratch) -> bool,
    step: impl FnMut(&mut ProjectionScratch) -> bool,
) -> Result<(), EvalError> {
    scratch.poses.clone_from(&data.world);
    let mut steps = NewtonSteps {
        model,
        data,
        q,
        scratch,
        round_off,
        step,
        chord: false,
    };
    correct(&mut steps, &NEWTON)?;
    Ok(())
}

/// The projection's iteration: Gauss–Newton, a step kept while it reduces the largest residual
/// at least fourfold.
const NEWTON: Settings = Settings {
    iterations: NEWTON_ITERATIONS,
    damping: Damping::None,
    acceptance: Acceptance::Descent,
    progress: Progress::Ratio(0.25),
};

/// The positions' Gauss–Newton steps onto the loops, for the corrector.
struct NewtonSteps<'a, R, S> {
    model: &'a Model,
    data: &'a mut Data,
    q: &'a mut [f64],
    scratch: &'a mut ProjectionScratch,
    round_off: R,
    step: S,
    /// Whether the step tried was taken with an earlier factor (`Held::Earlier`).
    chord: bool,
}

impl<R, S> Correction for NewtonSteps<'_, R, S>
where
    R: Fn(&ProjectionScratch) -> bool,
    S: FnMut(&mut ProjectionScratch) -> bool,
{
    type Error = EvalError;

    fn settled(&self) -> bool {
        self.merit() == 0.0 || (self.round_off)(self.scratch)
    }

    fn merit(&self) -> f64 {
        self.scratch.current.residual.amax()
    }

    fn step(&mut self, _damping: f64) -> Result<Option<f64>, EvalError> {
        self.chord = self.scratch.held == Held::Earlier;
        Ok((self.step)(self.scratch).then_some(0.0))
    }

    fn try_step(&mut self) -> Result<f64, EvalError> {
        let s = &mut *self.scratch;
        s.trial_q.clear();
        s.trial_q.extend_from_slice(self.q);
        self.model.retract(&mut s.trial_q, &s.correction);
        forward_kinematics(self.model, self.data, &s.trial_q, &s.rest)?;
        // G at a trial is needed only if the trial is kept.
        constraints_into(
            self.model,
            self.data,
            &s.trial_q,
            &s.rest,
            Extent::Residual,
            &mut s.trial,
        )?;
        if let Some(plane) = &mut s.plane {
            plane.translations_into(self.model, &s.trial_q, &mut s.trial);
        }
        Ok(s.trial.residual.amax())
    }

    fn accept(&mut self) {
        let s = &mut *self.scratch;
        complete_rows(self.model, self.data, &s.rest, &mut s.trial);
        self.q.copy_from_slice(&s.trial_q);
        std::mem::swap(&mut s.current, &mut s.trial);
        s.moved_to_current(true);
        s.poses.clone_from(&self.data.world);
    }

    fn retry(&mut self) -> bool {
        if self.chord {
            self.scratch.refresh();
        }
        self.chord
    }
}
