//! The simulator's right-hand side and projection allocate nothing once their scratch is sized,
//! on every example: the test binary's allocator counts the allocations of each thread
//! (`benches/common/counting.rs`, shared with `cargo bench --bench allocations`), and one
//! derivative and one projection at each example's initial state, after two of each have sized
//! every buffer, must make none.

#[path = "../../benches/common/counting.rs"]
mod counting;
use counting::allocations;

#[test]
fn derivatives_and_projections_allocate_nothing_on_every_example() {
    let (mut counted, mut contacts_and_rotors) = (0, 0);
    let mut allocating = Vec::new();
    let mut mimics = 0;
    for file in counting::examples() {
        let Some((_, derivative, projection)) = counting::per_evaluation(&file) else {
            continue;
        };
        let projection = projection.unwrap_or(0);
        if derivative + projection > 0 {
            allocating.push(format!(
                "{}: {derivative} per derivative, {projection} per projection",
                file.display()
            ));
        }
        counted += 1;
        let name = file.to_string_lossy();
        if name.contains("rolling_") || name.ends_with("geared_arm.lsd") {
            contacts_and_rotors += 1;
        }
        mimics += usize::from(name.ends_with("meshed_gears.lsd"));
        mimics += usize::from(name.ends_with("four_bar_mimic.lsd"));
    }
    assert!(counted >= 20, "only {counted} examples counted");
    assert!(
        contacts_and_rotors >= 3,
        "the examples with contacts or geared rotors were not counted"
    );
    assert_eq!(
        mimics, 2,
        "the examples with mimic couplings were not counted"
    );
    assert!(allocating.is_empty(), "allocations: {allocating:#?}");
}

#[test]
fn the_counter_counts() {
    // The test above could not fail if the counter saw nothing.
    let made = allocations(|| {
        std::hint::black_box(vec![1.0_f64; 16]);
    });
    assert_eq!(made, 1);
}

/// A coordinate resting on its stop adds a held row to a tree's right-hand side: holding it
/// allocates nothing either, once the held rows are sized (with the articulated-body algorithm,
/// and with the mass matrix that joint friction needs, sticking on another coordinate).
#[test]
fn holding_a_coordinate_on_its_stop_allocates_nothing() {
    use lsdc::dynamics::friction::Phase;
    use lsdc::simulate::system::MechanicalSystem;
    let pendulum = "import joints;\n\
        let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;\n\
        let tip = body mass = 0.3, iframe = [0, 0, -0.2] ++ 1, inertia = [0.01, 0.01, 0.001] end;\n\
        join earth and rod with limited_revolute([1, 0, 0], 0.3, pi, 0) as swing;\n\
        join [0, 0, -1] ++ 1 @ rod and tip with JOINT as wrist;\n\
        apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;\n\
        initial swing.q = 0.3;\n";
    let joints = [
        "revolute([1, 0, 0])",
        "friction_revolute([1, 0, 0], 5, 0.1)",
    ];
    for joint in joints {
        let text = pendulum.replace("JOINT", joint);
        let prepared = super::common::programs::prepared_text(&text);
        let model = &prepared.model;
        let y = super::common::programs::initial_state(&prepared);
        let reference = prepared.coordinates.clone();
        let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
        system.state.resting[0] = true;
        system
            .state
            .phases
            .iter_mut()
            .for_each(|p| *p = Phase::Sticking);
        let mut dydt = vec![0.0; y.len()];
        for _ in 0..2 {
            system.derivative(0.0, &y, &mut dydt).expect("derivative");
        }
        assert!(dydt[y.len() / 2].abs() < 1e-14, "held: {dydt:?}");
        assert!(system.scratch.contact[0] > 0.0);
        let made = allocations(|| {
            let _ = system.derivative(0.0, &y, &mut dydt);
        });
        assert_eq!(made, 0, "{joint}: {made} allocations per derivative");
    }
}

/// A chain of `n` links in URDF: revolute joints about alternating axes, each link 0.5 m long.
fn urdf_chain(n: usize) -> String {
    let mut text =
        String::from("<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n<link name=\"base\"/>\n");
    for i in 1..=n {
        text += &format!(
            "<link name=\"l{i}\"><inertial><origin xyz=\"0.25 0 0\"/><mass value=\"1.5\"/>\
             <inertia ixx=\"0.01\" iyy=\"0.02\" izz=\"0.02\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n"
        );
        let (parent, offset) = match i {
            1 => ("base".to_string(), "0 0 0"),
            _ => (format!("l{}", i - 1), "0.5 0 0"),
        };
        let axis = if i % 2 == 1 { "0 0 1" } else { "0 1 0" };
        text += &format!(
            "<joint name=\"j{i}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"l{i}\"/>\
             <origin xyz=\"{offset}\"/><axis xyz=\"{axis}\"/>\
             <limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint>\n"
        );
    }
    text + "</robot>\n"
}

/// The most bytes held at once while a chain of `n` links read from URDF is prepared and
/// simulated for 10 ms (dopri5, the stiffness check on, outputs every 5 ms).
fn urdf_chain_peak_bytes(n: usize) -> usize {
    let dir = std::env::temp_dir().join(format!("lsdc-allocations-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let path = dir.join(format!("chain{n}.urdf"));
    std::fs::write(&path, urdf_chain(n)).expect("writes the URDF file");
    let bytes = counting::peak_bytes(|| {
        let mut prepared = crate::common::programs::prepared_file(path.to_str().expect("UTF-8"));
        prepared.settings.duration = 0.01;
        prepared.settings.output = 0.005;
        let simulation = lsdc::simulate::run::run(&prepared, &mut |_| {});
        assert!(
            simulation.report.failure.is_none(),
            "{:?}",
            simulation.report.failure
        );
    });
    std::fs::remove_file(&path).expect("removes the URDF file");
    bytes
}

/// A tree's run holds no matrix of its velocities squared (the mimic couplings' basis, the mass
/// matrix, the reduced equations' storage, the rows of each branch): quadrupling a URDF chain's
/// length at most quadruples, with a fifth for what does not grow with it, the memory its
/// preparation and run hold at once. `lsdc simulate` of the same chains for 10 ms under
/// heaptrack peaked at 4.2 MB and 38.4 MB before (9.1 times), 2.4 MB and 9.4 MB after (3.9).
#[test]
fn a_long_chain_from_urdf_runs_in_memory_linear_in_its_length() {
    let (short, long) = (urdf_chain_peak_bytes(150), urdf_chain_peak_bytes(600));
    let growth = long as f64 / short as f64;
    assert!(
        growth < 4.8,
        "150 links: {short} bytes, 600 links: {long} bytes ({growth:.2} times)"
    );
}
