//! Random tree mechanisms as LSD programs: bodies with random inertias joined by a mix of the
//! standard joints, half of the joins written child first, so both traversals are exercised.

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
        if b % 3 == 0 {
            text += &format!(
                "join b{b} and {offset} @ {parent} with {} as j{b};\n",
                JOINTS[kinds[i] % JOINTS.len()]
            );
        } else {
            text += &format!(
                "join {offset} @ {parent} and b{b} with {} as j{b};\n",
                JOINTS[kinds[i] % JOINTS.len()]
            );
        }
    }
    text
}
