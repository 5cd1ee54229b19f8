//! What a run sees of its loops: the redundant constraints at the start, the residuals before
//! and after each projection, and the passages through singular configurations (where the
//! constraints lose rank), for the run report.

use serde::Serialize;

use crate::dynamics::algorithms::{forward_kinematics, Data};
use crate::dynamics::loops::{
    self, ConstraintJacobian, Extent, Factored, MomentumBasis, Orientation, ProjectionScratch,
    Residuals, RowChoice, Stabilisation, Structure, StructureError, ROW_NAMES,
};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;

/// Below this conditioning of the kept rows (`Factored::conditioning`: their smallest pivot over
/// the largest), the loops are near a singular configuration: constraint forces and
/// accelerations are amplified by more than its inverse. The run goes on; the report says when.
const NEAR_SINGULAR: f64 = 1e-3;

/// A projection leaving a kept row above this (dimensionless: radians, or metres per metre of
/// the mechanism's length) stops the run: the loops came open, and going on would be a wrong
/// answer.
const OPEN: f64 = 1e-6;

/// Below this conditioning the projection is skipped (see `LoopMonitor::keep`).
const SKIP_PROJECTION: f64 = 1e-6;

/// Below this fraction of how well they reproduced the rows left out when chosen
/// (`Structure::chosen_reproduction`), the kept rows are chosen again, if better ones exist.
const RECHOOSE_BELOW: f64 = 0.8;

/// Below this conditioning (on the dimensionless rows, not relative to the start's), the kept
/// rows are about to lose their independence: the run enters a singular passage, an event between steps. The rows losing it
/// are set aside (the smallest pivots first, until the others are conditioned above
/// `PASSAGE_LEFT`), so that the motion in the passage is that of a mechanism with those few
/// constraints released for a few microseconds, instead of one whose constraint forces along
/// the direction being lost grow as the inverse of the distance to the singularity and whose
/// smallest velocity error off the branch (the residual of that row over its vanishing
/// independence) grows with them until the run leaves its branch. Once the rows are independent
/// again (`PASSAGE_LEFT`), they are restored, and the projection brings the state back onto all
/// of them: the nearest closed state is then on the branch the motion was on, the other branch
/// being many times further than what the released constraints let the state drift.
const PASSAGE_ENTERED: f64 = 1e-5;
const PASSAGE_LEFT: f64 = 2e-5;

/// An adaptive step in a passage ending with the rows set aside conditioned above this is taken
/// again to end halfway (`LoopMonitor::leaving`).
const PASSAGE_LEFT_BY: f64 = 1.5 * PASSAGE_LEFT;

/// At or above this conditioning a state kept around a passage ends the stretch whose outputs
/// are interpolated between its ends (see `LoopFindings`). Nearer the passage the step ends' own
/// velocities drift across the rows about to be lost (on a row of two parallelograms with the
/// implicit integrator at 1e-8, by 3e-7 rad/s between the cranks at 1e-5). With each loop's
/// rows scaled by its own length (`structure::loop_lengths`) the conditioning no longer carries
/// the 1/N of one length for the whole mechanism (the ladder of N loops: 0.195 at every N,
/// against 1.95e-4 at N = 1,000), and 3e-5, chosen on that scaling, ended stretches too near
/// the passage. Measured
/// through the first flat passage (largest spread of the cranks' rates over the outputs; the
/// stretch's span): the row of ten, rk4 at 2e-4, 2.7e-6 at 3e-5, 8.1e-8 at 1e-4, 5.7e-8 at 3e-4
/// (0.6 ms) and at 1e-3 (1.2 ms); the row of two, rk4 at 1e-3, 2.5e-7, 2.4e-9, 6.7e-10, 6.7e-10;
/// the row of 40, rk4 at 1e-3 over 1.5 s, 7.5e-6, 1.2e-6, 5.0e-7, 5.0e-7 (spans at most 2 ms).
/// 3e-4 is the smallest value at the floor in each; 1e-3 doubles the spans at 2e-4 for nothing
/// (BENCHMARKS.md, "The ladder of 1,000 loops closed to round-off").
const STRETCH_ENDS: f64 = 3e-4;

/// A step that crossed a singular configuration of the loops between its ends
/// (`Orientation`: the sign of its rows' determinant against the last state kept changed), the
/// conditioning at both ends perhaps well above `PASSAGE_ENTERED`, is taken again to end this
/// fraction of the way to where it crossed (the measure taken as linear along the step): the
/// steps then come nearer it by halves, each ending short of it, until one ends within
/// `PASSAGE_ENTERED`, where the passage is set aside as at any step's end. A step whose stages
/// fall on the singular configuration itself is never accepted: on the row of one
/// parallelogram with `rk4` at 1 ms, the step across its twelfth flat configuration, with no
/// end within a conditioning of 1e-3, changed the energy by 1.57e-4 J in planar form and
/// 1.05e-6 J in spatial form, the two forms' round-off amplified. Ending the steps at once
/// where the conditioning is half `PASSAGE_ENTERED`, and those with rows set aside at twice
/// `PASSAGE_LEFT` past it, was measured and not kept: the row of one drifted by 2.8e-7 to
/// 9.5e-7 over the runs of `tests/suite/singular_passages.rs` against 2.2e-7 to 3.4e-7 so.
const APPROACH: f64 = 0.5;

/// Below this fraction of how well they parametrised the allowed motions when chosen
/// (`Structure::free_quality`), the free coordinates are chosen again.
const FREE_AGAIN_BELOW: f64 = 0.1;

/// Before the start, the structure of a mechanism without loops.
const NO_STRUCTURE: Structure = Structure {
    choice: RowChoice::NONE,
    length: 1.0,
    lengths: Vec::new(),
    redundant: Vec::new(),
    rank: 0,
    massless: 0,
    free: Vec::new(),
    idle: Vec::new(),
    tree_velocities: 0,
    free_quality: 1.0,
    chosen_reproduction: 1.0,
    active_rows: Vec::new(),
};

/// The state closest to a singular configuration the run saw.
#[derive(Clone, Debug, Serialize)]
pub struct ClosestApproach {
    pub time: f64,
    /// How far the kept rows are from dependent (`Factored::conditioning`, on dimensionless
    /// rows): 1 is far from any singularity, 0 is singular.
    pub ratio: f64,
    pub loop_name: String,
}

/// A stretch of time where the constraints lost rank.
#[derive(Clone, Debug, Serialize)]
pub struct SingularPassage {
    /// First and last accepted steps seen singular (`end` is None if the run ended there).
    pub start: f64,
    pub end: Option<f64>,
    /// The loop of the row losing its independence.
    pub loop_name: String,
    /// Smallest conditioning ratio seen.
    pub smallest_ratio: f64,
}

/// A stretch of the run around a passage where rows were set aside (see `PASSAGE_ENTERED`),
/// from the last state kept outside the passage well conditioned (`STRETCH_ENDS`) to the first
/// such state after it: the states (positions, then velocities) at its ends and their times.
/// `exit` is the latest state kept since the rows were restored, and `settled` says whether it
/// ends the stretch (None and false while the passage lasts).
#[derive(Clone, Debug)]
pub struct ReleasedStretch {
    pub entry: (f64, Vec<f64>),
    pub exit: Option<(f64, Vec<f64>)>,
    pub settled: bool,
}

/// What a run's monitors found of its loops, held once in the run (`RunState::loops`). First
/// the stretches it integrated with rows set aside, in time order, which the steps' monitor
/// records and the outputs' sampler reads: an output inside a stretch comes from an interpolant of the motion with rows released, off
/// the branch along the direction they no longer hold (on a row of 10 four-bars, an output at
/// a conditioning of 6.5e-7 had its cranks' rates apart by 4e-4 rad/s), and projecting it there
/// cannot find the branch again: the released drift of the positions along that direction is
/// below round-off in the rows' residual, yet turns the motions the rows allow by the drift
/// over the distance to the singular configuration. Such outputs are interpolated between the
/// stretch's ends instead (`sampler::Sampler`).
#[derive(Clone, Debug, Default)]
pub struct LoopFindings {
    pub released: Vec<ReleasedStretch>,
    /// What the steps saw, and what the outputs saw: kept apart because an output lies inside
    /// the step that reached it, earlier than the step's end, and a passage is followed in time
    /// order; the report takes both (`LoopRecord::merge`).
    pub steps: LoopRecord,
    pub outputs: LoopRecord,
}

impl LoopFindings {
    /// The record of the steps' monitor, or of the outputs' (`LoopMonitor::samples_outputs`).
    fn record(&mut self, outputs: bool) -> &mut LoopRecord {
        match outputs {
            true => &mut self.outputs,
            false => &mut self.steps,
        }
    }
}

/// What one monitor saw of the loops along a run: how often the kept rows were chosen again
/// (see `Structure::rechoose`), the largest residuals before and after each projection, the
/// singular passages and the closest approach to a singular configuration.
#[derive(Clone, Debug, Default)]
pub struct LoopRecord {
    rechosen: usize,
    before: Residuals,
    after: Residuals,
    singular: Vec<SingularPassage>,
    closest: Option<ClosestApproach>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ConstraintReport {
    pub stabilisation: String,
    /// Constraint rows (6 per complementary link) and their rank at the start.
    pub rows: usize,
    pub rank: usize,
    /// Rows implied by earlier ones at the start: `join: rotation about x`, …
    pub redundant: Vec<String>,
    /// How many times the independent rows the equations use were chosen again along the run.
    pub rows_rechosen: usize,
    /// Largest residuals reached by the integration before each projection (metres or radians,
    /// and their rates).
    pub position_residual_before_projection: f64,
    pub velocity_residual_before_projection: f64,
    /// Largest residuals of the states the run continued from and of every output.
    pub position_residual: f64,
    pub velocity_residual: f64,
    pub singular: Vec<SingularPassage>,
    pub closest: Option<ClosestApproach>,
    /// The times of the outputs inside a passage with rows set aside that the run ended in:
    /// they could not be interpolated between the passage's ends, and may be off the branch
    /// (W0903).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub outputs_off_branch: Vec<f64>,
}

/// How one evaluator keeps the loops closed along a run: the kept rows and free coordinates it
/// chose, its passages through singular configurations; what it sees goes to the run's
/// `LoopFindings`.
#[derive(Clone)]
pub struct LoopMonitor {
    pub stabilisation: Stabilisation,
    /// The decisions taken on the loops at the start (see `loops::Structure`).
    pub structure: Structure,
    /// Whether they were taken.
    started: bool,
    /// The complementary links' names, for the report.
    loop_names: Vec<String>,
    /// While the run passes a singular configuration: the rows kept before it (see `PASSAGE_ENTERED`).
    passage: Option<RowChoice>,
    /// Whether the rows set aside for a passage were just restored (the next projection then
    /// keeps the momentum along the allowed motions, `loops::project_momentum`).
    restored: bool,
    /// Whether this monitor keeps the outputs closed, which come from the integrator's
    /// interpolant inside a step. It never sets rows aside: an output is a state of the
    /// mechanism, on every row (outputs inside a stretch integrated with rows released are
    /// interpolated between its ends before they get here, see `LoopFindings`). Near a singular
    /// configuration the velocities are projected by the constraints' impulse, as at the end of
    /// a passage: the plain projection would turn an error across the rows into an energy
    /// error.
    pub samples_outputs: bool,
    /// A projection that could not close the loops: when, the row left open and by how much.
    pub opened: Option<(f64, usize, f64)>,
    /// The last state this monitor kept outside a passage (after its projection) and its time,
    /// and the last such state kept with a conditioning above `STRETCH_ENDS`: where a passage's
    /// stretch starts (see `ReleasedStretch`).
    last_kept: Option<(f64, Vec<f64>)>,
    anchor: Option<(f64, Vec<f64>)>,
    /// Whether the step control should forget the error's trend after the last `keep`: the
    /// equations off the closed set changed (rows or free coordinates chosen again, a passage
    /// entered or left), or the loops are near a singular configuration (`NEAR_SINGULAR`).
    /// There the error grows as the passage nears, and extrapolating that growth ends the steps
    /// right at the passage's threshold, where releasing the rows costs most energy: a row of
    /// two parallelograms at 1e-11 lost 7.8e-9 of its energy so, against 5.8e-11.
    pub breaks_trend: bool,
    /// The kept rows at the last state kept outside a passage, from which a step's end is seen
    /// on one side or the other of a singular configuration (`crossing`).
    orientation: Orientation,
    /// Whether the free coordinates are watched (`Structure::free_quality`): where the
    /// equations of motion work on them, the null-space method's allowed motions. The
    /// range-space method (`loops::range_space`) does not, and measuring them would cost what
    /// it spares (a factorisation of their block of the projector, cubic in the mobility).
    pub watches_free: bool,
}

fn max(a: Residuals, b: Residuals) -> Residuals {
    Residuals {
        position: a.position.max(b.position),
        velocity: a.velocity.max(b.velocity),
    }
}

impl LoopMonitor {
    pub fn new(stabilisation: Stabilisation) -> LoopMonitor {
        LoopMonitor {
            stabilisation,
            structure: NO_STRUCTURE,
            started: false,
            loop_names: Vec::new(),
            passage: None,
            restored: false,
            samples_outputs: false,
            opened: None,
            last_kept: None,
            anchor: None,
            breaks_trend: false,
            orientation: Orientation::default(),
            watches_free: true,
        }
    }

    /// Decides the loops' structure at the (closed) initial state and records its residuals.
    pub fn start(
        &mut self,
        model: &Model,
        data: &mut Data,
        (q, v): (&[f64], &[f64]),
        findings: &mut LoopFindings,
    ) -> Result<(), StructureError> {
        self.structure = Structure::decide(model, data, q)?;
        self.started = true;
        self.loop_names = model.loops.iter().map(|l| l.name.clone()).collect();
        let c = loops::constraints(model, data, q, v, Extent::Rows)?;
        let residuals = Residuals {
            position: c.residual.amax(),
            velocity: c.velocity.amax(),
        };
        let record = findings.record(self.samples_outputs);
        (record.before, record.after) = (residuals, residuals);
        self.watch_crossings(&c.jacobian);
        Ok(())
    }

    /// Whether a step's end is checked for a singular configuration crossed since the last
    /// state kept (`crossing`): by the run's monitor, outside a passage, when it projects.
    pub fn watches_crossings(&self) -> bool {
        !self.samples_outputs
            && self.passage.is_none()
            && self.stabilisation == Stabilisation::Projection
    }

    /// Takes the state kept, whose rows are `jacobian`, as where the next step starts: its
    /// kept rows become the reference of `crossing`, outside a passage.
    fn watch_crossings(&mut self, jacobian: &ConstraintJacobian) {
        match self.watches_crossings() {
            true => self.orientation.set(jacobian, &self.structure.choice),
            false => self.orientation.clear(),
        }
    }

    /// Where a step from the last state kept to the rows `jacobian` should end instead, as a
    /// fraction of it, when it crossed a singular configuration of the loops (`APPROACH`).
    pub fn crossing(&mut self, jacobian: &ConstraintJacobian) -> Option<f64> {
        if !self.watches_crossings() {
            return None;
        }
        let (end, _) = self.orientation.relative(jacobian)?;
        (end < 0.0).then(|| APPROACH / (1.0 - end))
    }

    /// Where an adaptive step in a passage ending at the rows `jacobian` should end instead, as a
    /// fraction of it: halfway while the rows set aside are conditioned above `PASSAGE_LEFT_BY`.
    pub fn leaving(&mut self, jacobian: &ConstraintJacobian) -> Option<f64> {
        let before = self.passage.as_ref().filter(|_| self.cuts_passage())?;
        let conditioning = Factored::new(jacobian, before).conditioning().0;
        (conditioning > PASSAGE_LEFT_BY).then_some(0.5)
    }

    /// Whether a step's end is checked for leaving a passage (`leaving`): by the run's monitor,
    /// in a passage, when it projects.
    pub fn cuts_passage(&self) -> bool {
        self.passage.is_some()
            && !self.samples_outputs
            && self.stabilisation == Stabilisation::Projection
    }

    /// A monitor for the outputs, from this one's structure as it stands
    /// (`samples_outputs`).
    pub fn for_outputs(&self) -> LoopMonitor {
        let mut monitor = self.clone();
        monitor.samples_outputs = true;
        monitor
    }

    /// Whether the structure was decided (`start`).
    pub fn started(&self) -> bool {
        self.started
    }

    /// Moves (q, v) onto the constraints when the stabilisation is by projection, and records the
    /// residuals and the rank there. Returns whether the state changed.
    ///
    /// At a singular configuration (conditioning below `SKIP_PROJECTION`) the projection is
    /// skipped: where two branches of the closed set cross, the nearest closed point may lie on
    /// the other branch, and projecting there would switch branches against the momentum. The
    /// accelerations keep the constraints to the integration's accuracy through the short
    /// passage, and projection resumes after it. Merely near one, it projects: a mechanism that
    /// only comes close (a Bricard linkage) would otherwise drift off its loops.
    pub fn keep(
        &mut self,
        model: &Model,
        data: &mut Data,
        time: f64,
        (q, v): (&mut [f64], &mut [f64]),
        scratch: &mut ProjectionScratch,
        findings: &mut LoopFindings,
    ) -> Result<bool, EvalError> {
        self.breaks_trend = false;
        forward_kinematics(model, data, q, v)?;
        scratch.constraints_here(model, data, q, v)?;
        let was_in_passage = self.passage.is_some();
        let conditioning = self.conditioning(scratch, findings.record(self.samples_outputs));
        self.record_entry(was_in_passage, time, (&*q, &*v), &mut findings.released);
        self.breaks_trend |= conditioning.0 < NEAR_SINGULAR;
        // An output is not projected where a step end would set rows aside: there the
        // interpolant's error along the direction being lost, invisible in the residual, would
        // turn the projected velocities off the branch (see `LoopFindings`).
        let projects = match self.samples_outputs {
            true => conditioning.0 >= PASSAGE_ENTERED,
            false => self.passage.is_some() || conditioning.0 >= SKIP_PROJECTION,
        };
        let moved = self.stabilisation == Stabilisation::Projection && projects;
        if moved {
            // Rows just restored after a passage, or a state near a singular configuration:
            // the velocities are projected from those the state arrived with, by the
            // constraints' impulse (`loops::project_momentum`), which changes the kinetic
            // energy only at second order in the correction. Near a singular configuration
            // the position step alone (on a residual at round-off, 4e-16) turns the rows
            // being lost by about that residual over their independence, and the velocities'
            // projection across the turned rows (orthogonal in the coordinates, not in the
            // mass matrix) changes the energy at first order: on the parallelogram at 1e-12,
            // one projection at a conditioning of 1.3e-5 took 8.4e-7 J of its 50 (the run's
            // whole drift of 9.4e-9), the integration's own steps changing it by 1e-14 each
            // (`singular_passages`).
            let restored = std::mem::take(&mut self.restored);
            let impulse = restored || conditioning.0 < NEAR_SINGULAR;
            let arriving = impulse.then(|| v.to_vec());
            let choice = &self.structure.choice;
            let mut projection = loops::project_from(model, data, choice, q, v, scratch)?;
            if let Some(arriving) = arriving {
                v.copy_from_slice(&arriving);
                // The outputs' velocities with the accurate basis; the run's own restores keep
                // the free coordinates' motions, which its equations use (the dense basis there
                // moved the row of two four-bars at 1e-12 from 3.6e-10 to 1.7e-9 of its
                // energy at its first passage).
                let basis = match self.samples_outputs {
                    true => MomentumBasis::Orthonormal,
                    false => MomentumBasis::Free,
                };
                let structure = &self.structure;
                loops::project_momentum(model, data, structure, (q, v), basis, scratch)?;
                // The velocities kept are the impulse's, not those the projection's own step
                // left (on the ladder of 1,000 loops 3e-17 against 1.1e-9, the damped step's
                // remainder along rows of conditioning 2e-4): their rows are the ones recorded.
                projection.after.velocity = scratch.velocity_residual(v);
            }
            if let (left, Some(row)) = projection.left {
                if left > OPEN && self.opened.is_none() {
                    self.opened = Some((time, row, left));
                }
            }
            findings.record(self.samples_outputs).observe(
                model,
                time,
                projection.before,
                projection.after,
                conditioning,
            );
        } else {
            let record = findings.record(self.samples_outputs);
            record.observe_current(model, time, conditioning, scratch);
        }
        let seated = !moved && loops::seat_ball_angles(model, data, q, v, false)?;
        self.record_kept(time, conditioning.0, (&*q, &*v), &mut findings.released);
        self.watch_crossings(&scratch.current.jacobian);
        Ok(moved || seated)
    }

    /// Starts a stretch around a passage where it sets rows aside (see `LoopFindings`).
    fn record_entry(
        &mut self,
        was_in_passage: bool,
        time: f64,
        (q, v): (&[f64], &[f64]),
        released: &mut Vec<ReleasedStretch>,
    ) {
        if was_in_passage || self.passage.is_none() {
            return;
        }
        if let Some(last) = released.last_mut().filter(|s| !s.settled) {
            // The stretch before never reached a well-conditioned state: it ends at the last
            // one kept.
            if let Some(kept) = &self.last_kept {
                last.exit = Some(kept.clone());
            }
            last.settled = true;
        }
        let entry = (self.anchor.take())
            .or_else(|| self.last_kept.take())
            .unwrap_or_else(|| (time, [q, v].concat()));
        released.push(ReleasedStretch {
            entry,
            exit: None,
            settled: false,
        });
    }

    /// Remembers a state kept outside a passage, and ends the stretch around the last passage
    /// at the first one well conditioned (see `LoopFindings`).
    fn record_kept(
        &mut self,
        time: f64,
        conditioning: f64,
        (q, v): (&[f64], &[f64]),
        released: &mut [ReleasedStretch],
    ) {
        if self.samples_outputs || self.passage.is_some() {
            return;
        }
        store(&mut self.last_kept, time, (q, v));
        let settles = conditioning >= STRETCH_ENDS;
        if let Some(last) = released.last_mut().filter(|s| !s.settled) {
            store(&mut last.exit, time, (q, v));
            last.settled = settles;
        }
        if settles {
            store(&mut self.anchor, time, (q, v));
        }
    }

    /// The conditioning of the kept rows (`Factored::conditioning`) at the constraint Jacobian
    /// G, after choosing them again if they are poorly conditioned and better ones exist, and
    /// the passages through singular configurations entered or left here (see `passage`).
    /// During a passage, the conditioning of all the rows chosen before it.
    fn conditioning(
        &mut self,
        scratch: &mut ProjectionScratch,
        record: &mut LoopRecord,
    ) -> (f64, Option<usize>) {
        let jacobian = &scratch.current.jacobian;
        if let Some(before) = &self.passage {
            let conditioning = Factored::new(jacobian, before).conditioning();
            if conditioning.0 >= PASSAGE_LEFT {
                self.structure.choice = self.passage.take().expect("in a passage");
                self.structure.choose_free(jacobian);
                self.restored = true;
                self.breaks_trend = true;
            }
            return conditioning;
        }
        let conditioning = scratch.conditioning(&self.structure.choice);
        let structure = &mut self.structure;
        let reproduction = scratch.reproduction(&structure.active_rows, &structure.lengths);
        let jacobian = &scratch.current.jacobian;
        if let Some(now) =
            reproduction.filter(|&now| now < RECHOOSE_BELOW * structure.chosen_reproduction)
        {
            if structure.rechoose(jacobian, now) {
                record.rechosen += 1;
                self.breaks_trend = true;
                structure.choose_free(jacobian);
                return Factored::new(jacobian, &structure.choice).conditioning();
            }
            // The rows kept are still the best: try again once they have fallen as far again.
            structure.chosen_reproduction = now;
        }
        if conditioning.0 < PASSAGE_ENTERED && !self.samples_outputs {
            let before = structure.choice.clone();
            structure.choice = without_lost_rows(jacobian, &before, PASSAGE_LEFT);
            structure.choose_free(jacobian);
            self.passage = Some(before);
            self.breaks_trend = true;
            return conditioning;
        }
        let quality = match self.watches_free {
            true => scratch.free_quality(&structure.free),
            false => None,
        };
        if quality.is_some_and(|q| q < FREE_AGAIN_BELOW * structure.free_quality) {
            structure.choose_free(&scratch.current.jacobian);
            self.breaks_trend = true;
        }
        conditioning
    }

    /// Records the residuals and the conditioning at (q, v) without moving it.
    pub fn measure(
        &mut self,
        model: &Model,
        data: &mut Data,
        time: f64,
        (q, v): (&[f64], &[f64]),
        scratch: &mut ProjectionScratch,
        findings: &mut LoopFindings,
    ) -> Result<(), EvalError> {
        forward_kinematics(model, data, q, v)?;
        scratch.constraints_at(model, data, q, v)?;
        let was_in_passage = self.passage.is_some();
        let conditioning = self.conditioning(scratch, findings.record(self.samples_outputs));
        self.record_entry(was_in_passage, time, (q, v), &mut findings.released);
        self.record_kept(time, conditioning.0, (q, v), &mut findings.released);
        let record = findings.record(self.samples_outputs);
        record.observe_current(model, time, conditioning, scratch);
        Ok(())
    }

    /// The report of the loops: the structure this monitor decided at the start, and what the
    /// run's monitors found (`findings`).
    pub fn report(&self, findings: &LoopFindings) -> ConstraintReport {
        let stabilisation = match self.stabilisation {
            Stabilisation::Projection => "projection".to_string(),
            Stabilisation::Baumgarte(rate) => format!("baumgarte ({rate} 1/s)"),
            Stabilisation::Integrator => {
                "the integrator's constraint equations (RATTLE)".to_string()
            }
            Stabilisation::None => "none".to_string(),
        };
        let structure = &self.structure;
        let seen = findings.steps.merge(&findings.outputs);
        ConstraintReport {
            stabilisation,
            rows: structure.active(),
            rank: structure.rank,
            redundant: structure
                .redundant
                .iter()
                .map(|&row| format!("{}: {}", self.loop_names[row / 6], ROW_NAMES[row % 6]))
                .collect(),
            rows_rechosen: seen.rechosen,
            position_residual_before_projection: seen.before.position,
            velocity_residual_before_projection: seen.before.velocity,
            position_residual: seen.after.position,
            velocity_residual: seen.after.velocity,
            singular: seen.singular,
            closest: seen.closest,
            outputs_off_branch: Vec::new(),
        }
    }
}

impl LoopRecord {
    /// Records the residuals of the constraints in `scratch.current` and the conditioning.
    fn observe_current(
        &mut self,
        model: &Model,
        time: f64,
        conditioning: (f64, Option<usize>),
        scratch: &ProjectionScratch,
    ) {
        let residuals = Residuals {
            position: scratch.current.residual.amax(),
            velocity: scratch.current.velocity.amax(),
        };
        self.observe(model, time, residuals, residuals, conditioning);
    }

    fn observe(
        &mut self,
        model: &Model,
        time: f64,
        before: Residuals,
        after: Residuals,
        (ratio, row): (f64, Option<usize>),
    ) {
        self.before = max(self.before, before);
        self.after = max(self.after, after);
        let Some(row) = row else { return };
        let loop_name = || model.loops[row / 6].name.clone();
        if self.closest.as_ref().is_none_or(|c| ratio < c.ratio) {
            self.closest = Some(ClosestApproach {
                time,
                ratio,
                loop_name: loop_name(),
            });
        }
        let open = self.singular.last_mut().filter(|p| p.end.is_none());
        match open {
            Some(passage) if ratio >= NEAR_SINGULAR => passage.end = Some(time),
            Some(passage) => passage.smallest_ratio = passage.smallest_ratio.min(ratio),
            None if ratio < NEAR_SINGULAR => {
                self.singular.push(SingularPassage {
                    start: time,
                    end: None,
                    loop_name: loop_name(),
                    smallest_ratio: ratio,
                });
            }
            None => {}
        }
    }

    /// What this record and `other` saw together (the steps' and the outputs', which may fall
    /// inside a long step): the larger residuals, the closer approach, the passages of either,
    /// overlapping ones joined.
    fn merge(&self, other: &LoopRecord) -> LoopRecord {
        let mut merged = self.clone();
        merged.rechosen = self.rechosen.max(other.rechosen);
        merged.before = max(self.before, other.before);
        merged.after = max(self.after, other.after);
        if let Some(theirs) = &other.closest {
            if merged
                .closest
                .as_ref()
                .is_none_or(|c| theirs.ratio < c.ratio)
            {
                merged.closest = Some(theirs.clone());
            }
        }
        let mut passages: Vec<SingularPassage> = merged
            .singular
            .drain(..)
            .chain(other.singular.iter().cloned())
            .collect();
        passages.sort_by(|a, b| a.start.total_cmp(&b.start));
        for passage in passages {
            match merged.singular.last_mut() {
                Some(last) if last.end.is_none_or(|end| passage.start <= end) => {
                    last.end = match (last.end, passage.end) {
                        (Some(a), Some(b)) => Some(a.max(b)),
                        _ => None,
                    };
                    last.smallest_ratio = last.smallest_ratio.min(passage.smallest_ratio);
                }
                _ => merged.singular.push(passage),
            }
        }
        merged
    }
}

/// Stores a state (positions, then velocities) and its time in `slot`, reusing its storage: a
/// step allocates nothing once the slots are sized.
fn store(slot: &mut Option<(f64, Vec<f64>)>, time: f64, (q, v): (&[f64], &[f64])) {
    let (at, state) = slot.get_or_insert_with(|| (time, Vec::with_capacity(q.len() + v.len())));
    *at = time;
    state.clear();
    state.extend_from_slice(q);
    state.extend_from_slice(v);
}

/// `choice` without the firm rows losing their independence at G: the row of the smallest pivot
/// is set aside until the others are conditioned above `above` (at least one row is kept).
fn without_lost_rows(jacobian: &ConstraintJacobian, choice: &RowChoice, above: f64) -> RowChoice {
    let mut kept = choice.clone();
    while kept.rows.len() > kept.weak + 1 {
        let (ratio, row) = Factored::new(jacobian, &kept).conditioning();
        let Some(row) = row.filter(|_| ratio < above) else {
            break;
        };
        let k = kept
            .rows
            .iter()
            .position(|&r| r == row)
            .expect("a kept row");
        kept.rows.remove(k);
        kept.scales.remove(k);
    }
    kept
}
