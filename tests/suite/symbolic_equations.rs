#![allow(clippy::needless_range_loop)] // matrices are compared entry by entry
//! The symbolic equations of motion against closed forms (notes §9.8) and against the numeric
//! back end.

use std::collections::HashMap;
use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::dynamics::algorithms::{crba, forward_kinematics, rnea, Data};
use lsdc::dynamics::efforts::{self, Declared, Efforts};
use lsdc::dynamics::loops::{active_rows, constraints, Extent};
use lsdc::dynamics::model;
use lsdc::elab::mechanism::Origin;
use lsdc::elab::Mechanism;
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::model as kinematic_model;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Override, Settings};
use lsdc::symbolic::{self, Equations};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

use crate::common::symbolic::{equations_of, Sequence};
use crate::common::trees::tree_program;

fn equations(path: &str) -> Equations {
    equations_of(path)
}

#[test]
fn fixed_satellite_equals_the_closed_forms_of_section_9_8() {
    let eq = equations("examples/satellite_fixed.lsd");
    let tape = eq.tape();
    let mut random = Sequence(7);
    let (mu4, z34) = (40.0, 0.5);
    for _ in 0..20 {
        let values: HashMap<String, f64> = [
            "hinge.x", "slide.x", "tilt.x", "hinge.x'", "slide.x'", "tilt.x'", "t",
        ]
        .iter()
        .map(|n| (n.to_string(), 2.0 * random.next()))
        .collect();
        let symbols = eq
            .symbol_values(|n| values.get(n).copied())
            .expect("every symbol has a value");
        let at = eq.evaluate(&tape, &symbols);
        let (q8, q9) = (values["slide.x"], values["tilt.x"]);
        let (d7, d8, d9) = (values["hinge.x'"], values["slide.x'"], values["tilt.x'"]);
        let expected = [
            [
                q8 * q8 + z34 * z34 * q9.cos().powi(2),
                -z34 * q9.cos(),
                -z34 * q8 * q9.sin(),
            ],
            [-z34 * q9.cos(), 1.0, 0.0],
            [-z34 * q8 * q9.sin(), 0.0, z34 * z34],
        ];
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (at.mass[(i, j)] - mu4 * expected[i][j]).abs() < 1e-12 * mu4,
                    "M[{i}][{j}] = {} ≠ {}",
                    at.mass[(i, j)],
                    mu4 * expected[i][j]
                );
            }
        }
        // Lagrange's equations with q̈ = 0 give −S.
        let velocity_terms = [
            2.0 * q8 * d7 * d8
                - 2.0 * z34 * z34 * q9.sin() * q9.cos() * d7 * d9
                - z34 * q8 * q9.cos() * d9 * d9,
            -q8 * d7 * d7 + 2.0 * z34 * q9.sin() * d7 * d9,
            z34 * z34 * q9.sin() * q9.cos() * d7 * d7 - 2.0 * z34 * q9.sin() * d7 * d8,
        ];
        for i in 0..3 {
            assert!(
                (at.second_member[i] + mu4 * velocity_terms[i]).abs() < 1e-12 * mu4,
                "S[{i}]"
            );
        }
        let det = at.mass.determinant();
        let closed = mu4.powi(3) * q8 * q8 * z34 * z34 * q9.cos().powi(2);
        assert!(
            (det - closed).abs() < 1e-12 * mu4.powi(3),
            "det M = {det} ≠ {closed}"
        );
    }
}

/// The numeric back end's equations at one state, on a model whose joints all keep their
/// declared coordinates (no quaternions): M, S + F, and for loops Δ and Δ̇q.
struct Numeric {
    mass: DMatrix<f64>,
    right_hand_side: DVector<f64>,
    constraints: DMatrix<f64>,
    constraint_bias: DVector<f64>,
    active_rows: Vec<bool>,
}

/// Without `with_efforts`, the right-hand side is S alone (for programs whose efforts are
/// unknown laws).
fn numeric(
    mechanism: &Mechanism,
    unknowns: &UnknownValues,
    coordinates: &[f64],
    rates: &[f64],
    time: f64,
    with_efforts: bool,
) -> Numeric {
    let topology = lsdc::topology::build(mechanism).expect("a topology");
    let kinematics =
        kinematic_model::build(mechanism, topology, unknowns.clone()).expect("kinematics");
    let model = model::build_with(mechanism, &kinematics, false).expect("model");
    let mut data = Data::new(&model);
    let mass = crba(&model, &mut data, coordinates).expect("CRBA");
    forward_kinematics(&model, &mut data, coordinates, rates).expect("kinematics");
    let declared = Declared {
        model: &model,
        coordinates,
        rates,
        states: &[],
    };
    let efforts = if with_efforts {
        efforts::evaluate(&model, &mut data, &declared, time).expect("efforts")
    } else {
        Efforts::none(&model)
    };
    let zero = vec![0.0; model.nv];
    let bias = rnea(
        &model,
        &mut data,
        coordinates,
        rates,
        &zero,
        &efforts.external,
    )
    .expect("RNEA");
    let mut right_hand_side = efforts.tau.clone();
    for k in 0..model.nv {
        right_hand_side[k] -= bias[k];
    }
    let c =
        constraints(&model, &mut data, coordinates, rates, Extent::WithBias).expect("constraints");
    Numeric {
        mass,
        right_hand_side,
        constraints: c.jacobian.dense(),
        constraint_bias: c.bias,
        active_rows: active_rows(&model),
    }
}

/// Largest |a − b| over max(1, largest |b|).
fn relative_gap(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// Symbolic against numeric at (coordinates, rates); the largest relative gap of M, S + F, Δ
/// and Δ̇q.
fn compare(
    mechanism: &Mechanism,
    eq: &Equations,
    unknowns: &UnknownValues,
    coordinates: &[f64],
    rates: &[f64],
) -> f64 {
    let with_efforts = eq.variables.functions.is_empty();
    let time = 0.25;
    let mut named: HashMap<String, f64> = HashMap::new();
    for (k, variable) in eq.variables.positions.iter().enumerate() {
        named.insert(variable.name.clone(), coordinates[k]);
        named.insert(eq.variables.rates[k].name.clone(), rates[k]);
    }
    for parameter in &eq.variables.parameters {
        named.insert(
            parameter.name.clone(),
            unknowns[&parameter.unknown.expect("an unknown")],
        );
    }
    named.insert("t".to_string(), time);
    // Unknown laws act only in F, which is then left out of the comparison.
    for function in &eq.variables.functions {
        named.insert(
            eq.pool
                .name_of(function.symbol)
                .expect("a symbol")
                .to_string(),
            0.3,
        );
    }
    let symbols = eq
        .symbol_values(|n| named.get(n).copied())
        .expect("every symbol has a value");
    let at = eq.evaluate(&eq.tape(), &symbols);
    let expected = numeric(mechanism, unknowns, coordinates, rates, time, with_efforts);
    let nv = expected.mass.nrows();
    let n = eq.dimension();
    let mut gaps = vec![relative_gap(
        at.mass.view((0, 0), (nv, nv)).transpose().as_slice(),
        expected.mass.transpose().as_slice(),
    )];
    // The complementary coordinates carry no inertia.
    assert!(at.mass.rows(nv, n - nv).iter().all(|&m| m == 0.0));
    let rhs = if with_efforts {
        &at.second_member + &at.forces
    } else {
        at.second_member.clone()
    };
    gaps.push(relative_gap(
        rhs.as_slice(),
        expected.right_hand_side.as_slice(),
    ));
    if let Some(accelerations) = &at.accelerations {
        // The articulated-body recursion solves M q̇ = S + F: its residual, relative to the
        // terms' size (a backward error, free of M's conditioning).
        let applied = &at.mass * accelerations;
        let total = &at.second_member + &at.forces;
        let scale = at.mass.amax() * accelerations.amax() + total.amax();
        gaps.push(
            relative_gap(applied.as_slice(), total.as_slice()) * total.amax().max(1.0)
                / scale.max(1.0),
        );
    }
    for (r, active) in expected.active_rows.iter().enumerate() {
        if *active {
            let row: Vec<f64> = at.constraints.row(r).iter().copied().collect();
            let numeric_row: Vec<f64> = expected.constraints.row(r).iter().copied().collect();
            gaps.push(relative_gap(&row, &numeric_row));
            gaps.push(relative_gap(
                &[at.constraint_bias[r]],
                &[expected.constraint_bias[r]],
            ));
        }
    }
    gaps.into_iter().fold(0.0, f64::max)
}

/// A value in [0.5, 1.5) for every unknown parameter, under a name `--set` accepts.
fn values_for_unknowns(mechanism: &Mechanism, eq: &Equations, seed: u64) -> Vec<Override> {
    let mut random = Sequence(seed);
    eq.variables
        .parameters
        .iter()
        .map(|p| {
            let unknown = &mechanism.unknowns[p.unknown.expect("an unknown").0 as usize];
            let name = if unknown.origin == Origin::Written {
                p.name.clone()
            } else {
                p.meaning.clone()
            };
            Override {
                name,
                value: 1.0 + 0.5 * random.next(),
            }
        })
        .collect()
}

/// The examples, then the URDF robots of the fixtures (welded links, many bodies).
fn example_paths() -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut paths = Vec::new();
    for (dir, extension) in [("examples", "lsd"), ("tests/fixtures/urdf", "urdf")] {
        let mut found: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .expect("a directory")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == extension))
            .collect();
        found.sort();
        paths.extend(found);
    }
    paths
}

#[test]
fn symbolic_and_numeric_back_ends_agree_on_every_example() {
    let mut compared = Vec::new();
    for path in example_paths() {
        let compilation =
            compile_files(std::slice::from_ref(&path), &LoadOptions::default()).expect("readable");
        let mechanism = (compilation.mechanism.as_ref())
            .unwrap_or_else(|| panic!("{}: {:?}", path.display(), compilation.diagnostics));
        let topology = lsdc::topology::build(mechanism).expect("a topology");
        let has_rotors = mechanism.joins.iter().any(|join| {
            let link = mechanism.link(join.link);
            link.rotor().is_declared()
                || link.mimic().is_declared()
                || link.friction().is_declared()
        });
        if !mechanism.contacts.is_empty() || has_rotors {
            // The equations of a mechanism with contacts or geared rotors are refused, not
            // written without them.
            let refused = symbolic::generate(mechanism, &topology)
                .err()
                .expect("refused");
            // The contacts are refused first (an example may have both).
            let code = match mechanism.contacts.is_empty() {
                true => "E0826",
                false => "E0825",
            };
            assert_eq!(refused[0].code, code, "{}", path.display());
            continue;
        }
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let rheonomic = ["kapitza_pendulum.lsd", "bead_on_spinning_rod.lsd"];
        let driven = !mechanism.drives.is_empty() || !mechanism.position_drives.is_empty();
        if driven || rheonomic.contains(&name.as_str()) {
            // Motions imposed in time: refused, not written as the free mechanism's.
            let refused = symbolic::generate(mechanism, &topology)
                .err()
                .expect("refused");
            assert_eq!(refused[0].code, "E0828", "{name}");
            continue;
        }
        let eq = symbolic::generate(mechanism, &topology)
            .unwrap_or_else(|e| panic!("{}: {e:?}", path.display()));
        // Unknown laws have no numeric value: M and S are compared at random parameters.
        if !eq.variables.functions.is_empty() {
            let mut random = Sequence(5);
            let unknowns: UnknownValues = eq
                .variables
                .parameters
                .iter()
                .map(|p| (p.unknown.expect("an unknown"), 1.0 + 0.5 * random.next()))
                .collect();
            let coordinates: Vec<f64> = (0..eq.dimension()).map(|_| random.next()).collect();
            let rates: Vec<f64> = (0..eq.dimension()).map(|_| random.next()).collect();
            let worst = compare(mechanism, &eq, &unknowns, &coordinates, &rates);
            assert!(
                worst < 1e-12,
                "{name}: symbolic and numeric M and S differ by {worst:e} (relative)"
            );
            compared.push((name + " (M, S)", worst, eq.size()));
            continue;
        }
        let prepared = match prepare(mechanism, &[], &Settings::default()) {
            Ok(prepared) => prepared,
            // Drawn until they make rigid bodies: generic principal moments must satisfy the
            // triangle inequality (E0816).
            Err(_) => (11..40)
                .find_map(|seed| {
                    let values = values_for_unknowns(mechanism, &eq, seed);
                    prepare(mechanism, &values, &Settings::default()).ok()
                })
                .expect("prepares with values"),
        };
        let unknowns = &prepared.model.unknowns;
        let (coordinates, rates) = (prepared.coordinates.clone(), prepared.rates.clone());
        let mut worst = compare(mechanism, &eq, unknowns, &coordinates, &rates);
        if !prepared.model.has_loops() {
            let mut random = Sequence(path.as_os_str().len() as u64);
            for _ in 0..3 {
                let p: Vec<f64> = coordinates.iter().map(|c| c + random.next()).collect();
                let q: Vec<f64> = rates.iter().map(|r| r + 2.0 * random.next()).collect();
                worst = worst.max(compare(mechanism, &eq, unknowns, &p, &q));
            }
        }
        assert!(
            worst < 1e-12,
            "{name}: symbolic and numeric differ by {worst:e} (relative)"
        );
        compared.push((name, worst, eq.size()));
    }
    for (name, worst, size) in &compared {
        println!("{name:28} {worst:9.1e} {size:8} nodes");
    }
    assert!(
        compared.len() >= 15,
        "only {} examples compared",
        compared.len()
    );
}

/// The full satellite's mass matrix determinant at random points (notes §9.8):
/// det M = I1x I1y I1z μ1³ μ4³ q8² z34² cos²q2 cos²q9 with Bryant angles q1, q2, q3. The thesis's
/// program orients the satellite by Z-X-Z Euler angles (ψ, θ, φ) instead; their angular velocity
/// map has determinant sin θ where Bryant's has cos q2, so there det M has sin²θ in place of
/// cos²q2.
fn satellite_determinants(
    eq: &Equations,
    angle_factor: impl Fn(&HashMap<String, f64>) -> f64,
    names: [&str; 5],
) {
    let [mass1, inertia, mass4, z34, q8] = names;
    let tape = eq.tape();
    let mut random = Sequence(3);
    for _ in 0..10 {
        let mut values: HashMap<String, f64> = HashMap::new();
        for v in eq.variables.positions.iter().chain(&eq.variables.rates) {
            values.insert(v.name.clone(), 1.5 * random.next());
        }
        for p in &eq.variables.parameters {
            let key = if p.meaning.contains('(') {
                p.meaning.clone()
            } else {
                p.name.clone()
            };
            values.insert(key, 1.0 + 0.5 * random.next());
        }
        let named = |p: &lsdc::symbolic::lower::Variable| {
            if p.meaning.contains('(') {
                values[&p.meaning]
            } else {
                values[&p.name]
            }
        };
        let symbols = eq
            .symbol_values(|n| {
                values
                    .get(n)
                    .copied()
                    .or_else(|| {
                        eq.variables
                            .parameters
                            .iter()
                            .find(|p| p.name == n)
                            .map(named)
                    })
                    .or((n == "t" || n.contains('(')).then_some(0.0))
            })
            .expect("values");
        let det = eq.evaluate(&tape, &symbols).mass.determinant();
        let moments: f64 = ["x", "y", "z"]
            .iter()
            .map(|a| values[&format!("{inertia}_{a}(satellite)")])
            .product();
        let cos9 = values["join4.x"].cos();
        let closed = moments
            * values[mass1].powi(3)
            * values[mass4].powi(3)
            * values[q8].powi(2)
            * values[z34].powi(2)
            * angle_factor(&values)
            * cos9
            * cos9;
        assert!(
            (det - closed).abs() < 1e-10 * closed.abs(),
            "det M = {det:e}, closed form {closed:e}"
        );
    }
}

#[test]
fn satellite_mass_matrix_determinant_equals_the_closed_form() {
    // The thesis's program (§3.2.1): Euler angles ps, th, ph.
    let thesis = equations("examples/satellite.lsd");
    assert_eq!(thesis.dimension(), 9);
    let sin_theta = |v: &HashMap<String, f64>| v["join1.th"].sin().powi(2);
    satellite_determinants(
        &thesis,
        sin_theta,
        [
            "mass(satellite)",
            "inertia",
            "mass(reflecteur)",
            "v4T_4_G_z",
            "join3.x",
        ],
    );

    // The same satellite with Bryant angles, as in §9.8.
    let bryant = thesis_with_bryant_angles();
    let cos_q2 = |v: &HashMap<String, f64>| v["join1.b"].cos().powi(2);
    satellite_determinants(
        &bryant,
        cos_q2,
        [
            "mass(satellite)",
            "inertia",
            "mass(reflecteur)",
            "z34",
            "join3.x",
        ],
    );
}

fn thesis_with_bryant_angles() -> Equations {
    let text = "let z12 = ?s ; let z34 = ?s ;
        let satellite = body iframe = 0 end ;
        let bras_primaire = body mass = 0, inertia = 0 end ;
        let bras_secondaire = body mass = 0, inertia = 0 end ;
        let reflecteur = body iframe = [0,0,z34] ++ 1, inertia = 0 end ;
        join earth and satellite.frame with link(x,y,z,a,b,c)
            dof1 = [x,y,z], dof2 = a || [1,0,0], dof3 = b || [0,1,0], dof4 = c || [0,0,1] end ;
        join [0,0,z12] ++ 1 @ satellite and bras_primaire.frame with link(x) dof = x || [1,0,0] end ;
        join bras_primaire.frame and bras_secondaire.frame with link(x) dof = [0,x,0] end ;
        join bras_secondaire.frame and reflecteur.frame with link(x) dof = x || [0,1,0] end ;";
    let compilation = lsdc::driver::compile_text("bryant.lsd", text, None, &LoadOptions::default());
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
    let topology = lsdc::topology::build(mechanism).expect("a topology");
    symbolic::generate(mechanism, &topology).expect("equations")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random trees of mixed joints (some written child first, some welded): the symbolic M and
    /// S equal CRBA and RNEA at a random state.
    #[test]
    fn symbolic_equations_agree_with_the_recursive_algorithms_on_random_trees(
        parents in prop::collection::vec(any::<prop::sample::Index>(), 1..12),
        kinds in prop::collection::vec(0usize..11, 12),
        numbers in prop::collection::vec(-1.5f64..1.5, 64),
    ) {
        let parents: Vec<usize> = parents.iter().enumerate().map(|(i, p)| p.index(i + 1)).collect();
        let text = tree_program(&parents, &kinds, &numbers);
        let options = LoadOptions { library_dirs: Vec::new(), use_environment: false, scene: None };
        let compilation = lsdc::driver::compile_text("tree.lsd", &text, None, &options);
        prop_assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
        let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
        let topology = lsdc::topology::build(mechanism).expect("a topology");
        let eq = symbolic::generate(mechanism, &topology).expect("equations");
        let n = eq.dimension();
        let coordinates: Vec<f64> = (0..n).map(|i| numbers[(3 * i + 1) % numbers.len()]).collect();
        let rates: Vec<f64> = (0..n).map(|i| numbers[(5 * i + 2) % numbers.len()]).collect();
        let worst = compare(mechanism, &eq, &UnknownValues::new(), &coordinates, &rates);
        prop_assert!(worst < 1e-12, "symbolic and numeric differ by {worst:e}\n{text}");
    }
}

/// Notes §9.8: the fixed satellite's generalised forces with joint efforts C12, F23, C34 and a
/// force F4 (fixed axes) on the reflector's centre, all left unknown.
#[test]
fn fixed_satellite_generalised_forces_equal_the_closed_forms() {
    let text = "let z12 = 0.8 ; let z34 = 0.5 ;
        let C12 = ?s ; let F23 = ?s ; let C34 = ?s ; let F4 = ?v ;
        let bras_primaire = body mass = 0, inertia = 0 end ;
        let bras_secondaire = body mass = 0, inertia = 0 end ;
        let reflecteur = body mass = 40, iframe = [0,0,z34] ++ 1, inertia = 0 end ;
        join [0,0,z12] ++ 1 @ earth and bras_primaire.frame with link(x) dof = x || [1,0,0], torque = [C12,0,0] end as hinge ;
        join bras_primaire.frame and bras_secondaire.frame with link(x) dof = [0,x,0], force = [0,F23,0] end as slide ;
        join bras_secondaire.frame and reflecteur.frame with link(x) dof = x || [0,1,0], torque = [0,C34,0] end as tilt ;
        apply force value = F4, body = earth end on reflecteur.iframe ;";
    let compilation =
        lsdc::driver::compile_text("efforts.lsd", text, None, &LoadOptions::default());
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
    let eq = symbolic::generate(
        mechanism,
        &lsdc::topology::build(mechanism).expect("a topology"),
    )
    .expect("equations");
    let tape = eq.tape();
    let mut random = Sequence(17);
    let z34 = 0.5;
    for _ in 0..10 {
        let mut values: HashMap<String, f64> = HashMap::new();
        for v in eq
            .variables
            .positions
            .iter()
            .chain(&eq.variables.rates)
            .chain(&eq.variables.parameters)
        {
            values.insert(v.name.clone(), 2.0 * random.next());
        }
        values.insert("t".to_string(), 0.0);
        let symbols = eq
            .symbol_values(|n| values.get(n).copied())
            .expect("values");
        let forces = eq.evaluate(&tape, &symbols).forces;
        let (q7, q8, q9) = (values["hinge.x"], values["slide.x"], values["tilt.x"]);
        let (c12, f23, c34) = (values["C12"], values["F23"], values["C34"]);
        // `?v` components are named after their unknowns, in order.
        let mut components: Vec<_> = eq
            .variables
            .parameters
            .iter()
            .filter(|p| p.name.starts_with("unknown"))
            .collect();
        components.sort_by_key(|p| p.unknown);
        let f4: Vec<f64> = components.iter().map(|p| values[&p.name]).collect();
        let (s7, c7, s9, c9) = (q7.sin(), q7.cos(), q9.sin(), q9.cos());
        let expected = [
            c12 + f4[1] * (-s7 * q8 - c7 * c9 * z34) + f4[2] * (c7 * q8 - s7 * c9 * z34),
            f23 + f4[1] * c7 + f4[2] * s7,
            c34 + f4[0] * c9 * z34 + f4[1] * s7 * s9 * z34 - f4[2] * c7 * s9 * z34,
        ];
        for i in 0..3 {
            assert!(
                (forces[i] - expected[i]).abs() < 1e-13 * (1.0 + expected[i].abs()),
                "Q{}: {} ≠ {}",
                i + 7,
                forces[i],
                expected[i]
            );
        }
    }
}

/// What the program declares simplifies the equations as they are built: declared zero masses
/// and rotations about coordinate axes leave fewer nodes than the same mechanism with tiny masses
/// or slightly oblique axes, whose equations are numerically almost the same.
#[test]
fn declared_values_simplify_the_equations() {
    let program = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/satellite_fixed.lsd"
    ))
    .expect("example");
    let size = |text: &str| {
        let compilation =
            lsdc::driver::compile_text("variant.lsd", text, None, &LoadOptions::default());
        let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
        symbolic::generate(
            mechanism,
            &lsdc::topology::build(mechanism).expect("a topology"),
        )
        .expect("equations")
        .size()
    };
    let declared = size(&program);
    let with_masses = size(&program.replace(
        "mass = 0, inertia = 0",
        "mass = 1e-9, inertia = [1e-9, 1e-9, 1e-9]",
    ));
    let oblique = size(&program.replace("x || [1, 0, 0]", "x || [1, 1e-9, 0]"));
    println!("declared {declared}, tiny masses {with_masses}, oblique axis {oblique}");
    assert!(
        declared < with_masses && declared < oblique,
        "declared {declared}, tiny masses {with_masses}, oblique axis {oblique}"
    );
}
