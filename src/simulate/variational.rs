//! A variational integrator for long conservative runs: the discrete Euler–Lagrange equations of
//! the midpoint discrete Lagrangian L_d(q0, q1) = h L((q0 + q1)/2, (q1 − q0)/h), with the
//! efforts entering as discrete Lagrange–d'Alembert forces. It is symplectic and
//! momentum-preserving, so the energy error stays bounded instead of drifting. Each step solves
//!   p_k = M(q̄) v̄ − h/2 (∂T/∂q(q̄, v̄) + Q(q̄, v̄))   for q_{k+1},
//! then p_{k+1} = M(q̄) v̄ + h/2 (∂T/∂q(q̄, v̄) + Q(q̄, v̄)), with q̄, v̄ the midpoint and mean
//! velocity of the step and Q the generalised efforts.
//!
//! Spherical and free joints step on their groups, SO(3) and SE(3) (`lie_group`): the discrete
//! Lagrangian is h L(q0 · exp(X/2), X/h) with q1 = q0 · exp(X), and its discrete Euler–Lagrange
//! equations, written in the velocities' space with left-trivialised variations δq = q·η, are
//!   p_k = J_l(X)⁻ᵀ Π − h Ad_{exp(−X/2)}ᵀ g,   p_{k+1} = J_r(X)⁻ᵀ Π,   Π = M v̄ + h/2 J_r(X/2)ᵀ g,
//! with v̄ = X/h, g = ∂T/∂q + Q at the midpoint and J_r, J_l the exponential's Jacobians: on
//! coordinates they are the identity and these are the equations above. The discrete Lagrangian
//! is symmetric (second order); the quaternions are products of unit quaternions. References:
//! Marsden and West, Acta Numerica 10 (2001) 357–514; Lee, Leok and McClamroch, Comput. Methods
//! Appl. Mech. Engrg. 196 (2007) 2907–2924; Bou-Rabee and Marsden, Found. Comput. Math. 9 (2009)
//! 197–219; `docs/commands.md`, *Rotations on the group*.
//!
//! With loops the same discrete Lagrangian is constrained (RATTLE): the step also solves for the
//! impulse h·Gᵀλ of the constraint forces at its start so that the positions at its end close
//! every loop, and the end momentum is projected so that the velocities satisfy G v = 0. The
//! complementary links' coordinates carry no inertia; the constrained systems are solved by the
//! null-space method (Leyendecker, Marsden and Ortiz, ZAMM 88 (2008) 677–708) in the
//! least-squares sense, so redundant constraints cost nothing special, and on the allowed
//! motions that carry mass: those without mass are left at rest (see `with_mass`).
//!
//! The loops are the constraint stack's first block (`system::stack`), and the steps solve that
//! block as the run's equations do: the same kept rows in the same sparse factorisation
//! (`MechanicalSystem::loop_block_at`), its particular solutions and allowed motions. What is
//! the integrator's own is inherent to the method: the right-hand sides (the impulse acts
//! along the rows at the step's start, G(q₀)ᵀ, while the closure holds at its end, G(q₁)), and
//! the positions' closure, which is one of the step's implicit equations, solved with the
//! momentum balance by the same Newton iteration, not a projection after the step (a projection
//! through the corrector would break the map's symplecticity; the end state is only measured,
//! `measure_loops`). The integrator refuses every other kind of row (`integrators`), so the
//! loops' block is the whole stack it meets.

use std::fmt;

use nalgebra::{DMatrix, DVector};

use super::lie_group::Configuration;
use super::system::{MechanicalSystem, RunObserver, SystemError};
use crate::dynamics::algorithms::{crba, forward_kinematics, rnea};
use crate::dynamics::derivatives::kinetic_energy_gradient;
use crate::dynamics::efforts::{evaluate, Declared};
use crate::dynamics::loops::{self, Factored, LoopError, Singular, DAMPING};
use crate::integrate::{error_norm, Failure, IntegrationError, Interrupt, Stats, StepError};

const MAX_ITERATIONS: usize = 50;

/// Newton's corrections of a step's end positions, relative to 1 + |q|: below the first it has
/// converged; below the second it has converged if it no longer contracts (its corrections are
/// then round-off, which on a row of ten four-bars stays at 2.7e-15 and never falls below the
/// first).
const CONVERGED: f64 = 1e-15;
const ROUND_OFF: f64 = 1e-13;

/// A loop residual (radians, or metres) below which a step's end is not corrected further.
const CLOSED: f64 = 1e-13;

/// The largest loop residual a converged step may leave. Near a singular configuration (a row
/// of four-bars passing flat) the rows about to lose their independence close only at second
/// order, and no first-order correction closes them further: 5e-9 is left on the row of 40 at
/// its flat passage, and closed again by the steps after it.
const LEFT_OPEN: f64 = 1e-6;

impl MechanicalSystem<'_> {
    /// The generalised efforts at (q, v, t): link efforts plus the applied efforts seen through
    /// the Jacobians (computed as −RNEA with no motion).
    fn generalised_efforts(
        &mut self,
        q: &[f64],
        v: &[f64],
        t: f64,
    ) -> Result<DVector<f64>, SystemError> {
        let model = self.model;
        let efforts = if model.nq == model.nv {
            // Every joint is a chain: the state is the declared coordinates and rates.
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
            // The symplectic integrator refuses states (`integrators`): none to read.
            let declared = Declared {
                model,
                coordinates: q,
                rates: v,
                states: &[],
            };
            evaluate(model, &mut self.scratch.data, &declared, t)?
        } else {
            // The spherical and free joints' declared angles are recovered from their
            // quaternions, as for the other integrators.
            self.efforts(t, q, v)?
        };
        let zero = vec![0.0; model.nv];
        let applied = rnea(
            model,
            &mut self.scratch.data,
            q,
            &zero,
            &zero,
            &efforts.external,
        )?;
        let mut forcing = efforts.tau;
        let mut tree = forcing.rows_mut(0, model.nv);
        tree -= applied;
        Ok(forcing)
    }

    /// ∂T/∂q + Q at the step's midpoint, and the mass matrix there (the complementary links'
    /// coordinates, if any, with no inertia).
    fn midpoint_terms(
        &mut self,
        q: &[f64],
        v: &[f64],
        t: f64,
    ) -> Result<(DMatrix<f64>, DVector<f64>), SystemError> {
        let model = self.model;
        let gradient = kinetic_energy_gradient(model, &mut self.scratch.data, q, v)?;
        let mut terms = self.generalised_efforts(q, v, t)?;
        let mut tree = terms.rows_mut(0, model.nv);
        tree += gradient;
        Ok((self.mass(q)?, terms))
    }

    /// The mass matrix over the state's velocities.
    fn mass(&mut self, q: &[f64]) -> Result<DMatrix<f64>, SystemError> {
        let model = self.model;
        let tree = crba(model, &mut self.scratch.data, q)?;
        if !model.has_loops() {
            return Ok(tree);
        }
        let mut mass = DMatrix::zeros(model.velocities(), model.velocities());
        mass.view_mut((0, 0), (model.nv, model.nv)).copy_from(&tree);
        Ok(mass)
    }

    /// The motions the kept constraint rows allow at the start of a step, and how the step
    /// spans them (None for a tree).
    fn allowed_motions(&mut self, q: &[f64]) -> Result<Option<StepStart>, SystemError> {
        if !self.model.has_loops() {
            return Ok(None);
        }
        let (_, start) = self.loop_block_at(q)?;
        let basis = Basis::at(&start);
        let allowed = allowed_by(&start, basis, &self.scratch.loops.structure.free)
            .map_err(|e| self.loop_error(&e))?;
        let massless = self.massless_motions(basis);
        let allowed = with_mass(&self.mass(q)?, allowed, massless);
        Ok(Some(StepStart { basis, allowed }))
    }

    /// How many of the allowed motions spanned as `basis` says carry no mass: those the
    /// loops' structure counted, and with the orthonormal basis the idle coordinates' too.
    fn massless_motions(&self, basis: Basis) -> usize {
        let structure = &self.scratch.loops.structure;
        match basis {
            Basis::Free => structure.massless,
            Basis::Orthonormal => structure.massless + structure.idle.len(),
        }
    }

    /// The Newton correction of q1 for the momentum residual `rhs` (scaled by h), and how far
    /// q1 leaves the loops open. With loops, the balance holds up to the constraint impulse at
    /// the start of the step, Gᵀ(q)·(h λ): only its part on the motions G(q) allows is an
    /// equation for q1, and the closure at q1 is the other.
    fn correction(
        &mut self,
        mass: &DMatrix<f64>,
        start: &Option<StepStart>,
        q1: &[f64],
        rhs: &DVector<f64>,
    ) -> Result<(DVector<f64>, f64), SystemError> {
        let Some(start) = start else {
            return Ok((solve(mass, rhs)?, 0.0));
        };
        let (closure, end) = self.loop_block_at(q1)?;
        let open = closure.amax();
        // A closure already within what the step accepts is not corrected: rows that close their
        // loop only at second order (the meshes) would turn its round-off into corrections of
        // 1e-8 along them, and the iteration would never settle.
        let rows = match open <= CLOSED {
            true => DVector::zeros(end.len()),
            false => end.kept(&-&closure),
        };
        let (free, massless) = (
            &self.scratch.loops.structure.free,
            self.massless_motions(start.basis),
        );
        let spans = Spans {
            start: Some(start),
            basis: start.basis,
            free,
            massless,
        };
        let correction =
            constrained_solve(mass, &end, &spans, rhs, &rows).map_err(|e| self.loop_error(&e))?;
        Ok((correction, open))
    }

    /// The velocities of momentum p at q1 (projected onto the loops' velocity constraints: the
    /// RATTLE step), and the mass matrix there.
    fn end_velocity(
        &mut self,
        q1: &[f64],
        p: &DVector<f64>,
        basis: Basis,
    ) -> Result<(DVector<f64>, DMatrix<f64>), SystemError> {
        let mass = self.mass(q1)?;
        if !self.model.has_loops() {
            return Ok((solve(&mass, p)?, mass));
        }
        let (_, end) = self.loop_block_at(q1)?;
        let rows = DVector::zeros(self.scratch.loops.structure.choice.rows.len());
        let (free, massless) = (
            &self.scratch.loops.structure.free,
            self.massless_motions(basis),
        );
        let spans = Spans {
            start: None,
            basis,
            free,
            massless,
        };
        let velocity =
            constrained_solve(&mass, &end, &spans, p, &rows).map_err(|e| self.loop_error(&e))?;
        Ok((velocity, mass))
    }
}

/// How `constrained_solve` spans the motions the loops allow.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Basis {
    /// The allowed motions of the free coordinates (`Damped::allowed_motions`): one sparse solve
    /// each, as in the equations of motion, so that a step costs what the loops' structure
    /// costs.
    Free,
    /// An orthonormal basis from a dense QR factorisation of the kept rows, near a singular
    /// configuration (conditioning below `DENSE_BELOW`).
    Orthonormal,
}

/// Below this conditioning σ of the kept rows at a step's start, the step uses
/// `Basis::Orthonormal`: the sparse solves work on the normal matrix, whose round-off costs ε/σ²
/// and whose damping (μ/σ)², both above 1e-8 from here. On the row of 40 four-bars through its
/// flat configurations (σ down to 3e-7), the closed form's energy error is 4.8e-6 so, 8.3e-6
/// with the orthonormal basis at every step, 1.9e-4 with the sparse solves at every step.
const DENSE_BELOW: f64 = 1e-4;

impl Basis {
    fn at(start: &Factored) -> Basis {
        match start.conditioning().0 < DENSE_BELOW {
            true => Basis::Orthonormal,
            false => Basis::Free,
        }
    }
}

/// What a step keeps of its start: the basis it spans the allowed motions with, and those
/// motions there (where the constraint impulse acts), found once for all its iterations.
struct StepStart {
    basis: Basis,
    allowed: DMatrix<f64>,
}

fn singular(lost: Singular) -> LoopError {
    LoopError::Singular { row: lost.row }
}

/// The motions `factored`'s rows allow, spanned as `basis` says.
fn allowed_by(
    factored: &Factored,
    basis: Basis,
    free: &[usize],
) -> Result<DMatrix<f64>, LoopError> {
    Ok(match basis {
        Basis::Free => factored
            .damped(DAMPING)
            .map_err(singular)?
            .allowed_motions(free),
        Basis::Orthonormal => factored.dense_null_space().clone(),
    })
}

/// How `constrained_solve` spans the motions the loops allow: the step's start (None when the
/// start is the end), the basis, the free coordinates, and how many allowed motions carry no
/// mass.
struct Spans<'s> {
    start: Option<&'s StepStart>,
    basis: Basis,
    free: &'s [usize],
    massless: usize,
}

/// Solves `a x − g_startᵀ w = f` (for some w) with `g_end x = c` on the kept rows by the
/// null-space method: x is the minimum-norm solution of the constraints plus a motion they
/// allow, chosen so that the first equation holds on the motions the start's constraints allow
/// (`spans.start`). The allowed motions are spanned as `spans.basis` says, less those without
/// mass (see `with_mass`). The small system over them is solved in the least-squares sense.
fn constrained_solve(
    a: &DMatrix<f64>,
    end: &Factored,
    spans: &Spans,
    f: &DVector<f64>,
    c: &DVector<f64>,
) -> Result<DVector<f64>, LoopError> {
    let (particular, allowed_end) = match spans.basis {
        Basis::Free => {
            let factor = end.damped(DAMPING).map_err(singular)?;
            (factor.least_norm(c), factor.allowed_motions(spans.free))
        }
        Basis::Orthonormal => (
            end.least_norm(c).map_err(singular)?,
            end.dense_null_space().clone(),
        ),
    };
    let allowed_end = with_mass(a, allowed_end, spans.massless);
    if allowed_end.ncols() == 0 {
        return Ok(particular);
    }
    let allowed_start = spans.start.map_or(&allowed_end, |start| &start.allowed);
    let reduced = allowed_start.transpose() * a * &allowed_end;
    let rhs = allowed_start.transpose() * (f - a * &particular);
    let z = loops::decompose_with(&reduced, 1e-12).pseudo_inverse * rhs;
    Ok(particular + allowed_end * z)
}

/// The allowed motions `allowed` less the `massless` that carry no mass under `mass`: the
/// eigenvectors of its reduced mass matrix with the largest eigenvalues, mapped back. Without
/// mass, such a motion (a point-mass rod's spin about its own axis) is undetermined by the
/// dynamics; the step leaves it at rest, as the equations of motion do. The step's equation
/// along it is degenerate (on a rotation group its increment enters at second order only, exp(X)
/// not being the exponentials of X's parts composed), and the least-squares solve's relative
/// cutoff cannot tell it from a small pivot: on the Delta robot its corrections grew without
/// bound.
fn with_mass(mass: &DMatrix<f64>, allowed: DMatrix<f64>, massless: usize) -> DMatrix<f64> {
    if massless == 0 || allowed.ncols() == 0 {
        return allowed;
    }
    let reduced = allowed.transpose() * mass * &allowed;
    let eigen = reduced.symmetric_eigen();
    let mut order: Vec<usize> = (0..eigen.eigenvalues.len()).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[j].total_cmp(&eigen.eigenvalues[i]));
    let kept = allowed.ncols().saturating_sub(massless);
    let columns: Vec<_> = order[..kept]
        .iter()
        .map(|&k| eigen.eigenvectors.column(k).into_owned())
        .collect();
    match columns.is_empty() {
        true => DMatrix::zeros(allowed.nrows(), 0),
        false => allowed * DMatrix::from_columns(&columns),
    }
}

fn solve(mass: &DMatrix<f64>, rhs: &DVector<f64>) -> Result<DVector<f64>, SystemError> {
    mass.clone()
        .cholesky()
        .map(|c| c.solve(rhs))
        .ok_or(SystemError::SingularMassMatrix)
}

/// The fixed step of the variational integrator, the tolerances its steps are measured
/// against (nothing controls them), and the limits of the run: most steps, and the flag that
/// stops it between two steps.
#[derive(Clone, Debug)]
pub struct FixedStep {
    pub step: f64,
    pub rtol: f64,
    pub atol: f64,
    pub max_steps: usize,
    pub interrupt: Option<Interrupt>,
}

impl FixedStep {
    /// How far the step's mean velocity (its increment over h, the velocity the midpoint rule
    /// takes) is from the mean of its end velocities, in the norm the adaptive methods control:
    /// for the exact motion they differ by h²q‴/12, the order of the method's local error over
    /// h, so a defect above the tolerances says the step is too long for the motion (a stiff
    /// spring, a fast passage) however well the energy is kept.
    fn defect_norm(&self, mean: &DVector<f64>, v: &DVector<f64>, v1: &DVector<f64>) -> f64 {
        let defect: Vec<f64> = (0..mean.len())
            .map(|i| mean[i] - 0.5 * (v[i] + v1[i]))
            .collect();
        error_norm(&defect, v.as_slice(), v1.as_slice(), self.rtol, self.atol)
    }
}

/// Integrates with fixed step `h`, reporting the state (positions, velocities) at each output:
/// the steps of a [`VariationalMarch`] to `t_end`.
#[cfg(lsdc_internals)]
pub fn integrate<'m>(
    system: &mut MechanicalSystem<'m>,
    t0: f64,
    y0: &[f64],
    t_end: f64,
    steps: FixedStep,
    outputs: &[f64],
    observer: &mut RunObserver<'_, 'm>,
) -> Result<(Vec<f64>, Stats), IntegrationError> {
    let mut march = VariationalMarch::new(system, t0, y0, steps, outputs.to_vec())?;
    while march.time() < t_end {
        march.step(system, t_end, observer)?;
    }
    Ok((march.state(), march.stats.clone()))
}

/// The steps of a grid from `t0` to `t_end`, evenly spaced, and how many were taken.
#[derive(Clone, Copy, Debug)]
struct Grid {
    t0: f64,
    t_end: f64,
    count: usize,
    taken: usize,
}

/// The variational integration between two steps: the state (positions, velocities, and the
/// momentum the next step starts from), the grid of its steps, the outputs not passed yet.
pub struct VariationalMarch {
    configuration: Configuration,
    steps: FixedStep,
    t: f64,
    q: DVector<f64>,
    v: DVector<f64>,
    p: DVector<f64>,
    /// The grid to the end of the last step's call (made again for another end).
    grid: Option<Grid>,
    outputs: Vec<f64>,
    next_output: usize,
    pub stats: Stats,
}

impl VariationalMarch {
    /// The integration of `system` from (t0, y0), its outputs at `outputs` (sorted).
    pub fn new(
        system: &mut MechanicalSystem<'_>,
        t0: f64,
        y0: &[f64],
        steps: FixedStep,
        outputs: Vec<f64>,
    ) -> Result<VariationalMarch, IntegrationError> {
        let model = system.model;
        let positions = model.positions();
        let (q, v) = (
            DVector::from_column_slice(&y0[..positions]),
            DVector::from_column_slice(&y0[positions..]),
        );
        let mass = system
            .mass(q.as_slice())
            .map_err(|m| failure(t0, Failure::System(m.to_string()), &Stats::default()))?;
        Ok(VariationalMarch {
            configuration: Configuration::of(model),
            steps,
            t: t0,
            p: &mass * &v,
            q,
            v,
            grid: None,
            outputs,
            next_output: 0,
            stats: Stats::default(),
        })
    }

    pub fn time(&self) -> f64 {
        self.t
    }

    /// The state at the current point (positions, velocities).
    pub fn state(&self) -> Vec<f64> {
        let mut y = self.q.as_slice().to_vec();
        y.extend_from_slice(self.v.as_slice());
        y
    }

    /// Delivers the outputs up to the current time at the current state (those at the start).
    fn deliver_start<'m>(
        &mut self,
        system: &mut MechanicalSystem<'m>,
        observer: &mut RunObserver<'_, 'm>,
    ) -> Result<(), IntegrationError> {
        while let Some(&time) = self.outputs.get(self.next_output).filter(|&&t| t <= self.t) {
            let observed = observer(system, self.t, &self.state());
            observed.map_err(|m| failure(time, Failure::Observer(m.to_string()), &self.stats))?;
            self.next_output += 1;
        }
        Ok(())
    }

    /// One step of the grid from the current point to `t_end` (evenly spaced, the last landing
    /// on `t_end`), delivering the outputs it passes (the first step, those at the start too).
    pub fn step<'m>(
        &mut self,
        system: &mut MechanicalSystem<'m>,
        t_end: f64,
        observer: &mut RunObserver<'_, 'm>,
    ) -> Result<(), IntegrationError> {
        self.deliver_start(system, observer)?;
        let (t, h) = (self.t, self.steps.step);
        let not_converged = |time: f64, step: f64, detail: Option<String>, stats: &Stats| {
            let error = NotConverged { time, step, detail };
            failure(time, Failure::System(error.to_string()), stats)
        };
        if let Some(value) = self.steps.interrupt.as_ref().and_then(Interrupt::requested) {
            return Err(failure(t, Failure::Interrupted(value), &self.stats));
        }
        if self.stats.steps >= self.steps.max_steps {
            return Err(failure(t, Failure::TooManySteps, &self.stats));
        }
        let grid = match self.grid {
            Some(grid) if grid.t_end == t_end => grid,
            _ => Grid {
                t0: t,
                t_end,
                count: step_count(t, t_end, h),
                taken: 0,
            },
        };
        // The last step ends exactly at t_end: t + (t_end − t) may round below it, and the
        // output there would be lost.
        let k = grid.taken;
        let t_next = match k + 1 == grid.count {
            true => t_end,
            false => grid.t0 + (t_end - grid.t0) * (k + 1) as f64 / grid.count as f64,
        };
        let step = t_next - t;
        let (configuration, q, v) = (&self.configuration, &self.q, &self.v);
        let start = system
            .allowed_motions(q.as_slice())
            .map_err(|m| failure(t, Failure::System(m.to_string()), &self.stats))?;
        let basis = start.as_ref().map_or(Basis::Free, |start| start.basis);
        let mut end = configuration.first_guess(q, v, step);
        let mut converged = false;
        let mut previous = f64::INFINITY;
        let (mut mass_mid, mut terms) = (DMatrix::zeros(0, 0), DVector::zeros(0));
        for _ in 0..MAX_ITERATIONS {
            let mid = configuration.midpoint(q, &end);
            let mean = configuration.mean_velocity(q, &end, step);
            // An iterate the equations cannot be evaluated at (loops singular there, efforts
            // not finite) is the iteration failing, not the mechanism: the step is too long.
            (mass_mid, terms) = system
                .midpoint_terms(mid.as_slice(), mean.as_slice(), t + 0.5 * step)
                .map_err(|m| not_converged(t, step, Some(m.to_string()), &self.stats))?;
            self.stats.rhs_evaluations += 1;
            let mass_mean = &mass_mid * &mean;
            let mut momentum = &mass_mean - &terms * (0.5 * step) - &self.p;
            configuration.start_balance(&end, (&mass_mean, &terms), &self.p, step, &mut momentum);
            // Newton with the leading part of the Jacobian, M/h (scaled by h): converges quickly
            // for small h.
            let (correction, open) = system
                .correction(
                    &mass_mid,
                    &start,
                    end.positions.as_slice(),
                    &(-momentum * step),
                )
                .map_err(|m| not_converged(t, step, Some(m.to_string()), &self.stats))?;
            configuration.correct(q, &mut end, &correction);
            if end.positions.iter().any(|x| !x.is_finite()) {
                // Diverged: reported below, rather than iterated on.
                break;
            }
            let (size, scale) = (correction.amax(), 1.0 + end.positions.amax());
            let stalled = size <= ROUND_OFF * scale && size >= 0.5 * previous;
            if size <= CONVERGED * scale || stalled {
                converged = open <= LEFT_OPEN;
                break;
            }
            previous = size;
        }
        if end.positions.iter().any(|x| !x.is_finite()) {
            let detail = Some("its iterates diverged".to_string());
            return Err(not_converged(t, step, detail, &self.stats));
        }
        if !converged {
            return Err(not_converged(t, step, None, &self.stats));
        }
        let mean = configuration.mean_velocity(q, &end, step);
        let mass_mean = &mass_mid * &mean;
        let mut p_end = &mass_mean + &terms * (0.5 * step);
        configuration.end_momentum(&end, (&mass_mean, &terms), step, &mut p_end);
        let (v1, mass_end) = system
            .end_velocity(end.positions.as_slice(), &p_end, basis)
            .map_err(|m| failure(t_next, Failure::System(m.to_string()), &self.stats))?;
        let p = &mass_end * &v1;
        let defect = self.steps.defect_norm(&mean, v, &v1);
        StepError::keep_largest(&mut self.stats.largest_step_error, defect, t_next);
        self.stats.steps += 1;
        let mut end_state = end.positions.as_slice().to_vec();
        end_state.extend_from_slice(v1.as_slice());
        // Only recorded: projecting would spoil the symplectic map.
        system
            .measure_loops(t_next, &end_state)
            .map_err(|m| failure(t_next, Failure::System(m.to_string()), &self.stats))?;
        system
            .follow_reference(t_next, &end_state)
            .map_err(|m| failure(t_next, Failure::System(m.to_string()), &self.stats))?;
        while let Some(&time) = self.outputs.get(self.next_output).filter(|&&o| o <= t_next) {
            let s = (time - t) / step;
            let y = configuration.interpolate((q, v), (&end, &v1), s, step);
            let observed = observer(system, time, &y);
            observed.map_err(|m| failure(time, Failure::Observer(m.to_string()), &self.stats))?;
            self.next_output += 1;
        }
        (self.q, self.v, self.p, self.t) = (end.positions, v1, p, t_next);
        self.grid = Some(Grid {
            taken: k + 1,
            ..grid
        });
        Ok(())
    }
}

/// A failure of the integration at `time`, with the work done so far.
fn failure(time: f64, failure: Failure, stats: &Stats) -> IntegrationError {
    IntegrationError {
        time,
        failure,
        stats: Box::new(stats.clone()),
    }
}

/// The implicit equations of the step from `time` did not converge within the iterations
/// allowed: a smaller step makes them closer to linear.
#[derive(Debug)]
pub struct NotConverged {
    pub time: f64,
    pub step: f64,
    /// How the iteration failed, where it did before its iterations ran out.
    pub detail: Option<String>,
}

impl fmt::Display for NotConverged {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the implicit equations of the step from t = {} did not converge",
            self.time
        )?;
        if let Some(detail) = &self.detail {
            write!(f, " ({detail})")?;
        }
        write!(f, ": use a smaller `step` than {}", self.step)
    }
}

impl std::error::Error for NotConverged {}

/// Steps of equal size at most h from t0 to t_end, their ends computed from their number rather
/// than accumulated: never a sliver of a last step, whose mean velocity (q1 − q)/step would be
/// round-off divided by almost nothing.
fn step_count(t0: f64, t_end: f64, h: f64) -> usize {
    ((t_end - t0) / h * (1.0 - 1e-12)).ceil().max(1.0) as usize
}
