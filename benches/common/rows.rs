//! The row of N parallelogram four-bars (the programs of `examples/hard/four_bar_row_N.lsd`,
//! generated here for any N), with or without its closing joins: the loops benchmarks' case
//! (`loop_scaling`) and the peers' (`peers`, beside MuJoCo's model of the same row written by
//! `bench/peers.py`).

/// The row of `n` four-bars, with its closing joins or without them.
pub fn row_program(n: usize, closed: bool) -> String {
    let mut text = String::from(
        "import joints ;\nimport gravity ;\nlet R = 0.5 ;\nlet L = 1.0 ;\nlet z = [0, 0, 1] ;\n\
         let down = [0, -9.81, 0] ;\n\
         let bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;\n",
    );
    for i in 0..=n {
        text += &format!("let crank{i} = bar(R) ;\n");
        text +=
            &format!("join [{i} * L, 0, 0] ++ 1 @ earth and crank{i} with revolute(z) as c{i} ;\n");
        text += &format!("apply weight_in(crank{i}, down) on crank{i}.iframe ;\n");
    }
    let mut initial = vec!["c0.q = -pi / 2 fixed".to_string()];
    for i in 1..=n {
        text += &format!("let rod{i} = bar(L) ;\n");
        text += &format!(
            "join [R, 0, 0] ++ 1 @ crank{} and rod{i} with revolute(z) as p{i} ;\n",
            i - 1
        );
        text += &format!("apply weight_in(rod{i}, down) on rod{i}.iframe ;\n");
        initial.push(format!("c{i}.q = -pi / 2"));
        initial.push(format!("p{i}.q = pi / 2"));
        if closed {
            text += &format!(
                "join [L, 0, 0] ++ 1 @ rod{i} and [R, 0, 0] ++ 1 @ crank{i} with revolute(z) as e{i} ;\n"
            );
            initial.push(format!("e{i}.q = -pi / 2"));
        }
    }
    text += &format!("initial {} ;\ninitial c0.q' = 12.0 ;\n", initial.join(", "));
    text
}
