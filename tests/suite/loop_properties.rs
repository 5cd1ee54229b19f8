//! Property tests of the constrained dynamics over random mechanisms with loops: planar
//! four-bars of random proportions (closed by construction: the coupler-rocker point is the
//! intersection of two circles) and spatial Bennett linkages from random Denavit–Hartenberg
//! data (closed by the linkage's closed form). With RK4 and with dopri5: no failure, the loops
//! closed to round-off after projection, and the energy conserved (to 1e-7, or for RK4 with an
//! error that falls at its order when the step is halved).

use proptest::prelude::*;

use crate::common::programs::{constraints, prepared};
use lsdc::prepare::{Integrator, Prepared};
use lsdc::simulate::run::run;

/// A four-bar with ground l0, crank l1, coupler l2, rocker l3, assembled with the crank at
/// `crank` rad (C above the ground line), or None when the loop cannot close there.
pub(crate) fn four_bar(l: [f64; 4], crank: f64, rate: f64) -> Option<Prepared> {
    let b = (l[1] * crank.cos(), l[1] * crank.sin());
    let (dx, dy) = (l[0] - b.0, -b.1);
    let d = (dx * dx + dy * dy).sqrt();
    // C on the circles of radius l2 about B and l3 about D = (l0, 0).
    let along = (l[2] * l[2] - l[3] * l[3] + d * d) / (2.0 * d);
    let height2 = l[2] * l[2] - along * along;
    if height2 <= 1e-3 {
        return None;
    }
    let h = height2.sqrt();
    let c = (
        b.0 + along * dx / d - h * dy / d,
        b.1 + along * dy / d + h * dx / d,
    );
    let coupler = (c.1 - b.1).atan2(c.0 - b.0);
    let rocker = c.1.atan2(c.0 - l[0]);
    let initial = format!(
        "initial crank.q = {crank} fixed, coupler.q = {}, rocker.q = {rocker}, c.q = {}, crank.q' = {rate} ;",
        coupler - crank,
        rocker - coupler
    );
    Some(prepared(
        "four_bar",
        &[
            ("let l0 = 4.0 ;", &format!("let l0 = {} ;", l[0])),
            ("let l1 = 1.0 ;", &format!("let l1 = {} ;", l[1])),
            ("let l2 = 3.5 ;", &format!("let l2 = {} ;", l[2])),
            ("let l3 = 3.0 ;", &format!("let l3 = {} ;", l[3])),
            (
                "initial crank.q = 1.0, coupler.q = -0.36 guess, rocker.q = 1.79 guess, c.q = 1.15 guess ;",
                &initial,
            ),
        ],
    ))
}

/// A Bennett linkage with a1, alpha1, alpha2 (a2 from Bennett's condition), its crank at `crank`.
pub(crate) fn bennett(a1: f64, alpha1: f64, alpha2: f64, crank: f64, rate: f64) -> Prepared {
    prepared(
        "hard/bennett",
        &[
            ("let a1 = 1.0 ;", &format!("let a1 = {a1} ;")),
            ("let alpha1 = pi / 3 ;", &format!("let alpha1 = {alpha1} ;")),
            ("let alpha2 = pi / 2 ;", &format!("let alpha2 = {alpha2} ;")),
            (
                "initial j1.q = 1.0, j2.q = 2 * atan(K / tan(0.5)), j3.q = -1.0, j4.q = -2 * atan(K / tan(0.5)) ;",
                &format!(
                    "initial j1.q = {crank}, j2.q = 2 * atan(K / tan({h})), j3.q = {}, j4.q = -2 * atan(K / tan({h})) ;",
                    -crank,
                    h = crank / 2.0
                ),
            ),
            ("initial j1.q' = 2 ;", &format!("initial j1.q' = {rate} ;")),
        ],
    )
}

/// The random four-bars' draws: the lengths l0 to l3, the crank's angle and rate (`four_bar`,
/// which rejects those that do not close).
pub(crate) fn four_bar_draws() -> impl Strategy<Value = ([f64; 4], f64, f64)> {
    (
        proptest::array::uniform4(0.5f64..3.0),
        0.2f64..3.0,
        -3.0f64..3.0,
    )
}

/// The random Bennett linkages' draws: a1, alpha1, alpha2 (alpha1 and a gap), the crank's
/// angle and rate (`bennett`).
pub(crate) fn bennett_draws() -> impl Strategy<Value = (f64, f64, f64, f64, f64)> {
    (
        0.5f64..2.0,
        0.4f64..1.2,
        0.3f64..1.2,
        0.3f64..2.5,
        -3.0f64..3.0,
    )
        .prop_map(|(a1, alpha1, gap, crank, rate)| (a1, alpha1, alpha1 + gap, crank, rate))
}

/// Runs the mechanism for 0.3 s with RK4 (step 1e-3) and dopri5 (1e-10): both complete, the
/// loops stay closed and the energy is conserved.
fn holds(mut p: Prepared, label: &str) -> Result<(), TestCaseError> {
    p.settings.duration = 0.3;
    for (integrator, step) in [
        (Integrator::Rk4, Some(1e-3)),
        (Integrator::DormandPrince, None),
    ] {
        p.settings.integrator = integrator.clone();
        p.settings.step = step;
        p.settings.rtol = 1e-10;
        p.settings.atol = 1e-10;
        let simulation = run(&p, &mut |_| {});
        prop_assert!(
            simulation.report.failure.is_none(),
            "{label} {integrator:?}: {:?}",
            simulation.report.failure
        );
        let c = constraints(&simulation);
        prop_assert!(
            c.position_residual < 1e-10,
            "{label} {integrator:?}: residual {:e}",
            c.position_residual
        );
        let drift = simulation.report.energy_drift.expect("conservative");
        if drift >= 1e-7 && integrator == Integrator::Rk4 {
            // Near a singular configuration the motion is fast and RK4's error at this step
            // larger: it must then fall at the method's order when the step is halved.
            p.settings.step = Some(5e-4);
            let finer = run(&p, &mut |_| {})
                .report
                .energy_drift
                .expect("conservative");
            prop_assert!(
                finer < drift / 8.0,
                "{label} Rk4: energy drift {drift:e}, then {finer:e} at half the step"
            );
            continue;
        }
        prop_assert!(
            drift < 1e-7,
            "{label} {integrator:?}: energy drift {drift:e}"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_four_bars_stay_closed_and_conserve_energy((l, crank, rate) in four_bar_draws()) {
        let Some(p) = four_bar(l, crank, rate) else {
            return Err(TestCaseError::reject("does not close at this crank angle"));
        };
        holds(p, &format!("four-bar {l:?} at {crank}"))?;
    }

    #[test]
    fn random_bennett_linkages_stay_closed_and_conserve_energy(
        (a1, alpha1, alpha2, crank, rate) in bennett_draws(),
    ) {
        let p = bennett(a1, alpha1, alpha2, crank, rate);
        holds(p, &format!("Bennett a1 = {a1}, alpha = {alpha1}, {alpha2}, at {crank}"))?;
    }
}
