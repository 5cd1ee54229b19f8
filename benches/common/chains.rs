//! Long closed chains for the loops' scaling benchmark (`loop_scaling`) and their tests
//! (`tests/suite/long_chains.rs`): the necklace, one loop of N rods hanging between two pivots
//! on the ground (mobility N − 2), and the ladder, N parallelograms between a beam swinging
//! from the ground and a rail of N segments, each loop sharing its rungs with its neighbours
//! and all of them the beam (mobility 2).

/// The rods' and rungs' body, as in the rows (`rows.rs`): a bar of length `l` along its x axis.
const PREAMBLE: &str = "import joints ;\nimport gravity ;\nlet z = [0, 0, 1] ;\n\
    let down = [0, -9.81, 0] ;\n\
    let bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;\n";

/// The necklace of `n` rods of length 1 between pivots at the origin and on the x axis, started
/// at rest on a circular arc (rod i at the angle −β + (i − 1)·2β/(n − 1) from the x axis, β = π/3),
/// which is not its equilibrium: it swings.
pub fn necklace_program(n: usize) -> String {
    necklace_of_rods(n, 1.0)
}

/// `necklace_program` with rods of `length` (metres, a whole number): the same shape scaled,
/// whose extent brings the round-off of a long chain's closure to small N.
pub fn necklace_of_rods(n: usize, length: f64) -> String {
    assert!(n >= 3, "a necklace of fewer than 3 rods does not move");
    let beta = std::f64::consts::FRAC_PI_3;
    let turn = 2.0 * beta / (n - 1) as f64;
    let span: f64 = (0..n).map(|i| (-beta + i as f64 * turn).cos()).sum::<f64>() * length;
    let mut text = String::from(PREAMBLE);
    let mut initial = vec![format!("c1.q = {:.17}", -beta)];
    for i in 1..=n {
        text += &format!("let rod{i} = bar({length:.1}) ;\n");
        if i == 1 {
            text += "join earth and rod1 with revolute(z) as c1 ;\n";
        } else {
            text += &format!(
                "join [{length:.1}, 0, 0] ++ 1 @ rod{} and rod{i} with revolute(z) as p{i} ;\n",
                i - 1
            );
            initial.push(format!("p{i}.q = {turn:.17}"));
        }
        text += &format!("apply weight_in(rod{i}, down) on rod{i}.iframe ;\n");
    }
    text += &format!(
        "join [{length:.1}, 0, 0] ++ 1 @ rod{n} and [{span:.17}, 0, 0] ++ 1 @ earth with revolute(z) as e ;\n"
    );
    initial.push(format!("e.q = {:.17}", -beta));
    text += &format!("initial {} ;\n", initial.join(", "));
    text
}

/// The ladder of `n` loops: a beam of length n swinging about its end on the ground, n + 1
/// rungs of length 1/2 hinged along it 1 apart, and a rail of n segments of length 1, segment i
/// hinged on rung i − 1 and closing a parallelogram on rung i. Each loop shares its rungs with
/// its neighbours, and every loop hangs from the beam: its cycle (rail segment, two rungs) closes
/// on the beam, not on the ground. Started at rest with the beam level and the rungs 0.3 rad
/// off the vertical: it falls and swings.
pub fn ladder_program(n: usize) -> String {
    let mut text = String::from(PREAMBLE);
    text += &format!("let beam = bar({n}.0) ;\njoin earth and beam with revolute(z) as swing ;\n");
    text += "apply weight_in(beam, down) on beam.iframe ;\n";
    let rung = -std::f64::consts::FRAC_PI_2 + 0.3;
    let mut initial = vec!["swing.q = 0 fixed".to_string()];
    for i in 0..=n {
        text += &format!("let rung{i} = bar(0.5) ;\n");
        text += &format!("join [{i}.0, 0, 0] ++ 1 @ beam and rung{i} with revolute(z) as r{i} ;\n");
        text += &format!("apply weight_in(rung{i}, down) on rung{i}.iframe ;\n");
        initial.push(match i {
            0 => format!("r0.q = {rung:.17} fixed"),
            _ => format!("r{i}.q = {rung:.17}"),
        });
    }
    for i in 1..=n {
        text += &format!("let rail{i} = bar(1.0) ;\n");
        text += &format!(
            "join [0.5, 0, 0] ++ 1 @ rung{} and rail{i} with revolute(z) as s{i} ;\n",
            i - 1
        );
        text += &format!("apply weight_in(rail{i}, down) on rail{i}.iframe ;\n");
        text += &format!(
            "join [1.0, 0, 0] ++ 1 @ rail{i} and [0.5, 0, 0] ++ 1 @ rung{i} with revolute(z) as e{i} ;\n"
        );
        initial.push(format!("s{i}.q = {:.17}", -rung));
        initial.push(format!("e{i}.q = {rung:.17}"));
    }
    text += &format!("initial {} ;\n", initial.join(", "));
    text
}
