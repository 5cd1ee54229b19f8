//! The generator's state while the equations are written: the mechanism, the expression pool,
//! each body's motion and mass properties, and the walks along the links' steps that every part of
//! the generation (inertia, loads, closure, forward dynamics) shares.

use super::expr::{ExprId, Pool};
use super::inertia::{Inertia, PerBody};
use super::kinematics::{Derivatives, LinkCoordinates, Moving, Step};
use super::lower::{LowerError, Lowering};
use super::quaternion_joints::{self, BallKind, QuaternionJoins};
use super::vector::{self as v, Mat3, Vec3};
use crate::elab::mechanism::Mechanism;
use crate::elab::value::{Displacement, Elementary, JoinId};
use crate::source::Span;
use crate::topology::Topology;

pub(super) struct Generator<'a> {
    pub(super) mechanism: &'a Mechanism,
    pub(super) topology: &'a Topology,
    pub(super) pool: Pool,
    pub(super) lowering: Lowering<'a>,
    pub(super) derivatives: Derivatives,
    /// Indexed by body number, 0 = earth.
    pub(super) bodies: Vec<Moving>,
    pub(super) inertias: Vec<Option<Inertia>>,
    /// The same in each body's own axes.
    pub(super) local_inertias: Vec<Option<Inertia>>,
    /// Per body, the steps from its parent's frame to its own (empty for earth).
    pub(super) link_steps: Vec<Vec<Step>>,
    /// Per body, the body its motion is computed with: itself, or for a body welded to its
    /// parent, the anchor of the parent (0 for a body welded to earth). See `inertia`.
    pub(super) anchors: Vec<usize>,
    /// The declaration being written, to locate an error.
    pub(super) context: Option<Span>,
}

impl<'a> Generator<'a> {
    pub(super) fn new(mechanism: &'a Mechanism, topology: &'a Topology) -> Generator<'a> {
        Generator::in_state(mechanism, topology, QuaternionJoins::new())
    }

    /// The generator of equations whose variables are the simulator's state for the joins of
    /// `quaternion_joins` (`quaternion_joints`), the declared coordinates for the others.
    pub(super) fn in_state(
        mechanism: &'a Mechanism,
        topology: &'a Topology,
        quaternion_joins: QuaternionJoins,
    ) -> Generator<'a> {
        let mut pool = Pool::new();
        let lowering = Lowering::in_state(&mut pool, mechanism, topology, quaternion_joins);
        Generator {
            mechanism,
            topology,
            pool,
            lowering,
            derivatives: Derivatives::default(),
            bodies: Vec::new(),
            inertias: Vec::new(),
            local_inertias: Vec::new(),
            link_steps: Vec::new(),
            anchors: Vec::new(),
            context: None,
        }
    }

    /// The number of rates: the columns of Ψ.
    pub(super) fn columns(&self) -> usize {
        self.lowering.variables.rates.len()
    }

    /// The number of the tree's rates (the columns before the complementary links' own).
    pub(super) fn tree_coordinates(&self) -> usize {
        self.topology
            .principal
            .iter()
            .map(|l| self.lowering.join_variables(l.join).rates)
            .sum()
    }

    /// The coordinates of a join, with their columns.
    pub(super) fn link_coordinates(&mut self, join: JoinId) -> LinkCoordinates {
        let at = self.lowering.join_variables(join);
        let variables = &self.lowering.variables;
        let symbols =
            |list: &[super::lower::Variable], start: usize, count: usize| -> Vec<ExprId> {
                list[start..start + count]
                    .iter()
                    .map(|p| p.symbol)
                    .collect()
            };
        let positions = symbols(&variables.positions, at.position, at.positions);
        let rates = symbols(&variables.rates, at.rate, at.rates);
        let position_rates = match self.lowering.ball(join) {
            None => rates.clone(),
            Some(kind) => ball_position_rates(&mut self.pool, kind, &positions, &rates),
        };
        LinkCoordinates {
            positions,
            rates,
            columns: (at.rate..at.rate + at.rates).collect(),
            position_rates,
        }
    }

    /// The steps of a displacement; `link` is the join whose coordinates they may use.
    pub(super) fn steps(
        &mut self,
        d: &Displacement,
        link: Option<JoinId>,
    ) -> Result<Vec<Step>, LowerError> {
        d.0.iter()
            .map(|step| match step {
                Elementary::Translation(t) => Ok(Step::Translation(self.lowering.vector(
                    &mut self.pool,
                    t,
                    link,
                )?)),
                Elementary::Rotation { angle, axis } => {
                    let axis = self.lowering.vector(&mut self.pool, axis, None)?;
                    let axis = unit(&mut self.pool, &axis)?;
                    Ok(Step::Rotation {
                        axis,
                        angle: self.lowering.scalar(&mut self.pool, angle, link)?,
                    })
                }
            })
            .collect()
    }

    pub(super) fn inverse_steps(&mut self, d: &Displacement) -> Result<Vec<Step>, LowerError> {
        let steps = self.steps(d, None)?;
        Ok(steps
            .iter()
            .rev()
            .map(|s| s.inverse(&mut self.pool))
            .collect())
    }

    /// The link's dof chain, in order; for a join in the simulator's state, its ball's motion.
    pub(super) fn chain(&mut self, join: JoinId) -> Result<Vec<Step>, LowerError> {
        if let Some(kind) = self.lowering.ball(join) {
            let at = self.lowering.join_variables(join);
            let positions = &self.lowering.variables.positions[at.position..];
            let symbol = |k: usize| positions[k].symbol;
            let q = kind.quaternion_offset();
            let translation = (kind == BallKind::Free).then(|| [symbol(0), symbol(1), symbol(2)]);
            return Ok(vec![Step::Ball {
                translation,
                quaternion: [symbol(q), symbol(q + 1), symbol(q + 2), symbol(q + 3)],
            }]);
        }
        let link = self.mechanism.link(self.mechanism.join(join).link);
        let chain = Displacement(link.dofs.iter().flat_map(|d| d.0.iter().cloned()).collect());
        self.steps(&chain, Some(join))
    }

    pub(super) fn walk(&mut self, frame: &mut Moving, steps: &[Step], link: &LinkCoordinates) {
        for step in steps {
            frame.walk(&mut self.pool, &mut self.derivatives, step, link);
        }
    }

    /// Every body's frame, parent first.
    pub(super) fn place_bodies(&mut self) -> Result<(), LowerError> {
        let columns = self.columns();
        let fixed = Moving::fixed(&mut self.pool, columns);
        self.bodies = vec![fixed];
        self.link_steps = vec![Vec::new()];
        for link in &self.topology.principal {
            let join = self.mechanism.join(link.join);
            self.context = Some(join.span);
            let (on_parent, on_child) = if link.first_on_parent {
                (&join.first, &join.second)
            } else {
                (&join.second, &join.first)
            };
            let to_joint = self.steps(&on_parent.displacement, None)?;
            let mut chain = self.chain(link.join)?;
            // A ball's quaternion is the child's motion M already, whichever side the join's
            // first frame is on (`dynamics::joint`).
            if !link.first_on_parent && self.lowering.ball(link.join).is_none() {
                chain = chain
                    .iter()
                    .rev()
                    .map(|s| s.inverse(&mut self.pool))
                    .collect();
            }
            let to_body = self.inverse_steps(&on_child.displacement)?;
            let coordinates = self.link_coordinates(link.join);
            let mut frame = self.bodies[link.parent].clone();
            self.walk(&mut frame, &to_joint, &LinkCoordinates::default());
            self.walk(&mut frame, &chain, &coordinates);
            self.walk(&mut frame, &to_body, &LinkCoordinates::default());
            self.bodies.push(frame);
            self.link_steps.push([to_joint, chain, to_body].concat());
        }
        Ok(())
    }

    /// Rotation and translation of a constant displacement.
    pub(super) fn pose(&mut self, d: &Displacement) -> Result<(Mat3, Vec3), LowerError> {
        let steps = self.steps(d, None)?;
        Ok(self.compose(&steps))
    }

    /// Rotation and translation of steps that depend on no coordinate.
    pub(super) fn compose(&mut self, steps: &[Step]) -> (Mat3, Vec3) {
        let mut rotation = v::identity(&mut self.pool);
        let mut origin = v::zero(&mut self.pool);
        for step in steps {
            match step {
                Step::Translation(t) => {
                    let moved = v::mat_vec(&mut self.pool, &rotation, t);
                    origin = v::add(&mut self.pool, &origin, &moved);
                }
                Step::Rotation { axis, angle } => {
                    let turn = v::rotation(&mut self.pool, axis, *angle);
                    rotation = v::mat_mul(&mut self.pool, &rotation, &turn);
                }
                Step::Ball {
                    translation,
                    quaternion,
                } => {
                    if let Some(t) = translation {
                        let moved = v::mat_vec(&mut self.pool, &rotation, t);
                        origin = v::add(&mut self.pool, &origin, &moved);
                    }
                    let turn = quaternion_joints::rotation(&mut self.pool, quaternion);
                    rotation = v::mat_mul(&mut self.pool, &rotation, &turn);
                }
            }
        }
        (rotation, origin)
    }

    /// The body that owns each tree column, and its parent.
    pub(super) fn owner(&self, column: usize) -> usize {
        for link in &self.topology.principal {
            if self.own_columns_of(link.join).contains(&column) {
                return link.child;
            }
        }
        0
    }

    pub(super) fn own_columns(&self, b: usize) -> std::ops::Range<usize> {
        self.own_columns_of(self.topology.principal[b - 1].join)
    }

    /// The columns of a join's rates.
    fn own_columns_of(&self, join: JoinId) -> std::ops::Range<usize> {
        let at = self.lowering.join_variables(join);
        at.rate..at.rate + at.rates
    }

    /// Each body's anchor: itself when its link has coordinates, its parent's anchor when it is
    /// welded (0, earth, for a body welded to earth).
    pub(super) fn anchors(&self) -> Vec<usize> {
        let mut anchors = vec![0];
        for link in &self.topology.principal {
            let moves = !self
                .mechanism
                .link(self.mechanism.join(link.join).link)
                .coordinates
                .is_empty();
            anchors.push(if moves {
                link.child
            } else {
                anchors[link.parent]
            });
        }
        anchors
    }

    /// Per body, its mass properties and those of the bodies welded to it at its origin, in its
    /// own axes and in the fixed axes; `None` for bodies without mass and for welded bodies.
    pub(super) fn merged_inertias(&mut self) -> Result<(PerBody, PerBody), LowerError> {
        let n = self.topology.body_count();
        let mut local: Vec<Option<Inertia>> = vec![None; n + 1];
        for (b, slot) in local.iter_mut().enumerate().skip(1) {
            *slot = self.local_inertia(b)?;
        }
        // Children after parents: carry welded bodies' inertias up to their anchors, in the
        // frames of the bodies on the way.
        for b in (1..=n).rev() {
            let anchor = self.anchors[b];
            let Some(inertia) = local[b].filter(|_| anchor != b) else {
                continue;
            };
            local[b] = None;
            let parent = self.topology.parent(b);
            if anchor == 0 {
                continue; // Welded to earth: it never moves.
            }
            let steps = self.link_steps[b].clone();
            let (rotation, origin) = self.compose(&steps);
            let moved = inertia.moved(&mut self.pool, &rotation, &origin);
            local[parent] = Some(match local[parent] {
                Some(existing) => existing.plus(&mut self.pool, &moved),
                None => moved,
            });
        }
        let world = (0..=n)
            .map(|b| {
                local[b].map(|inertia| {
                    let zero = v::zero(&mut self.pool);
                    inertia.moved(&mut self.pool, &self.bodies[b].rotation, &zero)
                })
            })
            .collect();
        Ok((local, world))
    }

    /// Body `b`'s mass properties about its origin, in its own axes (numbers when the program
    /// gives numbers); `None` for a body declared without mass or inertia.
    pub(super) fn local_inertia(&mut self, b: usize) -> Result<Option<Inertia>, LowerError> {
        let body = self.mechanism.body(self.topology.bodies[b - 1]);
        self.context = Some(body.span);
        let mass = self
            .lowering
            .scalar(&mut self.pool, body.mass.value(), None)?;
        let moments = self
            .lowering
            .vector(&mut self.pool, body.inertia.value(), None)?;
        if self.pool.is_zero(mass) && v::is_zero(&self.pool, &moments) {
            return Ok(None);
        }
        let (principal, centre) = self.pose(body.iframe.value())?;
        let pool = &mut self.pool;
        let zero = pool.constant(0.0);
        let mut diagonal = [[zero; 3]; 3];
        for k in 0..3 {
            diagonal[k][k] = moments[k];
        }
        let central = Inertia {
            mass,
            first_moment: v::zero(pool),
            at_origin: diagonal,
        };
        Ok(Some(central.moved(pool, &principal, &centre)))
    }
}

/// The time derivatives of a ball's positions from its rates (`quaternion_joints`): ṗ = R(Q) v_b
/// for a free joint's translation, Q̇ = ½ Q ⊗ (0, ω_b).
fn ball_position_rates(
    pool: &mut Pool,
    kind: BallKind,
    positions: &[ExprId],
    rates: &[ExprId],
) -> Vec<ExprId> {
    let q = kind.quaternion_offset();
    let quaternion = [
        positions[q],
        positions[q + 1],
        positions[q + 2],
        positions[q + 3],
    ];
    let turn =
        quaternion_joints::quaternion_rate(pool, &quaternion, &[rates[0], rates[1], rates[2]]);
    match kind {
        BallKind::Spherical => turn.to_vec(),
        BallKind::Free => {
            let rotation = quaternion_joints::rotation(pool, &quaternion);
            let translation = v::mat_vec(pool, &rotation, &[rates[3], rates[4], rates[5]]);
            translation.into_iter().chain(turn).collect()
        }
    }
}

/// The unit vector along `axis`: normalised now when it is a number, symbolically otherwise.
fn unit(pool: &mut Pool, axis: &Vec3) -> Result<Vec3, LowerError> {
    let values: Option<Vec<f64>> = axis.iter().map(|&a| pool.as_constant(a)).collect();
    match values {
        Some(x) => {
            let norm = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            if norm == 0.0 || !norm.is_finite() {
                return Err(LowerError("a rotation has a zero axis".to_string()));
            }
            Ok(v::constant(pool, [x[0] / norm, x[1] / norm, x[2] / norm]))
        }
        None => {
            let squared = v::dot(pool, axis, axis);
            let norm = pool.sqrt(squared);
            Ok(axis.map(|a| pool.div(a, norm)))
        }
    }
}
