//! Random tree mechanisms as LSD programs: bodies with random inertias joined by a mix of the
//! standard joints, half of the joins written child first, so both traversals are exercised.
//! `featured_tree_program` gives the joints of one coordinate link features too.

pub const JOINTS: [&str; 11] = [
    "revolute([0.3, -0.5, 0.8])",
    "prismatic([1, 0, 0])",
    "helical([0, 0, 1], 0.05)",
    "cylindrical([0, 1, 0])",
    "universal([1, 0, 0], [0, 1, 0])",
    "spherical",
    "planar",
    "free",
    "link(a, b) dof1 = [a, sin(b), 0.2 * a * b], dof2 = (2 * b) || [1, 1, 0] end",
    "link(x, y, z) dof1 = x || [0, 0, 1], dof2 = y || [1, 0, 0], dof3 = z || [0, 0, 1] end",
    // Welded bodies are merged into their anchor by the recursions.
    "weld",
];

pub fn tree_program(parents: &[usize], kinds: &[usize], numbers: &[f64]) -> String {
    program(parents, numbers, |i| {
        JOINTS[kinds[i] % JOINTS.len()].to_string()
    })
}

/// The joints of one coordinate of `JOINTS` (revolute, prismatic, helical) written as links with
/// the features `features[i]` asks for: bit 0 a geared rotor (unless its carrier, the body of
/// the join's first frame, is welded to its parent, which the model refuses), bit 1 dry and viscous friction,
/// bit 2 a mimic of the first earlier join of one coordinate that is not itself a mimic
/// (none where there is no such join). The other kinds are the standard joints.
pub fn featured_tree_program(
    parents: &[usize],
    kinds: &[usize],
    features: &[usize],
    numbers: &[f64],
) -> String {
    let value = |k: usize| numbers[k % numbers.len()];
    let mut leaders = Vec::new();
    program(parents, numbers, |i| {
        let b = i + 1;
        let kind = kinds[i] % JOINTS.len();
        let dof = match kind {
            0 => "dof = q || [0.3, -0.5, 0.8]",
            1 => "dof = q * [1, 0, 0]",
            2 => "dof1 = (0.05 * q) * [0, 0, 1], dof2 = q || [0, 0, 1]",
            _ => return JOINTS[kind].to_string(),
        };
        let mut text = format!("link(q) {dof}");
        let feature = features[i];
        let carrier_welded =
            !child_first(b) && parents[i] != 0 && kinds[parents[i] - 1] % JOINTS.len() == 10;
        if feature & 1 != 0 && !carrier_welded {
            text += &format!(
                ", rotor_inertia = {}, gear_ratio = {}, rotor_axis = [{}, {}, {}]",
                0.01 + 0.1 * value(11 * b).abs(),
                3.0 * value(11 * b + 1),
                value(11 * b + 2),
                value(11 * b + 3),
                0.5 + value(11 * b + 4).abs(),
            );
        }
        if feature & 2 != 0 {
            text += &format!(
                ", friction = {}, damping = {}",
                value(11 * b + 5).abs(),
                value(11 * b + 6).abs()
            );
        }
        match leaders.first() {
            Some(leader) if feature & 4 != 0 => {
                text += &format!(
                    ", mimic = j{leader}, mimic_multiplier = {}, mimic_offset = {}",
                    value(11 * b + 7),
                    value(11 * b + 8)
                );
            }
            _ => leaders.push(b),
        }
        text + " end"
    })
}

/// Whether join `j{b}` is written with the child's frame first.
fn child_first(b: usize) -> bool {
    b.is_multiple_of(3)
}

fn program(parents: &[usize], numbers: &[f64], mut joint: impl FnMut(usize) -> String) -> String {
    let mut text = String::from("import joints;\n");
    let value = |k: usize| numbers[k % numbers.len()];
    for (i, _) in parents.iter().enumerate() {
        let b = i + 1;
        // Principal moments of a rigid body: sums of two of the non-negative second moments of
        // its mass about its principal planes, so that they satisfy the triangle inequality.
        let second = [7, 8, 9].map(|k| 0.1 + value(7 * b + k).abs());
        text += &format!(
            "let b{b} = body mass = {m}, iframe = [{x}, {y}, {z}] ++ ({a} || [{ax}, 1, {az}]), inertia = [{i1}, {i2}, {i3}] end;\n",
            m = 0.5 + value(7 * b).abs(),
            x = value(7 * b + 1),
            y = value(7 * b + 2),
            z = value(7 * b + 3),
            a = value(7 * b + 4),
            ax = value(7 * b + 5),
            az = value(7 * b + 6),
            i1 = second[1] + second[2],
            i2 = second[0] + second[2],
            i3 = second[0] + second[1],
        );
    }
    for (i, &p) in parents.iter().enumerate() {
        let b = i + 1;
        let parent = if p == 0 {
            "earth".to_string()
        } else {
            format!("b{p}")
        };
        let offset = format!(
            "[{}, {}, {}] ++ ({} || [1, 0, 0])",
            value(3 * b),
            value(3 * b + 1),
            value(3 * b + 2),
            value(5 * b)
        );
        // Alternate the direction of the join so both traversals are exercised.
        if child_first(b) {
            text += &format!(
                "join b{b} and {offset} @ {parent} with {} as j{b};\n",
                joint(i)
            );
        } else {
            text += &format!(
                "join {offset} @ {parent} and b{b} with {} as j{b};\n",
                joint(i)
            );
        }
    }
    text
}
