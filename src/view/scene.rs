//! What the viewer draws, as plain serialisable data: the bodies (the points that shape them,
//! their inertia as an ellipsoid), the joints (where, about or along which axis, whether they
//! close a loop), the named frames; and an animation: the bodies' poses at each output of a
//! simulation with the series the plots show.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::elab::mechanism::Mechanism;
use crate::kinematics::eval::EvalError;
use crate::kinematics::forward::poses;
use crate::kinematics::frames::{self, quaternion, FramePoint};
use crate::kinematics::model::{KinematicModel, SingleMotion};
use crate::prepare::Prepared;
use crate::simulate::run::Simulation;
use crate::spatial::Pose;

use super::workspace_layer::WorkspaceLayer;

#[derive(Clone, Debug, Serialize)]
pub struct Scene {
    pub title: String,
    /// Body j at index j − 1 (earth, body 0, is the fixed frame).
    pub bodies: Vec<SceneBody>,
    pub joints: Vec<SceneJoint>,
    pub frames: Vec<SceneFrame>,
    /// The joint coordinates of the configuration shown first, for dragging from it.
    pub coordinates: Vec<f64>,
    pub coordinate_names: Vec<String>,
    /// The bodies' poses in that configuration.
    pub poses: Vec<[f64; 7]>,
    /// The workspace of a point, when asked for (`lsdc view --workspace`).
    pub workspace: Option<WorkspaceLayer>,
}

#[derive(Clone, Debug, Serialize)]
pub struct SceneBody {
    pub name: String,
    pub number: usize,
    /// Points of the body, in its frame: its joints' frames and its named frames. The viewer
    /// draws a rod from the first to each other one (a box or rod between join points).
    pub points: Vec<[f64; 3]>,
    pub mass: f64,
    pub com: [f64; 3],
    /// The uniform ellipsoid of the same mass and central inertia: semi-axes and orientation
    /// (quaternion w, x, y, z) in the body frame; none for a massless body.
    pub ellipsoid: Option<Ellipsoid>,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct Ellipsoid {
    pub semi_axes: [f64; 3],
    pub orientation: [f64; 4],
}

#[derive(Clone, Debug, Serialize)]
pub struct SceneJoint {
    pub name: String,
    /// Body numbers (0 = earth) of its first and second frames.
    pub first_body: usize,
    pub second_body: usize,
    /// The first frame's origin and the joint's axis, in the first body's frame.
    pub position: [f64; 3],
    pub axis: Option<[f64; 3]>,
    /// `revolute`, `prismatic` or `other` (several coordinates, or a chain of steps).
    pub kind: &'static str,
    /// A complementary link, which closes a loop.
    pub complementary: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct SceneFrame {
    pub name: String,
    pub body: usize,
    pub position: [f64; 3],
    pub orientation: [f64; 4],
}

/// Pose as `[x, y, z, qw, qx, qy, qz]`.
fn pose_array(pose: &Pose) -> [f64; 7] {
    let t = pose.translation.vector;
    let [w, x, y, z] = quaternion(&pose.rotation);
    [t.x, t.y, t.z, w, x, y, z]
}

fn array(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// The poses of the bodies (1…n) at coordinates `q`.
pub fn body_poses(model: &KinematicModel, q: &[f64]) -> Result<Vec<[f64; 7]>, EvalError> {
    Ok(poses(model, q)?[1..].iter().map(pose_array).collect())
}

/// The named frames of the program, resolved (those that are not constant on their body are
/// left out).
pub fn named_frames(mechanism: &Mechanism, model: &KinematicModel) -> Vec<FramePoint> {
    mechanism
        .frames
        .iter()
        .filter_map(|f| frames::resolve(mechanism, model, &f.name).ok())
        .collect()
}

/// The scene of a prepared mechanism, in its initial configuration.
pub fn scene(mechanism: &Mechanism, prepared: &Prepared, title: &str) -> Result<Scene, EvalError> {
    let model = &prepared.kinematics;
    let named = named_frames(mechanism, model);
    let mut points: Vec<Vec<[f64; 3]>> = vec![Vec::new(); model.topology.body_count() + 1];
    for joint in &model.joints {
        points[joint.first_body].push(array(&joint.first.translation.vector));
        points[joint.second_body].push(array(&joint.second.translation.vector));
    }
    for frame in &named {
        points[frame.body].push(array(&frame.offset.translation.vector));
    }
    let bodies = prepared
        .model
        .bodies
        .iter()
        .enumerate()
        .map(|(index, inertia)| {
            let number = index + 1;
            let mut shape = points[number].clone();
            shape.dedup();
            SceneBody {
                name: prepared.model.body_names[index].clone(),
                number,
                points: shape,
                mass: inertia.mass,
                com: array(&inertia.com),
                ellipsoid: ellipsoid(
                    inertia.mass,
                    &inertia.com,
                    &inertia.inertia.fixed_view::<3, 3>(0, 0).into_owned(),
                ),
            }
        })
        .collect();
    let principal = model.topology.body_count();
    let joints = model
        .joints
        .iter()
        .enumerate()
        .map(|(index, joint)| {
            let (kind, axis) = match joint.single_motion() {
                Some(SingleMotion::Rotation { axis, .. }) => ("revolute", Some(axis)),
                Some(SingleMotion::Translation { direction }) => {
                    ("prismatic", Some(direction.normalize()))
                }
                None => ("other", None),
            };
            SceneJoint {
                name: joint.name.clone(),
                first_body: joint.first_body,
                second_body: joint.second_body,
                position: array(&joint.first.translation.vector),
                axis: axis.map(|a| array(&(joint.first.rotation * a))),
                kind,
                complementary: index >= principal,
            }
        })
        .collect();
    let frames = named
        .iter()
        .map(|f| SceneFrame {
            name: f.name.clone(),
            body: f.body,
            position: array(&f.offset.translation.vector),
            orientation: quaternion(&f.offset.rotation),
        })
        .collect();
    Ok(Scene {
        title: title.to_string(),
        bodies,
        joints,
        frames,
        poses: body_poses(model, &prepared.coordinates)?,
        coordinates: prepared.coordinates.clone(),
        coordinate_names: prepared.coordinate_names.clone(),
        workspace: None,
    })
}

/// The uniform solid ellipsoid with the body's mass and central inertia (from the inertia
/// `about_origin` about the body frame's origin): with principal moments I₁, I₂, I₃, its
/// semi-axes are a₁² = 5 (I₂ + I₃ − I₁) / 2m and so on.
fn ellipsoid(mass: f64, com: &Vector3<f64>, about_origin: &Matrix3<f64>) -> Option<Ellipsoid> {
    if mass <= 0.0 {
        return None;
    }
    let central =
        about_origin - mass * (Matrix3::identity() * com.norm_squared() - com * com.transpose());
    let eigen = central.symmetric_eigen();
    let moments = eigen.eigenvalues;
    let semi = |i: usize| {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        (2.5 * (moments[j] + moments[k] - moments[i]) / mass)
            .max(0.0)
            .sqrt()
    };
    let mut axes = eigen.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.column_mut(2).neg_mut();
    }
    let rotation = nalgebra::UnitQuaternion::from_matrix(&axes);
    Some(Ellipsoid {
        semi_axes: [semi(0), semi(1), semi(2)],
        orientation: quaternion(&rotation),
    })
}

/// A simulation as the viewer plays it: the bodies' poses at each output, and the series the
/// plots offer (coordinates, rates, energies, the named frames' positions).
#[derive(Clone, Debug, Serialize)]
pub struct Animation {
    pub times: Vec<f64>,
    /// `poses[k][j − 1]`: body j at output k.
    pub poses: Vec<Vec<[f64; 7]>>,
    pub series: Vec<Series>,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
}

/// The part of a simulation the viewer plays: what `lsdc simulate --format json` writes, read
/// back (its other fields are ignored).
#[derive(Clone, Debug, Deserialize)]
pub struct Recorded {
    pub coordinate_names: Vec<String>,
    /// The columns of the program's named outputs (absent from runs without outputs).
    #[serde(default)]
    pub output_names: Vec<String>,
    pub samples: Vec<RecordedSample>,
    #[serde(skip)]
    pub failure: Option<String>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct RecordedSample {
    pub time: f64,
    pub coordinates: Vec<f64>,
    pub rates: Vec<f64>,
    pub kinetic_energy: f64,
    pub potential_energy: Option<f64>,
    #[serde(default)]
    pub outputs: Vec<f64>,
}

impl From<&Simulation> for Recorded {
    fn from(simulation: &Simulation) -> Recorded {
        let samples = simulation.samples.iter().map(|s| RecordedSample {
            time: s.time,
            coordinates: s.coordinates.clone(),
            rates: s.rates.clone(),
            kinetic_energy: s.kinetic_energy,
            potential_energy: s.potential_energy,
            outputs: s.outputs.clone(),
        });
        Recorded {
            coordinate_names: simulation.coordinate_names.clone(),
            output_names: simulation.output_names.clone(),
            samples: samples.collect(),
            failure: simulation
                .report
                .failure
                .as_ref()
                .map(|f| f.message.clone()),
        }
    }
}

/// Reads the output of `lsdc simulate --format json`, checking that it is a run of this
/// mechanism (the same coordinates).
pub fn read_results(text: &str, name: &str, prepared: &Prepared) -> Result<Recorded, String> {
    let recorded: Recorded = serde_json::from_str(text).map_err(|e| {
        format!(
            "{name}:{}:{}: not the output of `lsdc simulate --format json`: {e}",
            e.line(),
            e.column()
        )
    })?;
    if recorded.coordinate_names != prepared.coordinate_names {
        return Err(format!(
            "{name}: its coordinates ({}) are not this mechanism's ({})",
            recorded.coordinate_names.join(", "),
            prepared.coordinate_names.join(", ")
        ));
    }
    let count = recorded.coordinate_names.len();
    if let Some(k) = recorded
        .samples
        .iter()
        .position(|s| s.coordinates.len() != count || s.rates.len() != count)
    {
        return Err(format!(
            "{name}: sample {} does not have {count} coordinates and rates",
            k + 1
        ));
    }
    let outputs = recorded.output_names.len();
    if let Some(k) = (recorded.samples.iter()).position(|s| s.outputs.len() != outputs) {
        return Err(format!(
            "{name}: sample {} does not have the values of its {outputs} outputs",
            k + 1
        ));
    }
    Ok(recorded)
}

/// The animation of a run of the prepared mechanism.
pub fn animation(
    mechanism: &Mechanism,
    prepared: &Prepared,
    simulation: &Recorded,
) -> Result<Animation, EvalError> {
    let model = &prepared.kinematics;
    let named = named_frames(mechanism, model);
    let samples = &simulation.samples;
    let mut poses = Vec::with_capacity(samples.len());
    let mut frame_positions = vec![Vec::new(); 3 * named.len()];
    for sample in samples {
        poses.push(body_poses(model, &sample.coordinates)?);
        let states = frames::states(model, &named, &sample.coordinates, &sample.rates)?;
        for (k, state) in states.iter().enumerate() {
            for c in 0..3 {
                frame_positions[3 * k + c].push(state.position[c]);
            }
        }
    }
    let mut series = Vec::new();
    for (i, name) in simulation.coordinate_names.iter().enumerate() {
        let values = samples.iter().map(|s| s.coordinates[i]).collect();
        series.push(Series {
            name: name.clone(),
            values,
        });
    }
    for (i, name) in simulation.coordinate_names.iter().enumerate() {
        let values = samples.iter().map(|s| s.rates[i]).collect();
        series.push(Series {
            name: format!("{name}'"),
            values,
        });
    }
    series.push(Series {
        name: "kinetic_energy".into(),
        values: samples.iter().map(|s| s.kinetic_energy).collect(),
    });
    if samples.iter().all(|s| s.potential_energy.is_some()) {
        let potential: Vec<f64> = samples
            .iter()
            .map(|s| s.potential_energy.unwrap_or(0.0))
            .collect();
        let total = samples
            .iter()
            .zip(&potential)
            .map(|(s, p)| s.kinetic_energy + p)
            .collect();
        series.push(Series {
            name: "potential_energy".into(),
            values: potential,
        });
        series.push(Series {
            name: "energy".into(),
            values: total,
        });
    }
    for (i, name) in simulation.output_names.iter().enumerate() {
        series.push(Series {
            name: name.clone(),
            values: samples.iter().map(|s| s.outputs[i]).collect(),
        });
    }
    for (k, frame) in named.iter().enumerate() {
        for (c, axis) in ["x", "y", "z"].iter().enumerate() {
            let values = std::mem::take(&mut frame_positions[3 * k + c]);
            series.push(Series {
                name: format!("{}.{axis}", frame.name),
                values,
            });
        }
    }
    Ok(Animation {
        times: samples.iter().map(|s| s.time).collect(),
        poses,
        series,
        failure: simulation.failure.clone(),
    })
}
