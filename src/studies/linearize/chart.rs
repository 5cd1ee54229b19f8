//! The independent coordinates a linearisation is written in, and the mechanism's state they
//! stand for. In a tree every coordinate is independent. With closed loops the independent ones
//! z are as many as the mobility (the run's free coordinates, or those the user names), and
//! the others follow from the loops: at given z, the positions are closed by Gauss–Newton steps
//! that leave z where it is (minimum-norm steps on the closure rows with z's columns removed,
//! the house's corrector), always from the operating point's positions, so that the map from
//! z is one smooth function; at given ż, the dependent rates solve G v = 0.

use nalgebra::{DMatrix, DVector};

use crate::corrector::{self, Acceptance, Correction, Damping, Progress, Settings};
use crate::dynamics::algorithms::Data;
use crate::dynamics::loops::{self, basis::SOLVE_TOLERANCE, Extent};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;

/// A closure from nearby positions takes four or five steps; more means it is not converging.
const CLOSURE_ITERATIONS: usize = 30;

/// The largest closure row (radians, metres) left after closing that counts as closed: the
/// corrector goes on to round-off, a few 1e-16 relative to the mechanism's size.
const CLOSED: f64 = 1e-11;

/// The independent coordinates (their indices among the state's velocities) and how to
/// complete them.
#[derive(Clone, Debug)]
pub struct Chart {
    pub independent: Vec<usize>,
    /// The independent coordinates' indices among the state's positions.
    positions: Vec<usize>,
    /// The coordinates that follow from the independent ones through the loops (none in a
    /// tree).
    pub dependent: Vec<usize>,
    /// Velocities held at the operating point: motions the loops allow that carry no mass (a
    /// rod spinning about its axis between two ball joints), left out of the linear model.
    pub held: Vec<usize>,
    /// The coordinates imposed by laws of time (their state velocities), each with its rate at
    /// the operating point's time: not states of the linear model (a tree's only).
    pub driven: Vec<(usize, f64)>,
    /// The operating point's positions, where every closure starts (the driven coordinates'
    /// on their laws).
    origin: Vec<f64>,
    /// The loops' rows that constrain anything (a ball joint's rotation rows do not).
    rows: Vec<usize>,
}

/// Why a state cannot be formed from independent coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum ChartError {
    Evaluation(EvalError),
    /// The loops could not be closed at these independent coordinates: the largest row left.
    NotClosed {
        residual: f64,
    },
}

impl From<EvalError> for ChartError {
    fn from(error: EvalError) -> Self {
        ChartError::Evaluation(error)
    }
}

impl Chart {
    /// Every coordinate of a tree whose joints are all chains of coordinates, but those its
    /// drives impose: they stay on their laws, at the positions of `origin` and the rates of
    /// `rates` (the operating point's).
    pub fn tree(model: &Model, origin: &[f64], rates: &[f64]) -> Chart {
        let driven: Vec<(usize, f64)> = (model.drives.iter())
            .map(|d| (d.velocity, rates[d.velocity]))
            .collect();
        let independent: Vec<usize> = (0..model.velocities())
            .filter(|i| !driven.iter().any(|(d, _)| d == i))
            .collect();
        Chart {
            driven,
            positions: independent
                .iter()
                .filter_map(|&i| model.position_of(i))
                .collect(),
            independent,
            dependent: Vec::new(),
            held: Vec::new(),
            origin: origin.to_vec(),
            rows: Vec::new(),
        }
    }

    /// The coordinates `independent` (each a coordinate of a chain, see `Model::position_of`) of a
    /// mechanism with loops closed at `origin`, the velocities `held` where they are.
    pub fn with_loops(
        model: &Model,
        independent: Vec<usize>,
        held: Vec<usize>,
        origin: &[f64],
    ) -> Chart {
        let active = loops::active_rows(model);
        let rows = (0..active.len()).filter(|&r| active[r]).collect();
        Chart {
            driven: Vec::new(),
            dependent: (0..model.velocities())
                .filter(|i| !independent.contains(i) && !held.contains(i))
                .collect(),
            held,
            positions: independent
                .iter()
                .filter_map(|&i| model.position_of(i))
                .collect(),
            independent,
            origin: origin.to_vec(),
            rows,
        }
    }

    /// Whether the loops' rows, at the chart's origin, leave the dependent coordinates
    /// determined by the independent and held ones: removing their columns from G keeps its
    /// rank.
    pub fn parametrises(&self, model: &Model, data: &mut Data) -> Result<bool, EvalError> {
        let jacobian = self.rows_jacobian(model, data, &self.origin)?;
        let full = loops::decompose(&jacobian).rank;
        let dependent = loops::decompose(&self.without_independent(jacobian)).rank;
        Ok(full == dependent)
    }

    /// The positions and velocities at independent coordinates `z` and rates `rates`.
    pub fn state(
        &self,
        model: &Model,
        data: &mut Data,
        z: &[f64],
        rates: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), ChartError> {
        let mut q = self.origin.clone();
        let mut v = vec![0.0; model.velocities()];
        for &(i, rate) in &self.driven {
            v[i] = rate;
        }
        for (k, (&i, &p)) in self.independent.iter().zip(&self.positions).enumerate() {
            q[p] = z[k];
            v[i] = rates[k];
        }
        if self.dependent.is_empty() {
            return Ok((q, v));
        }
        let mut closure = HeldClosure {
            model,
            data: &mut *data,
            chart: self,
            residual: DVector::zeros(0),
            jacobian: DMatrix::zeros(0, 0),
            step: DVector::zeros(0),
            trial: Vec::new(),
            trial_residual: DVector::zeros(0),
            q,
        };
        closure.residual = closure.residual_at(&closure.q.clone())?;
        corrector::correct(&mut closure, &CLOSURE)?;
        let left = closure.merit();
        if left.is_nan() || left > CLOSED {
            return Err(ChartError::NotClosed { residual: left });
        }
        let q = closure.q;
        let jacobian = self.rows_jacobian(model, data, &q)?;
        let moving = &jacobian * DVector::from_column_slice(&v);
        let dependent = self.without_independent(jacobian);
        let completion = corrector::minimum_norm_step(&dependent, &moving, SOLVE_TOLERANCE)
            .ok_or(ChartError::NotClosed { residual: f64::NAN })?;
        v.iter_mut()
            .zip(completion.iter())
            .for_each(|(v, c)| *v += c);
        Ok((q, v))
    }

    /// The independent coordinates' values at positions q.
    pub fn coordinates(&self, q: &[f64]) -> Vec<f64> {
        self.positions.iter().map(|&p| q[p]).collect()
    }

    /// The active rows of G at q, one column per state velocity.
    fn rows_jacobian(
        &self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
    ) -> Result<DMatrix<f64>, EvalError> {
        let rest = vec![0.0; model.velocities()];
        let c = loops::constraints(model, data, q, &rest, Extent::Rows)?;
        Ok(c.jacobian.dense().select_rows(&self.rows))
    }

    /// `jacobian` with the independent and held velocities' columns zeroed: its minimum-norm
    /// steps leave them where they are.
    fn without_independent(&self, mut jacobian: DMatrix<f64>) -> DMatrix<f64> {
        for &i in self.independent.iter().chain(&self.held) {
            jacobian.column_mut(i).fill(0.0);
        }
        jacobian
    }
}

/// Gauss–Newton to round-off: a step is kept while it reduces the largest row.
const CLOSURE: Settings = Settings {
    iterations: CLOSURE_ITERATIONS,
    damping: Damping::None,
    acceptance: Acceptance::Descent,
    progress: Progress::Any,
};

/// The closure of the loops holding the independent coordinates, for the corrector.
struct HeldClosure<'a> {
    model: &'a Model,
    data: &'a mut Data,
    chart: &'a Chart,
    q: Vec<f64>,
    residual: DVector<f64>,
    jacobian: DMatrix<f64>,
    step: DVector<f64>,
    trial: Vec<f64>,
    trial_residual: DVector<f64>,
}

impl HeldClosure<'_> {
    fn residual_at(&mut self, q: &[f64]) -> Result<DVector<f64>, EvalError> {
        let rest = vec![0.0; self.model.velocities()];
        let c = loops::constraints(self.model, self.data, q, &rest, Extent::Residual)?;
        Ok(c.residual.select_rows(&self.chart.rows))
    }
}

impl Correction for HeldClosure<'_> {
    type Error = ChartError;

    fn settled(&self) -> bool {
        self.merit() == 0.0
    }

    fn merit(&self) -> f64 {
        self.residual.amax()
    }

    fn linearise(&mut self) -> Result<(), ChartError> {
        let jacobian = self.chart.rows_jacobian(self.model, self.data, &self.q)?;
        self.jacobian = self.chart.without_independent(jacobian);
        Ok(())
    }

    fn step(&mut self, _damping: f64) -> Result<Option<f64>, ChartError> {
        let step = corrector::minimum_norm_step(&self.jacobian, &self.residual, SOLVE_TOLERANCE);
        Ok(step.map(|step| {
            let size = step.amax();
            self.step = step;
            size
        }))
    }

    fn try_step(&mut self) -> Result<f64, ChartError> {
        self.trial.clone_from(&self.q);
        self.model.retract(&mut self.trial, self.step.as_slice());
        let trial = self.trial.clone();
        self.trial_residual = self.residual_at(&trial)?;
        Ok(self.trial_residual.amax())
    }

    fn accept(&mut self) {
        std::mem::swap(&mut self.q, &mut self.trial);
        std::mem::swap(&mut self.residual, &mut self.trial_residual);
    }
}
