//! `lsdc export-urdf`: the URDF of the examples read back with urdf-rs, its structure, and an
//! independent check that composing its origins and joint motions gives the bodies' poses and
//! inertias of lsdc's own forward kinematics.

use std::collections::HashMap;
use std::process::Command;

use nalgebra::{Matrix3, Matrix6, Point3, Translation3, UnitQuaternion, Vector3};

use lsdc::driver::{compile_files, compile_text, Compilation};
use lsdc::dynamics::algorithms::{forward_kinematics, Data};
use lsdc::dynamics::joint::{quaternion, JointType};
use lsdc::load::LoadOptions;
use lsdc::output::urdf::{export_urdf, link_frames, ExportError, NO_LIMIT};
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::spatial::{inertia_to_parent, skew, Pose};

fn options() -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    }
}

fn prepared(compilation: Compilation) -> Prepared {
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    prepare(&mechanism, &[], &Settings::default()).unwrap_or_else(|d| panic!("{d:?}"))
}

fn example(name: &str) -> Prepared {
    let path = format!("{}/examples/{name}.lsd", env!("CARGO_MANIFEST_DIR"));
    prepared(compile_files(&[path.into()], &options()).expect("reads the example"))
}

fn program(text: &str) -> Prepared {
    prepared(compile_text("test.lsd", text, None, &options()))
}

/// The URDF text and what urdf-rs reads from it.
fn exported(prepared: &Prepared) -> (String, urdf_rs::Robot) {
    let text = export_urdf(&prepared.model, "robot").unwrap_or_else(|e| panic!("{e}"));
    let robot = urdf_rs::read_from_string(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    (text, robot)
}

fn joint<'a>(robot: &'a urdf_rs::Robot, name: &str) -> &'a urdf_rs::Joint {
    robot
        .joints
        .iter()
        .find(|j| j.name == name)
        .unwrap_or_else(|| panic!("no joint `{name}`"))
}

fn link<'a>(robot: &'a urdf_rs::Robot, name: &str) -> &'a urdf_rs::Link {
    robot
        .links
        .iter()
        .find(|l| l.name == name)
        .unwrap_or_else(|| panic!("no link `{name}`"))
}

fn names<T>(items: &[T], name: impl Fn(&T) -> &str) -> Vec<&str> {
    items.iter().map(name).collect()
}

#[test]
fn the_double_pendulum_is_two_continuous_joints() {
    let (_, robot) = exported(&example("double_pendulum"));
    assert_eq!(robot.name, "robot");
    assert_eq!(
        names(&robot.links, |l| &l.name),
        ["earth", "upper", "lower"]
    );
    assert_eq!(names(&robot.joints, |j| &j.name), ["shoulder", "elbow"]);
    for (name, parent, child, z) in [
        ("shoulder", "earth", "upper", 0.0),
        ("elbow", "upper", "lower", -1.0),
    ] {
        let j = joint(&robot, name);
        assert_eq!(j.joint_type, urdf_rs::JointType::Continuous);
        assert_eq!(
            (j.parent.link.as_str(), j.child.link.as_str()),
            (parent, child)
        );
        assert_eq!(j.axis.xyz.0, [1.0, 0.0, 0.0]);
        assert_eq!(j.origin.xyz.0, [0.0, 0.0, z]);
        assert_eq!(j.origin.rpy.0, [0.0; 3]);
    }
    let upper = &link(&robot, "upper").inertial;
    assert_eq!(upper.mass.value, 1.0);
    assert_eq!(upper.origin.xyz.0, [0.0, 0.0, -0.5]);
    assert!((upper.inertia.ixx - 1.0 / 12.0).abs() < 1e-15 && upper.inertia.izz == 0.0);
    assert_eq!(link(&robot, "lower").inertial.mass.value, 0.8);
}

#[test]
fn the_satellite_floats_and_slides() {
    let (text, robot) = exported(&example("satellite_numeric"));
    assert_eq!(
        names(&robot.links, |l| &l.name),
        [
            "earth",
            "satellite",
            "bras_primaire",
            "bras_secondaire",
            "reflecteur"
        ]
    );
    let types: Vec<_> = robot
        .joints
        .iter()
        .map(|j| (j.name.as_str(), j.joint_type.clone()))
        .collect();
    use urdf_rs::JointType::{Continuous, Floating, Prismatic};
    assert_eq!(
        types,
        [
            ("base", Floating),
            ("hinge", Continuous),
            ("slide", Prismatic),
            ("tilt", Continuous)
        ]
    );
    assert_eq!(joint(&robot, "hinge").origin.xyz.0, [0.0, 0.0, 0.8]);
    assert_eq!(joint(&robot, "hinge").axis.xyz.0, [1.0, 0.0, 0.0]);
    let slide = joint(&robot, "slide");
    assert_eq!(slide.axis.xyz.0, [0.0, 1.0, 0.0]);
    assert_eq!(
        (
            slide.limit.lower,
            slide.limit.upper,
            slide.limit.effort,
            slide.limit.velocity
        ),
        (-NO_LIMIT, NO_LIMIT, NO_LIMIT, NO_LIMIT)
    );
    assert_eq!(joint(&robot, "tilt").axis.xyz.0, [0.0, 1.0, 0.0]);
    assert_eq!(link(&robot, "satellite").inertial.mass.value, 1200.0);
    assert_eq!(link(&robot, "satellite").inertial.inertia.iyy, 1100.0);
    assert_eq!(
        link(&robot, "reflecteur").inertial.origin.xyz.0,
        [0.0, 0.0, 0.5]
    );
    // Massless bodies have no <inertial>; joints without an axis or limits have none written.
    assert!(
        text.contains("<link name=\"bras_primaire\"/>")
            && text.contains("<link name=\"bras_secondaire\"/>")
    );
    assert_eq!(text.matches("<limit").count(), 1);
    assert_eq!(text.matches("<axis").count(), 3);
}

#[test]
fn mechanisms_with_loops_are_refused() {
    let prepared = example("four_bar");
    let error = export_urdf(&prepared.model, "four_bar").expect_err("four_bar has a loop");
    assert_eq!(error, ExportError::Loops(vec!["c".to_string()]));
    assert_eq!(
        error.message("four_bar.lsd"),
        "URDF describes trees: four_bar.lsd has complementary link c (it closes a loop)"
    );
}

/// Several coordinates per join: planar, universal, a spherical joint written from the child,
/// a weld at gimbal lock (pitch π/2), and a chain with constant steps, an offset and a reversed
/// coordinate.
const EXPANDED: &str = "import joints ;
let base = body mass = 2, iframe = [0.1, 0.2, 0.3] ++ (0.4 || [1, 2, 3]), inertia = [0.5, 0.6, 0.7] end ;
let arm = body mass = 1.5, iframe = [0.3, -0.1, 0.2] ++ (1.1 || [0, 1, 1]), inertia = [0.2, 0.3, 0.25] end ;
let hand = body mass = 0.7, iframe = [0, 0.05, 0.1] ++ 1, inertia = [0.01, 0.02, 0.03] end ;
let spacer = body mass = 0, inertia = 0 end ;
let tool = body mass = 0.3, iframe = [0.02, 0, 0] ++ (2 || [1, 0, 0]), inertia = [0.001, 0.002, 0.002] end ;
join [0.5, 0, 0.2] ++ (0.3 || [0, 0, 1]) @ earth and base with planar as floor ;
join [0, 0, 0.4] ++ 1 @ base and [0.1, 0, 0] ++ (0.2 || [1, 0, 0]) @ arm with universal([0, 0, 1], [0, 1, 0]) as shoulder ;
join [0.2, 0.1, 0] ++ (0.5 || [0, 1, 0]) @ hand and [0.6, 0, 0] ++ 1 @ arm with spherical as wrist ;
join [0.05, 0, 0] ++ (pi / 2 || [0, 1, 0]) @ hand and spacer with weld as mount ;
join spacer and tool with link(q, d)
  dof1 = (0.3 - q) || [1, 1, 0], dof2 = [0, 0.25, 0], dof3 = [0, d, 0], dof4 = 0.7 || [0, 0, 1]
end as twist ;
";

#[test]
fn joins_of_several_coordinates_become_chains_of_joints() {
    let (text, robot) = exported(&program(EXPANDED));
    let joints: Vec<_> = robot
        .joints
        .iter()
        .map(|j| {
            (
                j.name.as_str(),
                j.parent.link.as_str(),
                j.child.link.as_str(),
            )
        })
        .collect();
    assert_eq!(
        joints,
        [
            ("floor.x", "earth", "floor.x"),
            ("floor.y", "floor.x", "floor.y"),
            ("floor.q", "floor.y", "base"),
            ("shoulder.a", "base", "shoulder.a"),
            ("shoulder.b", "shoulder.a", "arm"),
            // Written from the hand, the wrist moves the hand by its chain undone: c, b, a.
            ("wrist.c", "arm", "wrist.c"),
            ("wrist.b", "wrist.c", "wrist.b"),
            ("wrist.a", "wrist.b", "hand"),
            ("mount", "hand", "spacer"),
            ("twist.q", "spacer", "twist.q"),
            ("twist.d", "twist.q", "tool"),
        ]
    );
    assert_eq!(joint(&robot, "wrist.c").axis.xyz.0, [0.0, 0.0, -1.0]);
    assert_eq!(joint(&robot, "mount").joint_type, urdf_rs::JointType::Fixed);
    let twist = joint(&robot, "twist.q").axis.xyz.0;
    assert!(
        (Vector3::from(twist) + Vector3::new(1.0, 1.0, 0.0).normalize()).norm() < 1e-15,
        "{twist:?}"
    );
    for intermediate in [
        "floor.x",
        "floor.y",
        "shoulder.a",
        "wrist.c",
        "wrist.b",
        "twist.q",
    ] {
        assert!(
            text.contains(&format!("<link name=\"{intermediate}\"/>")),
            "{intermediate} has no mass"
        );
    }
    assert!(text.contains("<link name=\"spacer\"/>"));
    assert_eq!(robot.links.len(), 12);
}

fn refusal(text: &str) -> String {
    let prepared = program(&format!(
        "import joints ;\nlet b = body mass = 1, iframe = 0, inertia = [1, 1, 1] end ;\n{text}"
    ));
    export_urdf(&prepared.model, "robot")
        .expect_err("cannot be written")
        .to_string()
}

#[test]
fn steps_without_a_urdf_joint_are_refused_by_join_and_step() {
    assert_eq!(
        refusal("join earth and b with helical([0, 0, 1], 1) as screw ;"),
        "join `screw` cannot be written as URDF joints: step 2 of its dof chain moves `q`, which step 1 moves too: a URDF joint has a coordinate of its own"
    );
    assert_eq!(
        refusal("join earth and b with link(q) dof = (q ^ 2) || [0, 0, 1] end as bent ;"),
        "join `bent` cannot be written as URDF joints: step 1 of its dof chain uses the coordinate `q` in a nonlinear expression"
    );
    assert_eq!(
        refusal("join earth and b with link(u, v) dof1 = [0, 0, 1], dof2 = (u + v) || [0, 0, 1] end as sum ;"),
        "join `sum` cannot be written as URDF joints: step 2 of its dof chain has an expression of two coordinates, `u` and `v`"
    );
    assert_eq!(
        refusal("join earth and b with prismatic([0, 0, 2]) as long ;"),
        "join `long` cannot be written as URDF joints: step 1 of its dof chain moves 2 per unit of `q`: a URDF joint moves 1 per unit of its coordinate"
    );
}

// ---------------------------------------------------------------------------------------------
// The numeric check: URDF poses composed here against lsdc's forward kinematics.

const TOLERANCE: f64 = 1e-12;

/// R = Rz(yaw)·Ry(pitch)·Rx(roll), as URDF defines rpy.
fn rpy_rotation(rpy: &urdf_rs::Vec3) -> UnitQuaternion<f64> {
    let about = |axis: Vector3<f64>, angle: f64| {
        UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle)
    };
    about(Vector3::z(), rpy[2]) * about(Vector3::y(), rpy[1]) * about(Vector3::x(), rpy[0])
}

fn origin(pose: &urdf_rs::Pose) -> Pose {
    Pose::from_parts(
        Translation3::from(Vector3::from(pose.xyz.0)),
        rpy_rotation(&pose.rpy),
    )
}

/// The motion of a URDF joint at position `q`, or at the rigid motion `floating`.
fn motion(joint: &urdf_rs::Joint, q: f64, floating: Option<Pose>) -> Pose {
    let axis = Vector3::from(joint.axis.xyz.0).normalize();
    match joint.joint_type {
        urdf_rs::JointType::Continuous | urdf_rs::JointType::Revolute => Pose::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_scaled_axis(axis * q),
        ),
        urdf_rs::JointType::Prismatic => {
            Pose::from_parts(Translation3::from(axis * q), UnitQuaternion::identity())
        }
        urdf_rs::JointType::Floating => floating.expect("a floating joint's motion"),
        _ => Pose::identity(),
    }
}

/// World poses of the links: child = parent · origin · motion, from the root `earth`.
fn link_poses(
    robot: &urdf_rs::Robot,
    position: impl Fn(&urdf_rs::Joint) -> (f64, Option<Pose>),
) -> HashMap<String, Pose> {
    let mut poses = HashMap::from([("earth".to_string(), Pose::identity())]);
    while poses.len() < robot.links.len() {
        let before = poses.len();
        for joint in &robot.joints {
            let Some(parent) = poses.get(&joint.parent.link).copied() else {
                continue;
            };
            let (q, floating) = position(joint);
            poses
                .entry(joint.child.link.clone())
                .or_insert(parent * origin(&joint.origin) * motion(joint, q, floating));
        }
        assert!(poses.len() > before, "links unreachable from earth");
    }
    poses
}

/// Spatial inertia about the world origin, in world axes, of a link's `<inertial>`.
fn world_inertia(link: &urdf_rs::Link, pose: &Pose) -> Matrix6<f64> {
    let inertial = &link.inertial;
    let m = inertial.mass.value;
    let i = &inertial.inertia;
    let tensor = Matrix3::new(
        i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
    );
    let frame = pose * origin(&inertial.origin);
    let r = frame.rotation.to_rotation_matrix().into_inner();
    let c = skew(&frame.transform_point(&Point3::origin()).coords);
    let mut spatial = Matrix6::zeros();
    spatial
        .fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(r * tensor * r.transpose() - m * c * c));
    spatial.fixed_view_mut::<3, 3>(0, 3).copy_from(&(m * c));
    spatial.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-m * c));
    spatial
        .fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(Matrix3::identity() * m));
    spatial
}

/// xorshift64*: reproducible pseudo-random numbers in [-3, 3).
struct Random(u64);

impl Random {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        6.0 * (bits as f64 / (1u64 << 53) as f64) - 3.0
    }
}

/// Which declared coordinate each URDF joint moves: `join.coordinate`, or `join` for a join of
/// one coordinate.
fn coordinate_indices(prepared: &Prepared) -> HashMap<String, usize> {
    let mut indices = HashMap::new();
    for joint in &prepared.model.joints {
        let chain = &joint.chain;
        for (k, coordinate) in chain.coordinate_names.iter().enumerate() {
            indices.insert(format!("{}.{coordinate}", chain.name), chain.offset + k);
        }
        if chain.coordinate_count() == 1 {
            indices.insert(chain.name.clone(), chain.offset);
        }
    }
    indices
}

fn assert_close(name: &str, what: &str, lsdc: &Matrix6<f64>, urdf: &Matrix6<f64>) {
    let scale = lsdc.amax().max(1.0);
    assert!(
        (lsdc - urdf).amax() <= TOLERANCE * scale,
        "{name}: {what} differs\nlsdc {lsdc}\nurdf {urdf}"
    );
}

fn check_poses_and_inertias(prepared: &Prepared) {
    let model = &prepared.model;
    let (_, robot) = exported(prepared);
    let frames = link_frames(model).expect("a tree");
    let indices = coordinate_indices(prepared);
    let floating: HashMap<&str, usize> = model
        .joints
        .iter()
        .filter(|j| matches!(j.kind, JointType::Free { .. }))
        .map(|j| (j.chain.name.as_str(), j.q_offset))
        .collect();
    let mut random = Random(0x9e37_79b9_7f4a_7c15);
    let mut data = Data::new(model);
    for _ in 0..5 {
        let declared: Vec<f64> = (0..model.declared_count).map(|_| random.next()).collect();
        let (q, v) = model
            .state_from_declared(&declared, &vec![0.0; model.declared_count])
            .expect("a state");
        forward_kinematics(model, &mut data, &q, &v).expect("forward kinematics");
        let poses = link_poses(&robot, |joint| {
            let free = floating.get(joint.name.as_str()).map(|&o| {
                Pose::from_parts(
                    Translation3::new(q[o], q[o + 1], q[o + 2]),
                    quaternion(&q[o + 3..o + 7]),
                )
            });
            (indices.get(&joint.name).map_or(0.0, |&i| declared[i]), free)
        });
        for (i, name) in model.body_names.iter().enumerate().map(|(k, n)| (k + 1, n)) {
            let expected = data.world[i] * frames[i];
            let pose = poses[name];
            assert_close(
                name,
                "the link's pose",
                &expected.to_homogeneous().fixed_resize(0.0),
                &pose.to_homogeneous().fixed_resize(0.0),
            );
            let lsdc = inertia_to_parent(&data.world[i], &model.bodies[i - 1].inertia);
            assert_close(
                name,
                "the spatial inertia about the world origin",
                &lsdc,
                &world_inertia(link(&robot, name), &pose),
            );
        }
    }
}

#[test]
fn urdf_poses_and_inertias_match_the_forward_kinematics() {
    for prepared in [
        example("double_pendulum"),
        example("satellite_numeric"),
        program(EXPANDED),
    ] {
        check_poses_and_inertias(&prepared);
    }
}

// ---------------------------------------------------------------------------------------------
// The command line.

fn lsdc(args: &[&str]) -> (i32, String, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_lsdc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs lsdc");
    let text = |bytes: Vec<u8>| String::from_utf8(bytes).expect("UTF-8");
    (
        output.status.code().unwrap_or(-1),
        text(output.stdout),
        text(output.stderr),
    )
}

#[test]
fn the_command_writes_urdf_or_says_why_it_cannot() {
    let (code, urdf, _) = lsdc(&["export-urdf", "examples/double_pendulum.lsd"]);
    assert_eq!(code, 0);
    assert_eq!(
        urdf_rs::read_from_string(&urdf).expect("URDF").name,
        "double_pendulum"
    );

    let out = std::env::temp_dir().join(format!("lsdc-export-{}.urdf", std::process::id()));
    let (code, stdout, _) = lsdc(&[
        "export-urdf",
        "examples/satellite_numeric.lsd",
        "--name",
        "sat",
        "-o",
        out.to_str().expect("a path"),
    ]);
    assert_eq!((code, stdout.as_str()), (0, ""));
    let written = std::fs::read_to_string(&out).expect("the URDF file");
    let _ = std::fs::remove_file(&out);
    assert_eq!(
        urdf_rs::read_from_string(&written).expect("URDF").name,
        "sat"
    );

    let (code, _, stderr) = lsdc(&["export-urdf", "examples/four_bar.lsd"]);
    assert_eq!(code, 1);
    assert_eq!(stderr, "error: URDF describes trees: examples/four_bar.lsd has complementary link c (it closes a loop)\n");
}
