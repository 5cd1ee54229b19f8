//! Importing URDF: the generated program compiles, reproduces the URDF's mass properties and
//! joint placements, reports what it leaves out at the right lines, renames what it must, and
//! turns bad input into diagnostics. Also `lsdc import-urdf` and `.urdf` files given to `lsdc`.

use crate::common::lsdc;

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};

use lsdc::diag::Diagnostic;
use lsdc::driver::{compile_text, Compilation};
use lsdc::dynamics::model::{self as dynamic_model, Model};
use lsdc::elab::value::BodyRef;
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::forward::forward;
use lsdc::kinematics::model::{self as kinematic_model, KinematicModel};
use lsdc::load::urdf::{import_urdf, lsd_name, ImportOptions, Imported};
use lsdc::load::LoadOptions;
use lsdc::source::SourceMap;
use lsdc::spatial;

/// A two-link arm with a prismatic tool on a fixed flange: off-diagonal inertia tensors, rpy
/// origins, a continuous joint that mimics the shoulder, limits, damping, a safety controller,
/// a calibration, a non-unit axis, geometry and elements that are not imported.
const ARM: &str = r#"<?xml version="1.0"?>
<robot name="arm">
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <link name="base"/>
  <link name="upper">
    <inertial>
      <origin xyz="0.01 -0.02 0.25" rpy="0.1 -0.2 0.3"/>
      <mass value="1.5"/>
      <inertia ixx="0.03" ixy="0.002" ixz="-0.003" iyy="0.025" iyz="0.001" izz="0.02"/>
    </inertial>
    <visual><geometry><box size="0.1 0.1 0.5"/></geometry></visual>
  </link>
  <link name="lower">
    <inertial>
      <origin xyz="0 0 0.2" rpy="0 0.5 0"/>
      <mass value="0.8"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.012" iyz="0" izz="0.003"/>
    </inertial>
    <collision><geometry><cylinder radius="0.02" length="0.4"/></geometry></collision>
  </link>
  <link name="slider">
    <inertial>
      <origin xyz="0.001 0.002 0.003"/>
      <mass value="0.1"/>
      <inertia ixx="2e-4" ixy="-1e-5" ixz="2e-5" iyy="1.5e-4" iyz="-3e-5" izz="1e-4"/>
    </inertial>
  </link>
  <link name="flange"/>
  <joint name="shoulder" type="revolute">
    <origin xyz="0 0 0.1" rpy="0.2 0.3 1.5707963267948966"/>
    <parent link="base"/>
    <child link="upper"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1.57" upper="1.57" effort="10" velocity="2"/>
    <dynamics damping="0.1" friction="0.01"/>
  </joint>
  <joint name="elbow" type="continuous">
    <origin xyz="0.05 0 0.5" rpy="-0.4 0 0"/>
    <parent link="upper"/>
    <child link="lower"/>
    <axis xyz="0 2 2"/>
    <mimic joint="shoulder" multiplier="-2" offset="0.1"/>
    <calibration rising="0.3"/>
  </joint>
  <joint name="fixed" type="fixed">
    <origin xyz="0 0 0.4"/>
    <parent link="lower"/>
    <child link="flange"/>
  </joint>
  <joint name="slide" type="prismatic">
    <origin xyz="0.01 0 0.02" rpy="0 0 -0.7"/>
    <parent link="flange"/>
    <child link="slider"/>
    <axis xyz="1 0 0"/>
    <limit lower="0" upper="0.1" effort="5" velocity="1"/>
    <safety_controller soft_lower_limit="0.01" soft_upper_limit="0.09" k_position="10" k_velocity="1"/>
  </joint>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type></transmission>
  <gazebo reference="upper"><material>Gazebo/Grey</material></gazebo>
  <gazebo reference="lower"><material>Gazebo/Grey</material></gazebo>
</robot>
"#;

fn import(xml: &str) -> Imported {
    import_urdf("arm.urdf", xml, &ImportOptions::default()).unwrap_or_else(|d| panic!("{d:?}"))
}

fn options() -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    }
}

fn compile(text: &str) -> Compilation {
    let compilation = compile_text("imported.lsd", text, None, &options());
    assert!(
        !compilation.has_errors(),
        "{:?}\n{text}",
        compilation.diagnostics
    );
    assert!(compilation.mechanism.is_some());
    compilation
}

fn models(text: &str) -> (Compilation, KinematicModel, Model) {
    let compilation = compile(text);
    let mechanism = compilation.mechanism.as_ref().expect("elaborates");
    let topology = lsdc::topology::build(mechanism).expect("a tree");
    let kinematics =
        kinematic_model::build(mechanism, topology, UnknownValues::new()).expect("numeric");
    let dynamics = dynamic_model::build(mechanism, &kinematics).expect("dynamic model");
    (compilation, kinematics, dynamics)
}

/// URDF's rpy: Rz(yaw) · Ry(pitch) · Rx(roll).
fn rpy(roll: f64, pitch: f64, yaw: f64) -> Rotation3<f64> {
    Rotation3::from_euler_angles(roll, pitch, yaw)
}

fn pose(xyz: [f64; 3], rotation: Rotation3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_rotation_matrix(&rotation),
    )
}

/// One-based line of the first occurrence of `needle` in `xml`.
fn line_of(xml: &str, needle: &str) -> usize {
    let at = xml
        .find(needle)
        .unwrap_or_else(|| panic!("`{needle}` in the URDF"));
    xml[..at].matches('\n').count() + 1
}

fn line(sources: &SourceMap, diagnostic: &Diagnostic) -> usize {
    let span = diagnostic.primary_span().expect("located");
    sources
        .file(span.file())
        .line_column(span.start() as usize)
        .0
}

#[test]
fn the_arm_compiles_with_one_join_per_joint() {
    let imported = import(ARM);
    let text = &imported.text;
    assert!(
        text.starts_with("(* Robot `arm`, imported from the URDF file `arm.urdf`."),
        "{text}"
    );
    for expected in [
        "import joints ;",
        "import gravity ;",
        "let base = body mass = 0, inertia = 0 end ;",
        "let flange = body mass = 0, inertia = 0 end ;",
        // A diagonal tensor keeps its axes and the order of its moments.
        "let lower = body mass = 0.8, iframe = [0, 0, 0.2] ++ (0.5 || [0, 1, 0]), inertia = [0.01, 0.012, 0.003] end ;",
        "join earth and base with weld as world_joint ;",
        // The limits, friction and damping of the shoulder; the elbow mimics it.
        "join [0, 0, 0.1] ++ (1.5707963267948966 || [0, 0, 1]) * (0.3 || [0, 1, 0]) * (0.2 || [1, 0, 0]) @ base and upper with link(q) dof = q || [0, 1, 0], lower = -1.57, upper = 1.57, restitution = 0, friction = 0.01, damping = 0.1 end as shoulder ;",
        "with link(q) dof = q || [0, 0.7071067811865475, 0.7071067811865475], mimic = shoulder, mimic_multiplier = -2, mimic_offset = 0.1 end as elbow ;",
        "join [0, 0, 0.4] ++ 1 @ lower and flange with weld as fixed_ ; (* URDF joint \"fixed\" *)",
        // `<limit>` ranges become stops on the coordinates.
        "with limited_prismatic([1, 0, 0], 0, 0.1, 0) as slide ;",
        "apply weight(upper) on upper.iframe ;",
        "apply weight(slider) on slider.iframe ;",
    ] {
        assert!(text.contains(expected), "missing `{expected}` in\n{text}");
    }
    assert!(!text.contains("weight(base)"), "{text}");
    let (_, kinematics, _) = models(text);
    assert_eq!(kinematics.topology.body_count(), 5);
    assert_eq!(kinematics.coordinate_count, 3);
}

#[test]
fn inertia_is_the_urdf_tensor_about_the_principal_axes() {
    let (_, _, model) = models(&import(ARM).text);
    let cases = [
        (
            "upper",
            1.5,
            [0.01, -0.02, 0.25],
            rpy(0.1, -0.2, 0.3),
            [0.03, 0.002, -0.003, 0.025, 0.001, 0.02],
        ),
        (
            "lower",
            0.8,
            [0.0, 0.0, 0.2],
            rpy(0.0, 0.5, 0.0),
            [0.01, 0.0, 0.0, 0.012, 0.0, 0.003],
        ),
        (
            "slider",
            0.1,
            [0.001, 0.002, 0.003],
            Rotation3::identity(),
            [2e-4, -1e-5, 2e-5, 1.5e-4, -3e-5, 1e-4],
        ),
    ];
    for (name, mass, com, rotation, [ixx, ixy, ixz, iyy, iyz, izz]) in cases {
        let index = model
            .body_names
            .iter()
            .position(|n| n == name)
            .expect("body");
        let body = &model.bodies[index];
        let tensor = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
        let central = rotation.matrix() * tensor * rotation.matrix().transpose();
        let expected = spatial::inertia(mass, &Vector3::from(com), &central);
        let error = (body.inertia - expected).norm() / expected.norm();
        assert!(
            error < 1e-12,
            "{name}: relative error {error:e}\n{}\n{expected}",
            body.inertia
        );
        assert_eq!(body.mass, mass);
    }
    for name in ["base", "flange"] {
        let index = model
            .body_names
            .iter()
            .position(|n| n == name)
            .expect("body");
        assert!(model.bodies[index].massless, "{name}");
    }
}

/// Tensors turned far from their principal axes, some with equal moments: whatever rotation the
/// importer picks, the body's inertia is the URDF's.
#[test]
fn rotated_and_degenerate_tensors_are_reproduced() {
    let turns = [
        (2.5, [1.0, 2.0, 3.0]),
        (3.1, [0.0, 0.0, 1.0]),
        (std::f64::consts::PI, [1.0, 1.0, 0.0]),
        (0.9, [-1.0, 0.5, 0.2]),
    ];
    let moments = [
        [0.01, 0.02, 0.025],
        [0.02, 0.02, 0.03],
        [0.01, 0.015, 0.015],
        [0.02, 0.02, 0.02],
    ];
    for (angle, axis) in turns {
        for diagonal in moments {
            let turn = Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::from(axis)), angle);
            let tensor = turn.matrix()
                * Matrix3::from_diagonal(&Vector3::from(diagonal))
                * turn.matrix().transpose();
            let t = |i: usize, j: usize| tensor[(i, j)];
            let xml = format!(
                r#"<robot name="r"><link name="a"><inertial><origin xyz="0.1 0.2 0.3" rpy="0.4 0.5 0.6"/><mass value="2"/>
                <inertia ixx="{}" ixy="{}" ixz="{}" iyy="{}" iyz="{}" izz="{}"/></inertial></link></robot>"#,
                t(0, 0),
                t(0, 1),
                t(0, 2),
                t(1, 1),
                t(1, 2),
                t(2, 2)
            );
            let imported = import(&xml);
            assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
            let (_, _, model) = models(&imported.text);
            let rotation = rpy(0.4, 0.5, 0.6);
            let expected = spatial::inertia(
                2.0,
                &Vector3::new(0.1, 0.2, 0.3),
                &(rotation.matrix() * tensor * rotation.matrix().transpose()),
            );
            let error = (model.bodies[0].inertia - expected).norm() / expected.norm();
            assert!(
                error < 1e-12,
                "{angle} {axis:?} {diagonal:?}: {error:e}\n{}",
                imported.text
            );
        }
    }
}

/// Every prefix of a URDF file is an error or a program, never a panic.
#[test]
fn truncated_files_never_panic() {
    for (end, _) in ARM.char_indices() {
        if let Ok(imported) = import_urdf("cut.urdf", &ARM[..end], &ImportOptions::default()) {
            compile(&imported.text);
        }
    }
}

#[test]
fn joints_place_the_child_at_parent_origin_motion() {
    let (compilation, kinematics, _) = models(&import(ARM).text);
    let mechanism = compilation.mechanism.as_ref().expect("mechanism");
    let (shoulder, elbow, slide) = (0.7, -1.3, 0.04);
    let mut q = vec![0.0; kinematics.coordinate_count];
    for joint in kinematics.principal() {
        match mechanism.join_name(joint.join).as_str() {
            "shoulder" => q[joint.offset] = shoulder,
            "elbow" => q[joint.offset] = elbow,
            "slide" => q[joint.offset] = slide,
            _ => assert_eq!(joint.coordinate_count(), 0),
        }
    }
    let revolve = |axis: Vector3<f64>, angle: f64| {
        pose(
            [0.0; 3],
            Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle),
        )
    };
    let base = Isometry3::identity();
    let upper = base
        * pose([0.0, 0.0, 0.1], rpy(0.2, 0.3, std::f64::consts::FRAC_PI_2))
        * revolve(Vector3::y(), shoulder);
    let lower = upper
        * pose([0.05, 0.0, 0.5], rpy(-0.4, 0.0, 0.0))
        * revolve(Vector3::new(0.0, 1.0, 1.0), elbow);
    let flange = lower * pose([0.0, 0.0, 0.4], Rotation3::identity());
    let slider = flange
        * pose([0.01, 0.0, 0.02], rpy(0.0, 0.0, -0.7))
        * pose([slide, 0.0, 0.0], Rotation3::identity());
    let configuration = forward(&kinematics, &q).expect("forward kinematics");
    for (name, expected) in [
        ("base", base),
        ("upper", upper),
        ("lower", lower),
        ("flange", flange),
        ("slider", slider),
    ] {
        let number = (1..=kinematics.topology.body_count())
            .find(|&j| {
                mechanism.body_name(BodyRef::Body(kinematics.topology.bodies[j - 1])) == name
            })
            .expect("body");
        let error =
            (configuration.poses[number].to_homogeneous() - expected.to_homogeneous()).amax();
        assert!(error < 1e-12, "{name}: {error:e}");
    }
}

#[test]
fn warnings_point_at_what_is_not_imported() {
    let imported = import(ARM);
    let mut sources = SourceMap::new();
    sources.add("arm.urdf", ARM);
    let found: Vec<(&str, usize)> = imported
        .warnings
        .iter()
        .map(|d| (d.code, line(&sources, d)))
        .collect();
    let expected = [
        ("W1007", line_of(ARM, "<material name=\"grey\"")),
        ("W1002", line_of(ARM, "<limit lower=\"-1.57\"")),
        ("W1009", line_of(ARM, "<axis xyz=\"0 2 2\"")),
        ("W1006", line_of(ARM, "<calibration")),
        ("W1001", line_of(ARM, "<joint name=\"fixed\"")),
        ("W1002", line_of(ARM, "<limit lower=\"0\"")),
        ("W1005", line_of(ARM, "<safety_controller")),
        ("W1008", line_of(ARM, "<transmission")),
        ("W1008", line_of(ARM, "<gazebo")),
    ];
    assert_eq!(found, expected, "{:#?}", imported.warnings);
    assert!(imported.warnings.iter().all(|d| !d.is_error()));
    // The mimic and the dynamics are imported: elbow = -2 shoulder + 0.1, with friction and
    // damping on the shoulder.
    assert!(imported
        .warnings
        .iter()
        .all(|d| d.code != "W1003" && d.code != "W1004"));
    assert!(
        imported
            .text
            .contains("mimic = shoulder, mimic_multiplier = -2, mimic_offset = 0.1"),
        "{}",
        imported.text
    );
    assert!(
        imported.text.contains("friction = 0.01, damping = 0.1"),
        "{}",
        imported.text
    );
    let gazebo = imported
        .warnings
        .iter()
        .find(|d| d.message.contains("gazebo"))
        .expect("gazebo");
    assert!(
        gazebo.message.starts_with("2 `<gazebo>` elements"),
        "{}",
        gazebo.message
    );
    let limit = imported
        .warnings
        .iter()
        .find(|d| d.code == "W1002")
        .expect("limit");
    assert!(
        limit
            .notes
            .iter()
            .any(|n| n.contains("lower = -1.57, upper = 1.57, effort = 10, velocity = 2")),
        "{:?}",
        limit.notes
    );
    let rendered = lsdc::diag::render::to_text(&sources, &imported.warnings);
    assert!(
        rendered.contains(&format!("arm.urdf:{}:", line_of(ARM, "<calibration"))),
        "{rendered}"
    );
}

const RENAMED: &str = r#"<robot name="names">
  <link name="base-link"/>
  <link name="with"/>
  <link name="2nd"/>
  <link name="earth"/>
  <link name="g"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <link name="base_link"/>
  <joint name="with" type="fixed"><parent link="base-link"/><child link="with"/></joint>
  <joint name="j" type="fixed"><parent link="with"/><child link="2nd"/></joint>
  <joint name="k" type="fixed"><parent link="2nd"/><child link="earth"/></joint>
  <joint name="world_joint" type="fixed"><parent link="earth"/><child link="g"/></joint>
  <joint name="l" type="fixed"><parent link="g"/><child link="base_link"/></joint>
</robot>
"#;

#[test]
fn names_that_are_not_lsd_names_are_renamed_and_reported() {
    let imported = import(RENAMED);
    let text = &imported.text;
    for expected in [
        // A valid name keeps it; the invalid one that would become it takes the next.
        "let base_link_ = body mass = 0, inertia = 0 end ; (* URDF link \"base-link\" *)",
        "let base_link = body",
        "let with_ = body",
        "let _2nd = body",
        "let earth_ = body",
        "let g_ = body mass = 1,",
        "with weld as with__ ; (* URDF joint \"with\" *)",
        "with weld as world_joint ;",
        "join earth and base_link_ with weld as world_joint_ ;",
        "apply weight(g_) on g_.iframe ;",
    ] {
        assert!(text.contains(expected), "missing `{expected}` in\n{text}");
    }
    let renames: Vec<&str> = imported
        .warnings
        .iter()
        .filter(|d| d.code == "W1001")
        .map(|d| d.message.as_str())
        .collect();
    assert_eq!(renames.len(), 6, "{renames:#?}");
    assert!(
        renames.contains(&"link `2nd` is called `_2nd` in LSD"),
        "{renames:#?}"
    );
    compile(text);
    assert_eq!(lsd_name("base-link"), "base_link");
    assert_eq!(lsd_name("planar"), "planar_");
}

#[test]
fn other_joint_types_compile() {
    let xml = r#"<robot name="kinds">
  <link name="a"/>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="c"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="d"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <joint name="p1" type="planar"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>
  <joint name="p2" type="planar"><parent link="b"/><child link="c"/></joint>
  <joint name="f" type="floating"><parent link="c"/><child link="d"/></joint>
</robot>"#;
    let imported = import(xml);
    assert!(
        imported.text.contains("with planar as p1 ;"),
        "{}",
        imported.text
    );
    assert!(
        imported.text.contains(
            "link(x, y, q) dof1 = x * [0, 1, 0] + y * [0, 0, 1], dof2 = q || [1, 0, 0] end as p2 ;"
        ),
        "{}",
        imported.text
    );
    assert!(
        imported.text.contains("with free as f ;"),
        "{}",
        imported.text
    );
    let (_, kinematics, _) = models(&imported.text);
    assert_eq!(kinematics.coordinate_count, 3 + 3 + 6);
}

#[test]
fn floating_base_without_gravity() {
    let options = ImportOptions {
        floating_base: true,
        gravity: false,
    };
    let imported = import_urdf("arm.urdf", ARM, &options).expect("imports");
    assert!(
        imported
            .text
            .contains("join earth and base with free as root_joint ;"),
        "{}",
        imported.text
    );
    assert!(
        !imported.text.contains("import gravity"),
        "{}",
        imported.text
    );
    assert!(!imported.text.contains("weight("), "{}", imported.text);
    let (_, kinematics, _) = models(&imported.text);
    assert_eq!(kinematics.coordinate_count, 6 + 3);
    let default = ImportOptions::default();
    assert!(!default.floating_base && default.gravity);
}

#[test]
fn numbers_are_written_without_loss() {
    let xml = r#"<robot name="tiny">
  <link name="a"><inertial><origin xyz="1e-7 -123456.789 1.23456789012345"/><mass value="1e-7"/><inertia ixx="1e-30" ixy="0" ixz="0" iyy="2e-30" iyz="0" izz="2.5e-30"/></inertial></link>
</robot>"#;
    let imported = import(xml);
    assert!(imported.text.contains("mass = 1e-7, iframe = [1e-7, -123456.789, 1.23456789012345] ++ 1, inertia = [1e-30, 2e-30, 2.5e-30]"), "{}", imported.text);
    let (_, _, model) = models(&imported.text);
    let body = &model.bodies[0];
    assert_eq!(body.mass, 1e-7);
    assert_eq!(body.com, Vector3::new(1e-7, -123456.789, 1.23456789012345));
}

#[test]
fn impossible_inertia_is_reported_imported_and_refused() {
    let xml = r#"<robot name="bad">
  <link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="3"/></inertial></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="1" ixy="2" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <link name="c"><inertial><mass value="2"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="k" type="fixed"><parent link="a"/><child link="c"/></joint>
</robot>"#;
    let imported = import(xml);
    let messages: Vec<&str> = imported
        .warnings
        .iter()
        .filter(|d| d.code == "W1010")
        .map(|d| d.message.as_str())
        .collect();
    assert_eq!(messages.len(), 3, "{messages:#?}");
    assert!(
        messages[0].contains("link `a`") && messages[0].contains("triangle inequality"),
        "{}",
        messages[0]
    );
    assert!(
        messages[1].contains("link `b`") && messages[1].contains("not positive definite"),
        "{}",
        messages[1]
    );
    assert!(
        messages[2].contains("link `c`") && messages[2].contains("not positive definite"),
        "{}",
        messages[2]
    );
    // Imported as written, an impossible body is then refused where the program writes it
    // (E0608; evaluation stops at its first error, the body of `a`).
    let compilation = compile_text("imported.lsd", &imported.text, None, &options());
    let codes: Vec<&str> = compilation.diagnostics.iter().map(|d| d.code).collect();
    assert_eq!(codes, ["E0608"], "{:?}", compilation.diagnostics);
    assert!(compilation.diagnostics[0].message.contains("1, 1, 3"));
}

#[test]
fn bad_urdf_is_a_located_error() {
    let cases = [
        ("<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n", "E1001", "</robot>"),
        ("<robot name=\"r\"><link name=\"a\"/><!-- never closed </robot>", "E1001", "<"),
        ("<robot name=\"r\"><link name=\"a\"/></robot>\n<robot/>", "E1001", "<robot/>"),
        ("<rob name=\"r\"/>", "E1002", "<rob name=\"r\"/>"),
        ("<robot name=\"r\"><link/></robot>", "E1002", "<link/>"),
        ("<robot name=\"r\"><link name=\"a\"><inertial><mass value=\"x\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>", "E1002", "value=\"x\""),
        ("<robot name=\"r\"><link name=\"a\"><inertial><origin xyz=\"1 2\"/><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>", "E1002", "xyz=\"1 2\""),
        ("<robot name=\"r\"><link name=\"a\"><inertial><mass value=\"1\"/></inertial></link></robot>", "E1002", "<inertial>"),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"hinge\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>", "E1002", "type=\"hinge\""),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"fixed\"><parent link=\"a\"/></joint></robot>", "E1002", "<joint name=\"j\" type=\"fixed\">"),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"c\"/></joint></robot>", "E1003", "link=\"c\""),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"a\"/></robot>", "E1004", "name=\"a\""),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/><joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"c\"/></joint><joint name=\"k\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint></robot>", "E1005", "<child link=\"c\"/>"),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint><joint name=\"k\" type=\"fixed\"><parent link=\"b\"/><child link=\"a\"/></joint></robot>", "E1006", "<joint name=\"j\" type=\"fixed\">"),
        ("<robot name=\"r\"></robot>", "E1007", "<robot name=\"r\">"),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/></robot>", "E1007", "<link name=\"b\"/>"),
        ("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 0\"/></joint></robot>", "E1008", "xyz=\"0 0 0\""),
    ];
    for (xml, code, located) in cases {
        let error = import_urdf("bad.urdf", xml, &ImportOptions::default()).expect_err(xml);
        assert!(error.is_error(), "{xml}");
        assert_eq!(error.code, code, "{xml}: {error:?}");
        let span = error
            .primary_span()
            .unwrap_or_else(|| panic!("{xml}: no position"));
        assert!(
            xml[span.range()].starts_with(located),
            "{xml}: `{}`",
            &xml[span.range()]
        );
    }
    for xml in [
        "",
        "   ",
        "not xml",
        "<",
        "<robot name=\"r\"",
        "<robot name='r>",
        "<robot></robot></robot>",
        "\u{feff}<é/>",
    ] {
        let error = import_urdf("bad.urdf", xml, &ImportOptions::default()).expect_err(xml);
        assert!(error.is_error(), "{xml}");
    }
}

/// Malformed XML is an error at the file, line and column of the fault, never a panic: an
/// unclosed tag, attributes without a value, unquoted or never closed, a second root.
#[test]
fn malformed_xml_is_an_error_at_its_line_and_column() {
    let cases = [
        (
            "<robot name=\"r\">\n  <link name=\"a\">\n  <link name=\"b\"/>\n</robot>\n",
            4,
            1,
        ),
        (
            "<robot name=\"r\">\n  <link name=\"a\" mass/>\n</robot>\n",
            2,
            22,
        ),
        ("<robot name=\"r\">\n  <link name=a/>\n</robot>\n", 2, 14),
        ("<robot name=\"r\">\n  <link name=\"a/>\n</robot>\n", 3, 1),
        (
            "<robot name=\"r\">\n  <link name=\"a\" name=\"b\"/>\n</robot>\n",
            2,
            18,
        ),
        (
            "<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\n<robot/>\n",
            4,
            1,
        ),
    ];
    for (xml, line, column) in cases {
        let error = import_urdf("bad.urdf", xml, &ImportOptions::default()).expect_err(xml);
        assert_eq!(error.code, "E1001", "{xml}: {error:?}");
        let mut sources = SourceMap::new();
        sources.add("bad.urdf", xml);
        let span = error
            .primary_span()
            .unwrap_or_else(|| panic!("{xml}: no position"));
        assert_eq!(
            sources.file(span.file()).line_column(span.start() as usize),
            (line, column),
            "{xml}: {error:?}"
        );
        let rendered = lsdc::diag::render::to_text(&sources, std::slice::from_ref(&error));
        assert!(
            rendered.contains(&format!("bad.urdf:{line}:{column}")),
            "{rendered}"
        );
    }
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-urdf-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn urdf_files_are_programs_for_every_command() {
    let dir = temp_dir("commands");
    let path = dir.join("arm.urdf");
    std::fs::write(&path, ARM).expect("write");
    let file = path.to_str().expect("utf-8 path");
    let (code, stdout, stderr) = lsdc(&["check", file]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("bodies    5 (base, upper, lower, flange, slider)"),
        "{stdout}"
    );
    assert!(!stderr.contains("warning[W1003]"), "{stderr}");
    let (code, stdout, stderr) = lsdc(&["tree", file]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("shoulder"), "{stdout}");
    let (code, _, stderr) = lsdc(&["simulate", file, "--duration", "0.02"]);
    assert_eq!(code, 0, "{stderr}");
    // A joint next to the URDF file does not replace the standard one the program was written for.
    std::fs::write(dir.join("joints.lsd"), "let unrelated = 1 ;\n").expect("write");
    let (code, _, stderr) = lsdc(&["check", file]);
    assert_eq!(code, 0, "{stderr}");
    std::fs::write(&path, "<robot name=\"r\"><link name=\"a\"/><joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>").expect("write");
    let (code, _, stderr) = lsdc(&["check", file]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("error[E1003]") && stderr.contains("arm.urdf:1:"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn import_urdf_prints_a_program_that_compiles() {
    let dir = temp_dir("cli");
    let path = dir.join("arm.urdf");
    std::fs::write(&path, ARM).expect("write");
    let file = path.to_str().expect("utf-8 path");
    let (code, stdout, stderr) = lsdc(&["import-urdf", file]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(
        stdout,
        import_urdf(file, ARM, &ImportOptions::default())
            .expect("imports")
            .text
    );
    assert!(stderr.contains("warning[W1002]"), "{stderr}");
    compile(&stdout);

    let out = dir.join("arm.lsd");
    let (code, stdout, stderr) = lsdc(&[
        "import-urdf",
        file,
        "--floating-base",
        "--no-gravity",
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.is_empty(), "{stdout}");
    let written = std::fs::read_to_string(&out).expect("written");
    assert!(
        written.contains("with free as root_joint ;") && !written.contains("weight("),
        "{written}"
    );
    let (code, _, stderr) = lsdc(&["check", out.to_str().expect("utf-8")]);
    assert_eq!(code, 0, "{stderr}");

    std::fs::write(&path, "<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n").expect("write");
    let (code, stdout, stderr) = lsdc(&["import-urdf", file]);
    assert_eq!(code, 1);
    assert!(stdout.is_empty(), "{stdout}");
    assert!(
        stderr.contains("error[E1001]") && stderr.contains("arm.urdf:3:1"),
        "{stderr}"
    );
    let (code, _, _) = lsdc(&["import-urdf", "no/such/file.urdf"]);
    assert_eq!(code, 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Materials with an empty `<texture />` (iCub's and Romeo's in example-robot-data): urdf-rs
/// requires a `filename`, but materials are not imported, so the import goes on and reports them
/// with the geometry.
const EMPTY_TEXTURES: &str = r#"<robot name="textures">
  <material name="grey">
    <texture />
    <color rgba="0.9 0.9 0.9 1"/>
  </material>
  <link name="base"/>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <visual>
      <geometry><box size="0.1 0.1 0.5"/></geometry>
      <material name="metal"><texture name="rouillé">
      </texture><color rgba="0 0 0 1"/></material>
    </visual>
    <visual>
      <geometry><sphere radius="0.1"/></geometry>
      <material name="skin"><texture filename="package://skin.png"/></material>
    </visual>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="base"/>
    <child link="arm"/>
    <axis xyz="0 0 1"/>
  </joint>
</robot>
"#;

#[test]
fn empty_textures_are_tolerated_and_materials_reported() {
    let imported = import(EMPTY_TEXTURES);
    assert!(
        imported
            .text
            .contains("with revolute([0, 0, 1]) as hinge ;"),
        "{}",
        imported.text
    );
    let mut sources = SourceMap::new();
    sources.add("textures.urdf", EMPTY_TEXTURES);
    let found: Vec<(&str, usize)> = imported
        .warnings
        .iter()
        .map(|d| (d.code, line(&sources, d)))
        .collect();
    assert_eq!(
        found,
        [("W1007", line_of(EMPTY_TEXTURES, "<material name=\"grey\""))],
        "{:#?}",
        imported.warnings
    );
    let geometry = &imported.warnings[0];
    assert_eq!(
        geometry.message,
        "the visual and collision geometry of 1 link is not imported"
    );
    assert!(
        geometry
            .notes
            .iter()
            .any(|n| n == "the robot defines 1 material"),
        "{:?}",
        geometry.notes
    );
    compile(&imported.text);

    // The errors found after the textures are blanked out still point at their line.
    let broken = EMPTY_TEXTURES.replace("<parent link=\"base\"/>", "<parent link=\"bas\"/>");
    let error = import_urdf("textures.urdf", &broken, &ImportOptions::default())
        .expect_err("no link `bas`");
    assert_eq!(error.code, "E1003");
    let mut sources = SourceMap::new();
    sources.add("textures.urdf", &broken);
    assert_eq!(
        line(&sources, &error),
        line_of(&broken, "<parent link=\"bas\"")
    );
}

/// Pinocchio's `<collision_checking>` in a link (simple_humanoid.urdf of example-robot-data):
/// its `<capsule name="test"/>` names a collision shape to turn into a capsule, it is not a shape.
const COLLISION_CHECKING: &str = r#"<robot name="checking">
  <link name="base"/>
  <link name="torso">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision name="test">
      <geometry><cylinder radius="0.1" length="0.2"/></geometry>
    </collision>
    <collision_checking>
      <capsule name="test"/>
      <convex name="box"/>
    </collision_checking>
  </link>
  <joint name="hinge" type="continuous">
    <parent link="base"/>
    <child link="torso"/>
    <axis xyz="1 0 0"/>
    <actuator name="motor"/>
  </joint>
</robot>
"#;

#[test]
fn extensions_inside_links_are_reported_not_checked_as_shapes() {
    let imported = import(COLLISION_CHECKING);
    let mut sources = SourceMap::new();
    sources.add("checking.urdf", COLLISION_CHECKING);
    let found: Vec<(&str, usize)> = imported
        .warnings
        .iter()
        .map(|d| (d.code, line(&sources, d)))
        .collect();
    let expected = [
        ("W1007", line_of(COLLISION_CHECKING, "<collision name=")),
        ("W1008", line_of(COLLISION_CHECKING, "<collision_checking>")),
        ("W1008", line_of(COLLISION_CHECKING, "<actuator")),
    ];
    assert_eq!(found, expected, "{:#?}", imported.warnings);
    assert_eq!(
        imported.warnings[1].message,
        "`<collision_checking>` of link `torso` is not imported"
    );
    assert_eq!(
        imported.warnings[2].message,
        "`<actuator>` of joint `hinge` is not imported"
    );
    compile(&imported.text);

    // A shape inside `<geometry>` is still checked.
    let broken = COLLISION_CHECKING.replace(
        "<cylinder radius=\"0.1\" length=\"0.2\"/>",
        "<capsule name=\"test\"/>",
    );
    let error = import_urdf("checking.urdf", &broken, &ImportOptions::default())
        .expect_err("a capsule without radius");
    assert_eq!(error.code, "E1002");
    assert_eq!(error.message, "`<capsule>` has no `radius` attribute");
    let span = error.primary_span().expect("located");
    assert_eq!(&broken[span.range()], "<capsule name=\"test\"/>");
    assert!(
        span.range().end < broken.find("<collision_checking>").expect("there"),
        "the one in `<geometry>`"
    );
}

/// Elements nested past the limit are refused at the first element too deep (E0209), at once
/// even for 100,000 levels (reading them took minutes); at the limit the document is read on.
#[test]
fn elements_nested_too_deep_are_refused_where_the_limit_is_passed() {
    use lsdc::load::urdf::document::MAX_ELEMENT_NESTING;
    let nested = |levels: usize| {
        let inner = levels - 2; // below <robot> and <link>
        format!(
            "<robot name=\"r\">\n<link name=\"a\">{}{}</link>\n</robot>\n",
            "<x>".repeat(inner),
            "</x>".repeat(inner)
        )
    };
    for levels in [MAX_ELEMENT_NESTING + 1, 100_000] {
        let xml = nested(levels);
        let error =
            import_urdf("deep.urdf", &xml, &ImportOptions::default()).expect_err("too deep");
        assert_eq!(error.code, "E0209", "{error:?}");
        let span = error.primary_span().expect("a place");
        let opened_before = xml[..span.start() as usize].matches("<x>").count();
        assert_eq!(opened_before + 2, MAX_ELEMENT_NESTING, "{error:?}");
        assert_eq!(&xml[span.start() as usize..span.end() as usize], "<x>");
    }
    let at_the_limit = import_urdf(
        "deep.urdf",
        &nested(MAX_ELEMENT_NESTING),
        &Default::default(),
    );
    assert!(
        at_the_limit
            .as_ref()
            .map_or_else(|e| e.code != "E0209", |_| true),
        "{:?}",
        at_the_limit.err()
    );
}

/// A gripper whose right finger mimics the left (listed before it in the URDF), whose left
/// finger has `<dynamics>`: imported with the coupling active and the friction acting, and
/// exported back with both.
#[test]
fn a_gripper_imports_with_its_mimic_coupling_and_friction_active() {
    let xml = std::fs::read_to_string("tests/fixtures/urdf/gripper.urdf").expect("fixture");
    let imported = import(&xml);
    let text = format!(
        "{}initial left_finger.q = 0.01, left_finger.q' = 0.05;\n",
        imported.text
    );
    // The leader is declared first whatever the URDF's order.
    let leader = text.find("as left_finger ;").expect("leader");
    let follower = text.find("as right_finger ;").expect("follower");
    assert!(leader < follower, "{text}");
    let settings = lsdc::prepare::Settings {
        duration: 1.0,
        output: 0.01,
        rtol: 1e-12,
        atol: 1e-12,
        ..Default::default()
    };
    let simulation = crate::common::programs::run_text(&text, settings);
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    for sample in &simulation.samples {
        assert!((sample.coordinates[0] + sample.coordinates[1]).abs() < 1e-15);
    }
    // Both fingers (0.2 kg) slow down under 0.2 N of dry and 0.5 v of viscous friction:
    // v(t) = (v0 + 0.4) e^(−2.5 t) − 0.4, at rest at t = ln(1.125) / 2.5, where they stick.
    let switches = &simulation.report.friction_switches;
    assert_eq!(switches.len(), 1, "{switches:?}");
    assert!(
        (switches[0].time - 1.125f64.ln() / 2.5).abs() < 1e-9,
        "{switches:?}"
    );
    assert_eq!(switches[0].phase, lsdc::dynamics::friction::Phase::Sticking);
    let mechanism = compile(&text).mechanism.expect("elaborates");
    let prepared = lsdc::prepare::prepare(&mechanism, &[], &Default::default())
        .unwrap_or_else(|d| panic!("{d:?}"));
    let exported = lsdc::output::urdf::export_urdf(&prepared.model, "gripper").expect("exports");
    assert!(
        exported.contains("<mimic joint=\"left_finger\" multiplier=\"-1\" offset=\"0\"/>"),
        "{exported}"
    );
    assert!(
        exported.contains("<dynamics damping=\"0.5\" friction=\"0.2\"/>"),
        "{exported}"
    );
}
