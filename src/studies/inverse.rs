//! Inverse dynamics along a motion (`lsdc inverse`): the efforts that impose the program's
//! drives, for trees and closed loops alike. With every useful degree of freedom driven the
//! run is kinematics: after each step the driven coordinates are put on their laws and the
//! loops closed to round-off (the rows of `dynamics::rows`, the loops' projection), so the
//! integrator's error does not reach the samples; at each sample the drives' multipliers are the
//! efforts, their sum of effort × rate the power, and the joins' reactions come from the same
//! solve (`--reactions`). Rates and accelerations of the driven coordinates are the laws'
//! exact derivatives.

use serde::Serialize;

use crate::dynamics::driven_points;
use crate::kinematics::mobility::useful_degrees;
use crate::prepare::Prepared;
use crate::simulate::run::{output_names_of, reaction_names_of, Simulation};

/// The efforts along the motion, one row per output time.
#[derive(Clone, Debug, Serialize)]
pub struct InverseDynamics {
    /// The driven coordinates (`crank.q`) and the names of their efforts
    /// (`crank.drive_effort`), in the order of the program's drives.
    pub driven: Vec<String>,
    pub efforts: Vec<String>,
    /// The joins whose reactions the samples carry (empty unless asked for).
    pub reaction_names: Vec<String>,
    pub samples: Vec<InverseSample>,
    /// The motion file's drives and how its columns were read (`lsdc inverse --motion`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<crate::studies::trajectory::Imposed>,
}

#[derive(Clone, Debug, Serialize)]
pub struct InverseSample {
    pub time: f64,
    /// Per driven coordinate: its law, the law's rate and acceleration.
    pub positions: Vec<f64>,
    pub rates: Vec<f64>,
    pub accelerations: Vec<f64>,
    /// Per driven coordinate, the generalised force that imposes it (N·m or N).
    pub efforts: Vec<f64>,
    /// Σ effort × rate: the power the drives give the mechanism.
    pub power: f64,
    /// As `Sample::reactions`: per join, moment then force on its second body, at the join, in
    /// the fixed axes.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reactions: Vec<f64>,
}

/// Why a program's motion is not given by its drives.
#[derive(Clone, Debug, PartialEq)]
pub enum NotDriven {
    NoDrives,
    /// Fewer drives than useful degrees of freedom (the mobility less the bodies' internal
    /// motions, such as a rod spinning between two ball joints).
    Underdriven {
        degrees: usize,
        drives: usize,
    },
    /// The mobility could not be computed at the starting configuration.
    Geometry(String),
}

impl std::fmt::Display for NotDriven {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NotDriven::NoDrives => write!(f, "the program drives no coordinate: declare the motion with `drive <join>.<coordinate> = <law of time>;`, one per degree of freedom"),
            NotDriven::Underdriven { degrees, drives } => write!(f, "the mechanism has {degrees} degrees of freedom (besides its bodies' internal motions) and the program drives {drives}: drive each one (`lsdc tree` gives the mobility), or run the mixed problem with `lsdc simulate`, whose outputs carry the drives' efforts"),
            NotDriven::Geometry(why) => write!(f, "cannot compute the mobility at the start: {why}"),
        }
    }
}

impl std::error::Error for NotDriven {}

/// Checks that the drives of `prepared` impose its every useful degree of freedom.
pub fn check_driven(prepared: &Prepared) -> Result<(), NotDriven> {
    let model = &prepared.model;
    let drives = model.drives.len() + 3 * model.position_drives.len();
    if drives == 0 {
        return Err(NotDriven::NoDrives);
    }
    let couplings = prepared.model.mimics.len();
    let degrees = useful_degrees(&prepared.kinematics, &prepared.coordinates, couplings)
        .map_err(|e| NotDriven::Geometry(format!("{e:?}")))?;
    match degrees > drives {
        true => Err(NotDriven::Underdriven { degrees, drives }),
        false => Ok(()),
    }
}

/// The inverse dynamics read from a run of `prepared` (the drives' efforts among its
/// outputs, see `simulate::run::output_names_of`).
pub fn from_run(prepared: &Prepared, simulation: &Simulation) -> InverseDynamics {
    let model = &prepared.model;
    let (drives, paths) = (&model.drives, &model.position_drives);
    // The coordinates' drives, then each position drive's x, y and z (its efforts the force
    // along each at the frame's origin).
    let driven: Vec<String> = (drives.iter().map(|d| d.coordinate.clone()))
        .chain(paths.iter().flat_map(|p| p.component_names()))
        .collect();
    let efforts: Vec<String> = (drives.iter().map(|d| d.effort_name()))
        .chain(paths.iter().flat_map(driven_points::force_names))
        .collect();
    let names = output_names_of(prepared);
    let first = (names.iter())
        .position(|n| Some(n) == efforts.first())
        .unwrap_or_default();
    let samples = (simulation.samples.iter())
        .map(|sample| {
            let t = sample.time;
            let laws: Vec<_> = (drives.iter().map(|d| d.at(t)))
                .chain(paths.iter().flat_map(|p| p.at(t)))
                .collect();
            let efforts = sample.outputs[first..first + laws.len()].to_vec();
            let power = (efforts.iter().zip(&laws))
                .map(|(effort, law)| effort * law.rate)
                .sum();
            InverseSample {
                time: sample.time,
                positions: laws.iter().map(|l| l.position).collect(),
                rates: laws.iter().map(|l| l.rate).collect(),
                accelerations: laws.iter().map(|l| l.acceleration).collect(),
                efforts,
                power,
                reactions: sample.reactions.clone(),
            }
        })
        .collect();
    InverseDynamics {
        driven,
        efforts,
        reaction_names: reaction_names_of(prepared),
        samples,
        motion: None,
    }
}

impl InverseDynamics {
    /// As CSV: time, each driven coordinate, its rate and acceleration, each effort, the power,
    /// then six columns per join's reaction (`join.reaction.mx` … `join.reaction.fz`, as
    /// `simulate --reactions` names them).
    pub fn to_csv(&self) -> String {
        let mut header = vec!["time".to_string()];
        for (suffix, names) in [
            ("", &self.driven),
            ("'", &self.driven),
            ("''", &self.driven),
        ] {
            header.extend(names.iter().map(|n| format!("{n}{suffix}")));
        }
        header.extend(self.efforts.iter().cloned());
        header.push("power".to_string());
        for join in &self.reaction_names {
            let parts = ["mx", "my", "mz", "fx", "fy", "fz"];
            header.extend(parts.map(|c| format!("{join}.reaction.{c}")));
        }
        let mut text = header.join(",") + "\n";
        for s in &self.samples {
            let row: Vec<String> = std::iter::once(s.time)
                .chain(s.positions.iter().copied())
                .chain(s.rates.iter().copied())
                .chain(s.accelerations.iter().copied())
                .chain(s.efforts.iter().copied())
                .chain(std::iter::once(s.power))
                .chain(s.reactions.iter().copied())
                .map(|x| format!("{x:e}"))
                .collect();
            text += &(row.join(",") + "\n");
        }
        text
    }
}
