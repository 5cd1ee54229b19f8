//! Geared rotors on mechanisms with closed loops: the four-bar of `examples/four_bar.lsd` with a
//! geared crank against the same linkage with the rotor's reflected inertia written into the
//! crank, and the energy of a rotor carried by a moving body.

use crate::common::programs::{column, prepared, simulated};
use lsdc::simulate::run::Simulation;

const CRANK: &str = "join earth and bar1 with revolute([0, 0, 1]) as crank ;";
const COUPLER: &str = "join [l1, 0, 0] ++ 1 @ bar1 and bar2 with revolute([0, 0, 1]) as coupler ;";

fn four_bar(replacements: &[(&str, &str)]) -> Simulation {
    simulated(&prepared("four_bar", replacements))
}

/// The largest difference between two runs' declared coordinates over their samples.
fn largest_difference(a: &Simulation, b: &Simulation) -> f64 {
    assert_eq!(a.samples.len(), b.samples.len());
    (a.samples.iter().zip(&b.samples))
        .flat_map(|(x, y)| x.coordinates.iter().zip(&y.coordinates))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The largest change of kinetic + potential energy over a run.
fn energy_drift(simulation: &Simulation) -> f64 {
    let total = |s: &lsdc::simulate::run::Sample| {
        s.kinetic_energy + s.potential_energy.expect("a potential")
    };
    let first = total(&simulation.samples[0]);
    (simulation.samples.iter())
        .map(|s| (total(s) - first).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_geared_crank_carried_by_earth_moves_the_four_bar_as_its_reflected_inertia_does() {
    // A rotor on earth spins at n q̇ only: its energy ½ J n² q̇² is that of n² J = 0.1 kg m²
    // more about the crank's axis, which the second linkage writes into the crank's inertia
    // (a constant added to the central moment adds the same about the pivot; the moment about
    // x grows too, for the triangle inequality, and no motion turns about x).
    let geared = four_bar(&[(
        CRANK,
        "join earth and bar1 with geared_revolute([0, 0, 1], 10, 0.001) as crank ;",
    )]);
    let heavier = four_bar(&[(
        "let bar1 = bar(l1) ;",
        "let bar1 = body mass = l1, iframe = [l1 / 2, 0, 0] ++ 1, \
         inertia = [1e-4 * l1 + 0.1, l1 * l1 * l1 / 12, l1 * l1 * l1 / 12 + 0.1] end ;",
    )]);
    let plain = four_bar(&[]);
    let difference = largest_difference(&geared, &heavier);
    assert!(
        difference < 1e-10,
        "geared against heavier crank: {difference:e}"
    );
    // The rotor matters: without it the linkage moves otherwise.
    assert!(largest_difference(&geared, &plain) > 1e-2);
    assert!(energy_drift(&geared) < 1e-8, "{:e}", energy_drift(&geared));
}

#[test]
fn a_rotor_carried_by_the_crank_keeps_the_four_bar_s_energy() {
    // The coupler's motor sits on the crank: its spin q̇_crank + n q̇_coupler couples the two
    // coordinates, and the rotor's energy counts in the kinetic energy that is conserved.
    let geared = four_bar(&[(
        COUPLER,
        "join [l1, 0, 0] ++ 1 @ bar1 and bar2 with geared_revolute([0, 0, 1], 5, 0.002) as coupler ;",
    )]);
    let plain = four_bar(&[]);
    assert!(largest_difference(&geared, &plain) > 1e-2);
    let drift = energy_drift(&geared);
    assert!(drift < 1e-8, "energy drift {drift:e}");
    let crank = column(&geared, "crank.q");
    assert!(geared
        .samples
        .iter()
        .all(|s| s.coordinates[crank].is_finite()));
}
