//! `lsdc view`: the mechanism in 3D in a web page — served on 127.0.0.1 with simulations on
//! demand and dragging, or exported as one standalone HTML file.

pub mod page;
pub mod scene;
pub mod server;
pub mod workspace_layer;

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::elab::mechanism::Mechanism;
use crate::kinematics::drag::{drag, DragError, DragOptions};
use crate::kinematics::frames::FramePoint;
use crate::kinematics::penalty;
use crate::prepare::settings::SettingsChanges;
use crate::prepare::Prepared;
use crate::simulate::run::{run_with, RunOptions};
use scene::{animation, scene, Animation, Recorded, Scene};

/// A mechanism ready to be shown: its scene, and the animation given with `--results`.
pub struct Viewer {
    pub mechanism: Mechanism,
    pub prepared: Prepared,
    pub scene: Scene,
    pub results: Option<Animation>,
}

impl Viewer {
    pub fn new(mechanism: Mechanism, prepared: Prepared, title: &str) -> Result<Viewer, String> {
        let scene = scene(&mechanism, &prepared, title)
            .map_err(|e| crate::kinematics::eval::describe(&e, &mechanism))?;
        Ok(Viewer {
            mechanism,
            prepared,
            scene,
            results: None,
        })
    }

    /// The animation of recorded results (`simulate --format json`).
    pub fn play(&mut self, recorded: &Recorded) -> Result<(), String> {
        let played = animation(&self.mechanism, &self.prepared, recorded)
            .map_err(|e| crate::kinematics::eval::describe(&e, &self.mechanism))?;
        self.results = Some(played);
        Ok(())
    }

    /// Runs the simulation, for `duration` seconds when given (else the program's), and
    /// returns its animation.
    pub fn simulate(&mut self, duration: Option<f64>) -> Result<Animation, String> {
        self.simulate_with(&SettingsChanges {
            duration,
            ..SettingsChanges::default()
        })
    }

    /// Runs the simulation with the program's settings changed by `changes`.
    pub fn simulate_with(&mut self, changes: &SettingsChanges) -> Result<Animation, String> {
        let saved = self.prepared.settings.clone();
        self.prepared
            .settings
            .apply(changes)
            .map_err(|e| e.to_string())?;
        let simulation = run_with(&self.prepared, &RunOptions::default(), &mut |_| {});
        self.prepared.settings = saved;
        let recorded = Recorded::from(&simulation);
        animation(&self.mechanism, &self.prepared, &recorded)
            .map_err(|e| crate::kinematics::eval::describe(&e, &self.mechanism))
    }

    /// Shows the workspace sampled in `slices` as a layer of the scene.
    pub fn show_workspace(&mut self, slices: &crate::output::workspace_plot::Slices) {
        self.scene.workspace = Some(slices.into());
    }

    /// The page, standalone (`live` false) or served.
    pub fn page(&self, live: bool) -> String {
        page::page(&self.scene, self.results.as_ref(), live)
    }

    /// One drag move: the point `request.point` of body `request.body` pulled to
    /// `request.target`, from the configuration `request.coordinates`.
    pub fn drag(&self, request: &DragRequest) -> Result<DragResponse, String> {
        let model = &self.prepared.kinematics;
        if request.body == 0 || request.body > model.topology.body_count() {
            return Err(format!("no body {} to drag", request.body));
        }
        if request.coordinates.len() != model.coordinate_count {
            return Err(format!("expected {} coordinates", model.coordinate_count));
        }
        let frame = FramePoint {
            name: "mouse".to_string(),
            body: request.body,
            offset: crate::spatial::translation(Vector3::from(request.point)),
        };
        match request.method {
            DragMethod::Exact => self.exact_drag(request, &frame),
            DragMethod::Penalty => self.penalty_drag(request, &frame),
        }
    }

    /// The exact method: the loops closed, the point a soft goal (`kinematics::drag`).
    fn exact_drag(
        &self,
        request: &DragRequest,
        frame: &FramePoint,
    ) -> Result<DragResponse, String> {
        let model = &self.prepared.kinematics;
        let options = DragOptions::default();
        let target = Vector3::from(request.target);
        let dragged =
            drag(model, frame, &request.coordinates, &target, &options).map_err(|e| match e {
                DragError::Evaluation(e) => crate::kinematics::eval::describe(&e, &self.mechanism),
                DragError::NoAssembly { loop_residual } => {
                    format!("the loops cannot be closed (residual {loop_residual:.3e})")
                }
            })?;
        let poses = scene::body_poses(model, &dragged.q)
            .map_err(|e| crate::kinematics::eval::describe(&e, &self.mechanism))?;
        Ok(DragResponse {
            reached: dragged.reached(&options),
            coordinates: dragged.q,
            poses,
            distance: dragged.distance,
            loop_residual: dragged.loop_residual,
            planar: None,
        })
    }

    /// The seed's penalty method, one linearised solve per move from the planar state the page
    /// carries (or the one of `request.coordinates` at the first move); the joint coordinates
    /// stay those of the last exact configuration, the bodies drawn at the penalty's poses.
    fn penalty_drag(
        &self,
        request: &DragRequest,
        frame: &FramePoint,
    ) -> Result<DragResponse, String> {
        let model = &self.prepared.kinematics;
        let describe = |e| crate::kinematics::eval::describe(&e, &self.mechanism);
        let planar = penalty::planar_model(model, self.prepared.model.body_names.clone())?;
        let state = match &request.planar {
            Some(state) if state.len() == planar.bodies => state.clone(),
            Some(_) => {
                return Err(format!(
                    "expected the planar state of {} bodies",
                    planar.bodies
                ))
            }
            None => penalty::planar_state(model, &request.coordinates).map_err(describe)?,
        };
        let point = penalty::planar_point(frame);
        let target = Vector2::new(request.target[0], request.target[1]);
        let stiffness = penalty::Stiffness {
            link: 1e6,
            mouse: 1.0,
        };
        let state = planar.step(&state, &point, &target, stiffness);
        let position = penalty::point_position(&planar, &state, &point);
        let distance = (position.xy() - target).norm();
        let heights = scene::body_poses(model, &request.coordinates).map_err(describe)?;
        let poses = (state.iter().zip(&heights))
            .map(|([x, y, angle], height)| {
                let (s, c) = (0.5 * angle).sin_cos();
                [*x, *y, height[2], c, 0.0, 0.0, s]
            })
            .collect();
        Ok(DragResponse {
            reached: distance <= DragOptions::default().reach_tolerance,
            coordinates: request.coordinates.clone(),
            poses,
            distance,
            loop_residual: planar.largest_gap(&state),
            planar: Some(state),
        })
    }
}

/// How the page drags: `exact` (the default) or the seed's `penalty` method.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum DragMethod {
    #[default]
    Exact,
    Penalty,
}

#[derive(Clone, Debug, Deserialize)]
pub struct DragRequest {
    pub body: usize,
    /// The grabbed point, in the body's frame.
    pub point: [f64; 3],
    pub target: [f64; 3],
    pub coordinates: Vec<f64>,
    #[serde(default)]
    pub method: DragMethod,
    /// Penalty method: the bodies' (X, Y, Θ) the previous move left, absent at the first.
    #[serde(default)]
    pub planar: Option<Vec<[f64; 3]>>,
}

#[derive(Clone, Debug, Serialize)]
pub struct DragResponse {
    pub coordinates: Vec<f64>,
    pub poses: Vec<[f64; 7]>,
    pub distance: f64,
    pub reached: bool,
    /// Exact: the loops' residual. Penalty: the largest gap of a pivot.
    pub loop_residual: f64,
    /// Penalty method: the bodies' (X, Y, Θ), for the next move.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub planar: Option<Vec<[f64; 3]>>,
}
