//! What `lsdc tree` and `lsdc assemble` report: the numbering, the joints, the assembled
//! configuration and the mobility. Plain serialisable data; the command line only prints it.

use serde::Serialize;

use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::elab::value::BodyRef;
use crate::kinematics::assembly::AssemblyOptions;
use crate::kinematics::contacts::{contact_mobility, contact_models, ContactMobility};
use crate::kinematics::eval::UnknownValues;
use crate::kinematics::forward::forward;
use crate::kinematics::initial::assemble_initial;
use crate::kinematics::joint::{analyse, JointAnalysis};
use crate::kinematics::mobility::{mobility, Mobility};
use crate::kinematics::model::{self, KinematicModel};
use crate::kinematics::sphere_on_disc::sphere_contacts_on_discs;
use crate::kinematics::unknowns::{given_values, unknown_values, Override};
use crate::topology::{self, notation, Topology};

#[derive(Clone, Debug, Serialize)]
pub struct LinkReport {
    /// The link's number: j for the principal link of body j, n+1… for complementary links.
    pub number: usize,
    /// The join's name (`as crank`, or `joinK`).
    pub join: String,
    /// Body numbers of the first and second frames of the join (0 is earth).
    pub first_body: usize,
    pub second_body: usize,
    pub coordinates: Vec<String>,
    /// `None` when the joint cannot be analysed (a value is missing).
    pub joint: Option<JointAnalysis>,
}

#[derive(Clone, Debug, Serialize)]
pub struct BodyReport {
    pub number: usize,
    pub name: String,
    pub parent: usize,
    pub link: LinkReport,
}

#[derive(Clone, Debug, Serialize)]
pub struct TreeReport {
    pub bodies: Vec<BodyReport>,
    pub complementary: Vec<LinkReport>,
    /// The mobility at the assembled configuration (for a tree: the sum of link DOF).
    pub mobility: Option<Mobility>,
    /// Why the mobility could not be computed.
    pub mobility_unavailable: Option<String>,
    /// The degrees of freedom in position and in velocity the contacts leave, if there are any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contacts: Option<ContactMobility>,
    /// Whether the mechanism's joints move its bodies in one plane (`kinematics::plane`, decided
    /// without dynamics; a run's planar form also asks its efforts in the plane), and if not,
    /// why.
    pub planar: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_planar: Option<String>,
    /// The assembly's warnings (the branch it reached, given values it moved).
    #[serde(skip)]
    pub warnings: Vec<Diagnostic>,
    /// The scene numbered and what its model holds (`elab::scene`); absent without scenes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<crate::elab::scene_model::SceneModel>,
}

#[derive(Clone, Debug, Serialize)]
pub struct CoordinateValue {
    /// `join.coordinate`
    pub name: String,
    pub value: f64,
    /// Held at its `initial` value during assembly.
    pub fixed: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct AssemblyReport {
    /// Every joint coordinate, principal links first (by number), then complementary links.
    pub coordinates: Vec<CoordinateValue>,
    pub iterations: usize,
    /// Largest component of the closure residual at the solution.
    pub residual: f64,
    /// Given values no closed configuration holds, and what assembly made of them (W0801).
    pub moved: Vec<MovedValue>,
}

#[derive(Clone, Debug, Serialize)]
pub struct MovedValue {
    /// `join.coordinate`
    pub name: String,
    pub given: f64,
    pub assembled: f64,
}

fn link_report(
    mechanism: &Mechanism,
    topology: &Topology,
    join: crate::elab::value::JoinId,
    number: usize,
    unknowns: &UnknownValues,
) -> LinkReport {
    let j = mechanism.join(join);
    let joint = model::link_only(mechanism, join, unknowns)
        .ok()
        .and_then(|m| analyse(&m).ok());
    LinkReport {
        number,
        join: mechanism.join_name(join),
        first_body: topology.number(j.first.body),
        second_body: topology.number(j.second.body),
        coordinates: mechanism
            .link(j.link)
            .coordinates
            .iter()
            .map(|c| c.to_string())
            .collect(),
        joint,
    }
}

/// The numbered tree, the joints and, when all values are known, the mobility.
pub fn tree(mechanism: &Mechanism) -> Result<TreeReport, Vec<Diagnostic>> {
    let topology = topology::build(mechanism)?;
    let unknowns = given_values(mechanism)?;
    let bodies: Vec<BodyReport> = topology
        .principal
        .iter()
        .map(|link| BodyReport {
            number: link.child,
            name: mechanism.body_name(BodyRef::Body(topology.bodies[link.child - 1])),
            parent: link.parent,
            link: link_report(mechanism, &topology, link.join, link.number, &unknowns),
        })
        .collect();
    let complementary = topology
        .complementary
        .iter()
        .map(|link| link_report(mechanism, &topology, link.join, link.number, &unknowns))
        .collect();
    // Each mimic joint couples two coordinates of the tree: one degree of freedom less.
    let couplings = (mechanism.joins.iter())
        .filter(|j| mechanism.link(j.link).mimic().is_declared())
        .count();
    let not_planar = planarity(mechanism, &topology, unknowns).err();
    if topology.complementary.is_empty() {
        // A tree: no constraint, the mobility is the sum of the links' degrees of freedom.
        let joints: Option<Vec<&JointAnalysis>> = bodies
            .iter()
            .map(|b: &BodyReport| b.link.joint.as_ref())
            .collect();
        let (mobility, unavailable) = match joints {
            Some(joints) => (
                Some(
                    Mobility::of_tree(joints.iter().map(|j| j.dof).sum()).with_couplings(couplings),
                ),
                None,
            ),
            None => (None, Some("a joint could not be analysed".to_string())),
        };
        let (contacts, unavailable) = match (&mobility, mechanism.contacts.is_empty()) {
            (Some(m), false) => match tree_contacts(mechanism, topology, m.tree_dof) {
                Ok(contacts) => (Some(contacts.with_couplings(couplings)), unavailable),
                // A contact written wrong is an error of the program, not a missing value.
                Err(d) if d.iter().any(|d| d.code.starts_with("E082")) => return Err(d),
                Err(d) => (None, Some(joined_messages(&d))),
            },
            _ => (None, unavailable),
        };
        return Ok(TreeReport {
            bodies,
            complementary,
            mobility,
            mobility_unavailable: unavailable,
            contacts,
            planar: not_planar.is_none(),
            not_planar,
            warnings: Vec::new(),
            model: mechanism.scene.clone(),
        });
    }
    let mut warnings = Vec::new();
    let (mobility, mobility_unavailable) =
        match assembled_model(mechanism, topology, &AssemblyOptions::default()) {
            Ok((model, assembled, assembly_warnings)) => {
                warnings = assembly_warnings;
                match mobility(&model, &assembled.coordinates_vector()) {
                    Ok(m) => (Some(m.with_couplings(couplings)), None),
                    Err(e) => (None, Some(crate::kinematics::eval::describe(&e, mechanism))),
                }
            }
            Err(diagnostics) => (
                None,
                Some(
                    diagnostics
                        .iter()
                        .map(|d| d.message.clone())
                        .collect::<Vec<_>>()
                        .join("; "),
                ),
            ),
        };
    Ok(TreeReport {
        bodies,
        complementary,
        mobility,
        mobility_unavailable,
        contacts: None,
        planar: not_planar.is_none(),
        not_planar,
        warnings,
        model: mechanism.scene.clone(),
    })
}

/// Whether the mechanism's joints move its bodies in one plane, with the program's own values;
/// if not, why (a value its kinematics lack among the reasons). Decided from the kinematic
/// model alone (`kinematics::plane`): `tree` builds no dynamics, so that a mechanism whose
/// inertias have no values is numbered, analysed and said planar all the same.
fn planarity(
    mechanism: &Mechanism,
    topology: &Topology,
    unknowns: UnknownValues,
) -> Result<(), String> {
    let kinematics =
        model::build(mechanism, topology.clone(), unknowns).map_err(|d| joined_messages(&d))?;
    crate::kinematics::plane::motion_plane(&kinematics).map(|_| ())
}

fn joined_messages(diagnostics: &[Diagnostic]) -> String {
    diagnostics
        .iter()
        .map(|d| d.message.clone())
        .collect::<Vec<_>>()
        .join("; ")
}

/// The contacts' degrees of freedom for a tree, at its `initial` configuration, or why they
/// cannot be computed.
fn tree_contacts(
    mechanism: &Mechanism,
    topology: Topology,
    tree_dof: usize,
) -> Result<ContactMobility, Vec<Diagnostic>> {
    let (model, assembled, _) = assembled_model(mechanism, topology, &AssemblyOptions::default())?;
    let mut errors = Vec::new();
    let contacts = contact_models(mechanism, &model, &mut errors);
    let configuration = forward(&model, &assembled.coordinates_vector()).map_err(|e| {
        vec![Diagnostic::error(
            "E0802",
            crate::kinematics::eval::describe(&e, mechanism),
        )]
    })?;
    Ok(contact_mobility(&contacts, &configuration, tree_dof))
}

impl AssemblyReport {
    pub fn coordinates_vector(&self) -> Vec<f64> {
        self.coordinates.iter().map(|c| c.value).collect()
    }
}

/// Builds the numeric model and assembles it from the program's `initial` values.
pub fn assembled_model(
    mechanism: &Mechanism,
    topology: Topology,
    options: &AssemblyOptions,
) -> Result<(KinematicModel, AssemblyReport, Vec<Diagnostic>), Vec<Diagnostic>> {
    assembled_model_with(mechanism, topology, options, &[])
}

/// `assembled_model` with values of unknowns from the command line (`--set`) over `given`.
pub fn assembled_model_with(
    mechanism: &Mechanism,
    topology: Topology,
    options: &AssemblyOptions,
    overrides: &[Override],
) -> Result<(KinematicModel, AssemblyReport, Vec<Diagnostic>), Vec<Diagnostic>> {
    let values = match overrides {
        [] => given_values(mechanism)?,
        _ => unknown_values(
            mechanism,
            &notation::unknown_names(mechanism, &topology),
            overrides,
        )?,
    };
    let model = model::build(mechanism, topology, values)?;
    let mut errors = Vec::new();
    contact_models(mechanism, &model, &mut errors);
    if !errors.is_empty() {
        return Err(errors);
    }
    let initial = assemble_initial(mechanism, &model, options)?;
    let assembled = initial.assembled;
    let names = model.coordinate_names();
    let moved = assembled
        .moved
        .iter()
        .map(|m| MovedValue {
            name: names[m.coordinate].clone(),
            given: m.given,
            assembled: m.assembled,
        })
        .collect();
    let coordinates = names
        .into_iter()
        .zip(&assembled.q)
        .zip(&initial.fixed)
        .map(|((name, &value), &fixed)| CoordinateValue { name, value, fixed })
        .collect();
    let report = AssemblyReport {
        coordinates,
        iterations: assembled.iterations,
        residual: assembled.residual,
        moved,
    };
    let mut warnings = initial.warnings;
    warnings.extend(sphere_contacts_on_discs(mechanism, &model, &assembled.q));
    Ok((model, report, warnings))
}
