//! The equations of motion of a tree mechanism as a first-order system y' = f(t, y), with
//! y = (positions, velocities): positions move with the joint velocities (quaternions included),
//! velocities with the accelerations from the articulated-body algorithm under the efforts.

use std::cell::RefCell;
use std::rc::Rc;

use crate::dynamics::algorithms::{aba, forward_kinematics, Data, DynamicsError};
use crate::dynamics::efforts::{evaluate, Declared};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;

pub struct MechanicalSystem<'m> {
    pub model: &'m Model,
    pub data: Data,
    /// Declared coordinates at the last output, shared with the sampler: recovered angles stay
    /// continuous (a spring on an angle sees 3π/2, not −π/2, after one and a half turns).
    pub reference: Rc<RefCell<Vec<f64>>>,
}

impl<'m> MechanicalSystem<'m> {
    pub fn new(model: &'m Model, reference: Rc<RefCell<Vec<f64>>>) -> MechanicalSystem<'m> {
        MechanicalSystem { model, data: Data::new(model), reference }
    }

    pub fn dimension(&self) -> usize {
        self.model.nq + self.model.nv
    }

    /// dy/dt at (t, y), or why it cannot be computed.
    pub fn derivative(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
        let model = self.model;
        let (q, v) = model.split_state(y);
        forward_kinematics(model, &mut self.data, &q, v).map_err(|e| evaluation_message(&e))?;
        let reference = self.reference.borrow().clone();
        let (coordinates, rates) = model.declared(&q, v, &reference).map_err(|e| evaluation_message(&e))?;
        let declared = Declared { model, coordinates: &coordinates, rates: &rates };
        let efforts = evaluate(model, &self.data, &declared, t).map_err(|e| evaluation_message(&e))?;
        let accelerations = aba(model, &mut self.data, &q, v, efforts.tau.as_slice(), &efforts.external)
            .map_err(|e| self.dynamics_message(&e))?;
        if let Some(k) = accelerations.iter().position(|a| !a.is_finite()) {
            let joint = model.joints.iter().find(|j| (j.v_offset..j.v_offset + j.nv()).contains(&k));
            let name = joint.map_or("?".to_string(), |j| j.chain.name.clone());
            let cause = if efforts.tau.iter().all(|x| x.is_finite()) && efforts.external.iter().all(|f| f.iter().all(|x| x.is_finite())) {
                "the state became too large"
            } else {
                "an effort is not a number (a square root or logarithm of a negative value, a division by zero)"
            };
            return Err(format!("the acceleration of join `{name}` is not finite: {cause}"));
        }
        let (dq, dv) = dydt.split_at_mut(model.nq);
        for joint in &model.joints {
            let range = joint.q_offset..joint.q_offset + joint.nq();
            joint.position_rate(&q[range.clone()], &v[joint.v_offset..joint.v_offset + joint.nv()], &mut dq[range]);
        }
        dv.copy_from_slice(accelerations.as_slice());
        Ok(())
    }

    fn dynamics_message(&self, error: &DynamicsError) -> String {
        match error {
            DynamicsError::Evaluation(e) => evaluation_message(e),
            DynamicsError::Singular { joint, body } => format!(
                "the mass matrix is singular: join `{}` carries no inertia along its motion (body `{}` and the bodies beyond it)",
                self.model.joints[*joint].chain.name,
                self.model.body_names[body - 1]
            ),
        }
    }
}

fn evaluation_message(error: &EvalError) -> String {
    match error {
        EvalError::Missing(_) => "an effort needs a value that was not given".to_string(),
        EvalError::NotGeometric(what) => format!("an expression cannot depend on {what} there"),
    }
}
