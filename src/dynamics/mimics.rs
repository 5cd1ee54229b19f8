//! Mimic joints (a link's `mimic`, `mimic_multiplier`, `mimic_offset`; URDF `<mimic>`): the
//! coordinate of a follower joint held to the coordinate of its leader, q_f = m q_l + o, a
//! holonomic constraint linear in the coordinates.
//!
//! On a tree the coupling is eliminated rather than enforced by multipliers: the velocities are
//! v = S u, with u the velocities of every joint but the followers and S the identity with each
//! follower's row m times its leader's, so the equations of motion reduce to
//! (Sᵀ M S) u̇ = Sᵀ (τ − b), exact and symmetric positive definite on a tree, and the
//! accelerations are S u̇: the response X = S (SᵀMS)⁻¹ Sᵀ (`response`), on which the contacts'
//! rows and the coordinates held at rest are solved. Where nothing else needs the mass matrix,
//! the same accelerations come from the articulated-body algorithm and the couplings' forces
//! on its articulated inertias (`coupled_aba`), the followers' set from their leaders'. The state keeps every coordinate, so outputs, energy and the
//! algorithms see the follower as any other joint; since the accelerations satisfy the coupling
//! exactly, q_f − m q_l − o is a linear invariant of the equations of motion, which every
//! Runge–Kutta and Rosenbrock method preserves: it stays at round-off over a run once the start
//! satisfies it ([`impose`]). With closed loops the couplings are rows solved together with
//! the loops' and the contacts' (`rows`), kept at the position level after each step.

use nalgebra::DMatrix;

use super::joint::Joint;
use crate::diag::Diagnostic;
use crate::elab::mechanism::{LinkMimic, Mechanism};
use crate::kinematics::eval::{eval, UnknownValues};
use crate::kinematics::model::JointModel;

/// One follower and its leader, in the model's numbering.
#[derive(Clone, Debug)]
pub struct Mimic {
    /// The follower's and the leader's joints (indices into `Model::joints`).
    pub joint: usize,
    pub leader_joint: usize,
    /// `finger.q`, the follower's coordinate as the outputs name it, and its leader's.
    pub coordinate: String,
    pub leader_coordinate: String,
    /// The follower's and the leader's indices among the state's positions and velocities.
    pub position: usize,
    pub velocity: usize,
    pub leader_position: usize,
    pub leader_velocity: usize,
    pub multiplier: f64,
    pub offset: f64,
}

impl Mimic {
    /// How far the positions `q` are from the coupling: q_f − (m q_l + o).
    pub fn violation(&self, q: &[f64]) -> f64 {
        q[self.position] - (self.multiplier * q[self.leader_position] + self.offset)
    }
}

/// Sets each follower's coordinate and rate from its leader's: the start of a run.
pub fn impose(mimics: &[Mimic], q: &mut [f64], v: &mut [f64]) {
    for mimic in mimics {
        q[mimic.position] = mimic.multiplier * q[mimic.leader_position] + mimic.offset;
        v[mimic.velocity] = mimic.multiplier * v[mimic.leader_velocity];
    }
}

/// Restores the couplings in a state y (positions first, `positions` of them) after the
/// coordinate and rate of the joint whose velocity index is `moved` were set: a follower's
/// leader follows it back (where the multiplier is not zero), then every follower its leader.
pub fn restore(mimics: &[Mimic], y: &mut [f64], positions: usize, moved: usize) {
    let (q, v) = y.split_at_mut(positions);
    let moved_follower = mimics.iter().find(|m| m.velocity == moved);
    if let Some(mimic) = moved_follower.filter(|m| m.multiplier != 0.0) {
        q[mimic.leader_position] = (q[mimic.position] - mimic.offset) / mimic.multiplier;
        v[mimic.leader_velocity] = v[mimic.velocity] / mimic.multiplier;
    }
    impose(mimics, q, v);
}

/// The basis S of the velocities the couplings allow (nv × (nv − followers)): one column per
/// velocity that is not a follower's, with the followers' rows filled from their leaders'.
pub fn basis(mimics: &[Mimic], nv: usize) -> DMatrix<f64> {
    let free: Vec<usize> = (0..nv)
        .filter(|&i| mimics.iter().all(|m| m.velocity != i))
        .collect();
    let mut s = DMatrix::zeros(nv, free.len());
    for (column, &i) in free.iter().enumerate() {
        s[(i, column)] = 1.0;
    }
    for mimic in mimics {
        let leader = s.row(mimic.leader_velocity).clone_owned();
        s.row_mut(mimic.velocity)
            .copy_from(&(leader * mimic.multiplier));
    }
    s
}

/// The couplings of the tree's links. Follower and leader must each have one coordinate
/// (E0470) and be a join of the tree, not one closing a loop (E0471); a leader that follows
/// another join, or the follower itself, is refused (E0472); the multiplier and offset must be
/// numbers (E0473).
pub fn build(
    mechanism: &Mechanism,
    joints: &[Joint],
    loops: &[JointModel],
    unknowns: &UnknownValues,
    errors: &mut Vec<Diagnostic>,
) -> Vec<Mimic> {
    let mut mimics = Vec::new();
    for joint in joints.iter() {
        let link = mechanism.link(mechanism.join(joint.chain.join).link);
        if link.mimic().is_declared() {
            let found = follower(mechanism, joint, joints, link.mimic(), unknowns);
            match found {
                Ok(mimic) => mimics.push(mimic),
                Err(error) => errors.push(error),
            }
        }
    }
    let loop_mimics = loops.iter().filter(|l| {
        mechanism
            .link(mechanism.join(l.join).link)
            .mimic()
            .is_declared()
    });
    for chain in loop_mimics {
        errors.push(refused(
            mechanism,
            format!("`{}` closes a loop and mimics another join", chain.name),
            chain.join,
            "a loop-closing join cannot follow another",
        ));
    }
    refuse_chains(mechanism, joints, &mimics, errors);
    mimics
}

fn refused(
    mechanism: &Mechanism,
    message: String,
    join: crate::elab::value::JoinId,
    label: &str,
) -> Diagnostic {
    Diagnostic::error("E0471", message)
        .primary(mechanism.join(join).span, label)
        .help("remove `mimic` from the link, or make the follower a join of the tree")
}

/// A leader that is itself a follower (a chain or cycle of mimics) is refused: E0472.
fn refuse_chains(
    mechanism: &Mechanism,
    joints: &[Joint],
    mimics: &[Mimic],
    errors: &mut Vec<Diagnostic>,
) {
    for mimic in mimics {
        if let Some(leader) = mimics.iter().find(|m| m.velocity == mimic.leader_velocity) {
            let joint = joints.iter().find(|j| j.v_offset == mimic.velocity);
            let span = joint.map(|j| mechanism.link(mechanism.join(j.chain.join).link).span);
            let mut error = Diagnostic::error(
                "E0472",
                format!(
                    "`{}` mimics `{}`, which itself mimics `{}`",
                    mimic.coordinate, mimic.leader_coordinate, leader.leader_coordinate
                ),
            )
            .help("make every mimic follow a join that is not a mimic (compose the multipliers)");
            if let Some(span) = span {
                error = error.primary(span, "a mimic of a mimic");
            }
            errors.push(error);
        }
    }
}

/// The coupling of `joint` to the leader its link names.
fn follower(
    mechanism: &Mechanism,
    joint: &Joint,
    joints: &[Joint],
    declared: &LinkMimic,
    unknowns: &UnknownValues,
) -> Result<Mimic, Diagnostic> {
    let link = mechanism.link(mechanism.join(joint.chain.join).link);
    let name = &joint.chain.name;
    let Some((leader_join, leader_span)) = declared.leader else {
        return Err(Diagnostic::error(
            "E0472",
            format!("`{name}` has a mimic multiplier or offset but no leader"),
        )
        .primary(
            link.span,
            "`mimic_multiplier` and `mimic_offset` need `mimic`",
        )
        .secondary(mechanism.join(joint.chain.join).span, "the join")
        .help("name the join to follow, e.g. `mimic = left`"));
    };
    let leader = joints.iter().find(|j| j.chain.join == leader_join);
    let single = |j: &Joint| j.is_single_coordinate();
    let leader = match leader {
        Some(leader) if leader.chain.join == joint.chain.join => {
            return Err(
                Diagnostic::error("E0472", format!("`{name}` mimics itself"))
                    .primary(leader_span, "the join being declared")
                    .help("name another join with one coordinate"),
            )
        }
        Some(leader) if single(joint) && single(leader) => leader,
        _ => {
            let leader_name = mechanism.join_name(leader_join);
            return Err(Diagnostic::error(
                "E0470",
                format!("`{name}` mimics `{leader_name}`, but a mimic couples two joins with one coordinate each"),
            )
            .primary(leader_span, "the leader")
            .help("couple revolute or prismatic joins of the tree (a loop-closing join cannot lead)"));
        }
    };
    let number = |value: &Option<crate::elab::value::Scalar>, default: f64| match value {
        None => Ok(default),
        Some(value) => match eval(value, unknowns) {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(Diagnostic::error(
                "E0473",
                format!("the mimic multiplier or offset of `{name}` is not a number"),
            )
            .primary(
                link.span,
                "`mimic_multiplier` and `mimic_offset` must be numbers",
            )
            .secondary(mechanism.join(joint.chain.join).span, "the join")
            .help("give the unknowns they use values (`--set`)")),
        },
    };
    Ok(Mimic {
        joint: index_of(joints, joint),
        leader_joint: index_of(joints, leader),
        coordinate: joint.coordinate_label(),
        leader_coordinate: leader.coordinate_label(),
        position: joint.q_offset,
        velocity: joint.v_offset,
        leader_position: leader.q_offset,
        leader_velocity: leader.v_offset,
        multiplier: number(&declared.multiplier, 1.0)?,
        offset: number(&declared.offset, 0.0)?,
    })
}

fn index_of(joints: &[Joint], joint: &Joint) -> usize {
    joints
        .iter()
        .position(|j| j.chain.join == joint.chain.join)
        .unwrap_or_default()
}
