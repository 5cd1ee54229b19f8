//! Plots of a simulation (being written).

pub fn plot(_simulation: &crate::simulate::run::Simulation, _path: &std::path::Path) -> Result<(), String> {
    Err("plots are not available yet".to_string())
}
