//! The loops' count of allowed motions that move no mass (`Structure::massless`), which the
//! null-space method leaves at rest: decided from the bodies' inertias, not from a threshold on
//! the spectrum of the reduced mass matrix NᵀMN. A necklace whose rods' masses span ten orders
//! of magnitude has that spectrum spread beyond 1e10 though every rod has full inertia: it
//! counts no massless motion, and its accelerations by the null-space method agree with the
//! range-space method's (which does not read the count). The Delta's rod spins (a rod's spin
//! about its own axis between two ball joints) are still counted.

use crate::common::programs::{prepared, prepared_text};
use crate::long_chains::chains::necklace_program;
use crate::range_space::{largest_difference, mass_conditioning};
use lsdc::dynamics::algorithms::{crba, Data};
use lsdc::dynamics::loops::{constraints, Extent, Factored, Structure};
use lsdc::prepare::Prepared;

/// The necklace of 8 rods (`necklace_program`) with rods 3 to 5 of mass 1e-5 and the others
/// of mass 1e5 (each rod's inertia scaled with its mass): the light rods close a four-bar on
/// the heavy ones, whose motion carries ten orders of magnitude less inertia than the others.
fn spread_necklace() -> Prepared {
    let mut text = necklace_program(8);
    for i in 1..=8 {
        let mass = if (3..=5).contains(&i) { "1e-5" } else { "1e5" };
        text = text.replace(
            &format!("let rod{i} = bar(1.0) ;"),
            &format!(
                "let rod{i} = body mass = {mass}, iframe = [0.5, 0, 0] ++ 1, \
                 inertia = [1e-4 * {mass}, {mass} / 12, {mass} / 12] end ;"
            ),
        );
    }
    prepared_text(&text)
}

/// The structure decided at `prepared`'s initial configuration, and the spread (largest over
/// smallest eigenvalue) of NᵀMN on an orthonormal basis N of the kept rows' allowed motions.
fn structure_and_spread(prepared: &Prepared) -> (Structure, f64) {
    let model = &prepared.model;
    let mut data = Data::new(model);
    let (q, v) = (model)
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("state");
    let structure = Structure::decide(model, &mut data, &q).expect("structure");
    let c = constraints(model, &mut data, &q, &v, Extent::Rows).expect("constraints");
    let allowed = Factored::new(&c.jacobian, &structure.choice)
        .dense_null_space()
        .clone();
    let tree = crba(model, &mut data, &q[..model.nq]).expect("mass");
    let mut mass = nalgebra::DMatrix::zeros(allowed.nrows(), allowed.nrows());
    mass.view_mut((0, 0), tree.shape()).copy_from(&tree);
    let values = (allowed.transpose() * mass * &allowed).symmetric_eigenvalues();
    (structure, values.max() / values.min())
}

#[test]
fn a_spread_of_masses_counts_no_massless_motion_and_the_null_space_method_moves_them_all() {
    let necklace = spread_necklace();
    let (structure, spread) = structure_and_spread(&necklace);
    assert!(
        spread > 1e10,
        "the reduced mass matrix's spread: {spread:e}"
    );
    // Both methods, the null-space one forced, along a motion: they agree to what the mass
    // matrix's conditioning makes of round-off (`range_space::AGREEMENT`'s rule); a motion left
    // at rest would differ by the light rods' accelerations, of the order of the largest.
    let difference = largest_difference(&necklace, false, 10, 1e-4);
    let bound = 1e-12 + f64::EPSILON * mass_conditioning(&necklace);
    assert!(
        difference <= bound,
        "the two methods differ by {difference:e} (bound {bound:e})"
    );
    assert_eq!(structure.massless, 0, "every rod has full inertia");
}

#[test]
fn the_delta_counts_its_six_rod_spins() {
    // Six rods, each between two ball joints, each spinning about its own axis without moving
    // mass (examples/delta_isir88.lsd: mobility 9, 6 of it the spins). The angles of the five
    // complementary balls are idle (allowed, massless, left at rest without being solved);
    // the six spins are the solved motions without mass.
    let (structure, spread) = structure_and_spread(&prepared("delta_isir88", &[]));
    assert_eq!(
        (structure.massless, structure.idle.len()),
        (6, 15),
        "spread {spread:e}"
    );
}
