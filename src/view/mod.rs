//! `lsdc view`: the mechanism in 3D in a web page — served on 127.0.0.1 with simulations on
//! demand and dragging, or exported as one standalone HTML file.

pub mod page;
pub mod scene;
pub mod server;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::elab::mechanism::Mechanism;
use crate::kinematics::drag::{drag, DragError, DragOptions};
use crate::kinematics::frames::FramePoint;
use crate::simulate::prepare::Prepared;
use crate::simulate::run::{run_with, RunOptions};
use crate::simulate::settings::SettingsChanges;
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
        let saved = self.prepared.settings.clone();
        let changes = SettingsChanges {
            duration,
            ..SettingsChanges::default()
        };
        self.prepared
            .settings
            .apply(&changes)
            .map_err(|e| e.to_string())?;
        let simulation = run_with(&self.prepared, &RunOptions::default(), &mut |_| {});
        self.prepared.settings = saved;
        let recorded = Recorded::from(&simulation);
        animation(&self.mechanism, &self.prepared, &recorded)
            .map_err(|e| crate::kinematics::eval::describe(&e, &self.mechanism))
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
        let options = DragOptions::default();
        let target = Vector3::from(request.target);
        let dragged =
            drag(model, &frame, &request.coordinates, &target, &options).map_err(|e| match e {
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
        })
    }
}

#[derive(Clone, Debug, Deserialize)]
pub struct DragRequest {
    pub body: usize,
    /// The grabbed point, in the body's frame.
    pub point: [f64; 3],
    pub target: [f64; 3],
    pub coordinates: Vec<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct DragResponse {
    pub coordinates: Vec<f64>,
    pub poses: Vec<[f64; 7]>,
    pub distance: f64,
    pub reached: bool,
    pub loop_residual: f64,
}
