//! The columns a plot draws when the user chooses them (`lsdc simulate --plot-columns`): names
//! of the samples' CSV header (a coordinate, its rate `name'`, `kinetic_energy`,
//! `potential_energy`, an output), in panels of their own, found before the run so that a
//! misspelt name stops it with a suggestion rather than after it.

use std::fmt;

use crate::diag::suggest::did_you_mean;
use crate::simulate::run::Sample;

/// One chosen column: its name and where a sample holds its value.
#[derive(Clone, Debug)]
pub struct Column {
    pub name: String,
    place: Place,
}

#[derive(Clone, Copy, Debug)]
enum Place {
    Coordinate(usize),
    Rate(usize),
    KineticEnergy,
    PotentialEnergy,
    Output(usize),
}

impl Column {
    /// The column's value in `sample` (none for a potential energy the sample does not know).
    pub fn value(&self, sample: &Sample) -> Option<f64> {
        match self.place {
            Place::Coordinate(i) => sample.coordinates.get(i).copied(),
            Place::Rate(i) => sample.rates.get(i).copied(),
            Place::KineticEnergy => Some(sample.kinetic_energy),
            Place::PotentialEnergy => sample.potential_energy,
            Place::Output(i) => sample.outputs.get(i).copied(),
        }
    }
}

/// A name that is no column of the samples, with the closest one.
#[derive(Debug, PartialEq)]
pub struct UnknownColumn {
    pub name: String,
    pub suggestion: Option<String>,
}

impl fmt::Display for UnknownColumn {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "`--plot-columns`: no column `{}` in the samples",
            self.name
        )?;
        if let Some(suggestion) = &self.suggestion {
            write!(f, "; did you mean `{suggestion}`?")?;
        }
        write!(
            f,
            "\n  = help: a column is named as in the samples' CSV header: a coordinate, its rate \
             (`name'`), `kinetic_energy`, `potential_energy` or an output; names are separated \
             by commas, and each `--plot-columns` draws one panel"
        )
    }
}

/// The panels of the chosen columns: one per `--plot-columns` value, its names separated by
/// commas (spaces around them ignored; empty names, and panels without a name, skipped).
pub fn resolve(
    coordinate_names: &[String],
    output_names: &[String],
    panels: &[String],
) -> Result<Vec<Vec<Column>>, UnknownColumn> {
    let rate_names: Vec<String> = coordinate_names.iter().map(|n| format!("{n}'")).collect();
    let named = |names: &[String], place: fn(usize) -> Place| {
        (names.iter().enumerate())
            .map(move |(i, name)| (name.clone(), place(i)))
            .collect::<Vec<_>>()
    };
    let columns: Vec<(String, Place)> = named(coordinate_names, Place::Coordinate)
        .into_iter()
        .chain(named(&rate_names, Place::Rate))
        .chain([
            ("kinetic_energy".to_string(), Place::KineticEnergy),
            ("potential_energy".to_string(), Place::PotentialEnergy),
        ])
        .chain(named(output_names, Place::Output))
        .collect();
    let find = |name: &str| {
        (columns.iter().find(|(n, _)| n == name))
            .map(|(n, place)| Column {
                name: n.clone(),
                place: *place,
            })
            .ok_or_else(|| UnknownColumn {
                name: name.to_string(),
                suggestion: did_you_mean(name, columns.iter().map(|(n, _)| n.as_str()))
                    .map(str::to_string),
            })
    };
    let mut resolved = Vec::new();
    for panel in panels {
        let names = panel.split(',').map(str::trim).filter(|n| !n.is_empty());
        let columns = names.map(find).collect::<Result<Vec<_>, _>>()?;
        if !columns.is_empty() {
            resolved.push(columns);
        }
    }
    Ok(resolved)
}
