//! The LSD program of a URDF robot, and the warnings for what it leaves out.

use std::collections::HashSet;

use nalgebra::Vector3;
use urdf_rs::{JointType, Robot};

use super::check::reads;
use super::document::{attributes, child, children, parent, tag_of, Element, Source};
use super::inertia::{axis_angle, is_massless, principal, tensor};
use super::lsd::{comment, count, displacement, factor, frame, planar, rpy_factors, vector};
use super::names::{is_identifier, lsd_name, reserved};
use super::options::ImportOptions;
use super::tree::Tree;
use crate::diag::number::shortest as number;
use crate::diag::Diagnostic;

#[derive(Default)]
struct Names {
    links: Vec<String>,
    joints: Vec<String>,
    /// The join of the root link to earth.
    base: String,
}

/// Writes the LSD program of a robot that urdf-rs read, collecting the warnings on the way.
pub(super) struct Importer<'a> {
    robot: &'a Robot,
    source: &'a Source<'a>,
    tree: &'a Tree,
    options: &'a ImportOptions,
    names: Names,
    warnings: Vec<Diagnostic>,
}

impl<'a> Importer<'a> {
    pub(super) fn new(
        robot: &'a Robot,
        source: &'a Source<'a>,
        tree: &'a Tree,
        options: &'a ImportOptions,
    ) -> Importer<'a> {
        Importer {
            robot,
            source,
            tree,
            options,
            names: Names::default(),
            warnings: Vec::new(),
        }
    }

    /// The program, and the warnings in the order they were found.
    pub(super) fn program(
        mut self,
        file_name: &str,
    ) -> Result<(String, Vec<Diagnostic>), Diagnostic> {
        let text = self.write(file_name)?;
        Ok((text, self.warnings))
    }

    fn write(&mut self, file_name: &str) -> Result<String, Diagnostic> {
        self.assign_names();
        let mut out = self.header(file_name);
        out += "import joints ;\n";
        if self.options.gravity {
            out += "import gravity ;\n";
        }
        out += "\n(* Links *)\n";
        for index in 0..self.robot.links.len() {
            out += &self.link(index);
        }
        out += "\n(* Joints *)\n";
        out += &self.base_joint();
        for index in self.joint_order() {
            out += &self.joint(index)?;
            self.joint_warnings(index);
        }
        out += &self.gravity();
        self.geometry_warning();
        self.unsupported_warnings();
        Ok(out)
    }

    /// The joints in the URDF's order, except that a mimic joint comes after the joint it
    /// follows (its join names its leader, which must be declared before it).
    fn joint_order(&self) -> Vec<usize> {
        let joints = &self.robot.joints;
        let leader = |i: usize| {
            let name = &joints[i].mimic.as_ref()?.joint;
            joints.iter().position(|j| &j.name == name)
        };
        let mut order: Vec<usize> = Vec::new();
        let mut pending: Vec<usize> = Vec::new();
        for index in 0..joints.len() {
            match leader(index) {
                Some(l) if !order.contains(&l) => pending.push(index),
                _ => order.push(index),
            }
            // Each joint placed may release the mimics that wait for it, and theirs in turn.
            while let Some(k) =
                (pending.iter()).position(|&p| leader(p).is_some_and(|l| order.contains(&l)))
            {
                order.push(pending.remove(k));
            }
        }
        // A cycle of mimics: in the URDF's order, refused where its coupling is written.
        order.extend(pending);
        order
    }

    fn header(&self, file_name: &str) -> String {
        let root = &self.names.links[self.tree.root];
        let base = if self.options.floating_base {
            format!(
                "is free, a floating base joined to earth by `{}`",
                self.names.base
            )
        } else {
            "is welded to earth".to_string()
        };
        let gravity = if self.options.gravity {
            "Standard gravity pulls every link with mass along -z."
        } else {
            "No gravity."
        };
        let robot = if self.robot.name.is_empty() {
            "Robot".to_string()
        } else {
            format!("Robot `{}`", self.robot.name)
        };
        let text = format!(
            "{robot}, imported from the URDF file `{file_name}`.\n   \
             Units are URDF's: m, rad, kg, kg m². Each link is a body whose reference frame is the link\n   \
             frame, with `iframe` at its centre of mass along its principal axes of inertia. Each joint\n   \
             joins its origin on the parent link to the child link's frame.\n   \
             The root link `{root}` {base}.\n   \
             {gravity}"
        );
        comment(&text) + "\n\n"
    }

    /// Gives every link and joint its LSD name: first the names that can stay as they are, in the
    /// order of the file, links first; then the others, renamed by [`lsd_name`] and made unique.
    fn assign_names(&mut self) {
        let robot = self.robot;
        let requests: Vec<(&str, &str)> = robot
            .links
            .iter()
            .map(|l| ("link", l.name.as_str()))
            .chain(robot.joints.iter().map(|j| ("joint", j.name.as_str())))
            .collect();
        let mut used = HashSet::new();
        let mut assigned: Vec<Option<String>> = requests
            .iter()
            .map(|(_, name)| {
                (lsd_name(name) == *name && used.insert(name.to_string())).then(|| name.to_string())
            })
            .collect();
        for (slot, &(tag, name)) in assigned.iter_mut().zip(&requests) {
            if slot.is_none() {
                let mut candidate = lsd_name(name);
                while !used.insert(candidate.clone()) {
                    candidate.push('_');
                }
                self.warnings
                    .push(self.rename_warning(tag, name, &candidate));
                *slot = Some(candidate);
            }
        }
        let mut names = assigned.into_iter().flatten();
        self.names.links = names.by_ref().take(robot.links.len()).collect();
        self.names.joints = names.collect();
        let mut base = if self.options.floating_base {
            "root_joint"
        } else {
            "world_joint"
        }
        .to_string();
        while used.contains(&base) {
            base.push('_');
        }
        self.names.base = base;
    }

    fn rename_warning(&self, tag: &str, name: &str, lsd: &str) -> Diagnostic {
        let reason = if lsd_name(name) == name {
            "another link or joint has this name (links and joints share one name space in LSD)"
                .to_string()
        } else if reserved().contains(name) {
            format!("`{name}` is a builtin or standard library name that the program uses")
        } else if is_identifier(&format!("{name}_")) && !is_identifier(name) {
            format!("`{name}` is an LSD keyword")
        } else {
            "an LSD name is letters, digits and `_`, and does not start with a digit".to_string()
        };
        let element = self.source.element(tag, name);
        Diagnostic::warning("W1001", format!("{tag} `{name}` is called `{lsd}` in LSD"))
            .primary(self.source.attribute_span(element, "name"), "renamed")
            .note(reason)
    }

    /// The program's comment after a renamed link or joint: its URDF name.
    fn original(&self, tag: &str, name: &str, lsd: &str) -> String {
        if name == lsd {
            String::new()
        } else {
            format!(" {}", comment(&format!("URDF {tag} \"{name}\"")))
        }
    }

    fn link(&mut self, index: usize) -> String {
        let link = &self.robot.links[index];
        let inertial = &link.inertial;
        let body = if is_massless(inertial) {
            "body mass = 0, inertia = 0 end".to_string()
        } else {
            let principal = principal(&tensor(inertial));
            self.check_inertia(index, &principal.moments);
            let mut rotation = rpy_factors(&inertial.origin.rpy);
            rotation.extend(
                principal
                    .axes
                    .as_ref()
                    .and_then(axis_angle)
                    .map(|(angle, axis)| factor(angle, axis)),
            );
            format!(
                "body mass = {}, iframe = {}, inertia = {} end",
                number(inertial.mass.value),
                displacement(inertial.origin.xyz.0, &rotation),
                vector(principal.moments.into())
            )
        };
        let name = &self.names.links[index];
        format!(
            "let {name} = {body} ;{}\n",
            self.original("link", &link.name, name)
        )
    }

    /// A warning when the link's mass and inertia are not those of a rigid body.
    fn check_inertia(&mut self, index: usize, moments: &Vector3<f64>) {
        let link = &self.robot.links[index];
        let mass = link.inertial.mass.value;
        let tolerance = 1e-12 * moments.amax();
        let mut problems = Vec::new();
        if mass < 0.0 {
            problems.push(format!("its mass {} is negative", number(mass)));
        } else if mass == 0.0 {
            problems.push("it has inertia but no mass".to_string());
        }
        if moments.min() < -tolerance {
            problems.push(
                "its inertia tensor is not positive definite (a negative principal moment)"
                    .to_string(),
            );
        } else if moments.min() <= tolerance {
            problems.push("its inertia tensor is not positive definite (a zero principal moment, as of a point mass or a thin rod)".to_string());
        }
        let mut sorted = [moments.x, moments.y, moments.z];
        sorted.sort_by(f64::total_cmp);
        if sorted[0] + sorted[1] < sorted[2] - tolerance {
            problems.push("its principal moments violate the triangle inequality".to_string());
        }
        if problems.is_empty() {
            return;
        }
        let element = self.source.element("link", &link.name);
        let inertial = child(element, "inertial");
        let at = inertial
            .and_then(|i| child(i, "inertia"))
            .or(inertial)
            .unwrap_or(element);
        self.warnings.push(
            Diagnostic::warning("W1010", format!("the inertia of link `{}` is not physically consistent: {}", link.name, problems.join("; ")))
                .primary(self.source.span(at), "imported as written")
                .note(format!("mass {}, principal moments {}, {}, {}", number(mass), number(moments.x), number(moments.y), number(moments.z)))
                .note("a rigid body has a positive mass and principal moments with I1 + I2 ≥ I3 for any two of them and the third")
                .help("the moments are about the centre of mass, in kg m²: check the URDF's `<inertia>` and `<mass>`"),
        );
    }

    fn base_joint(&self) -> String {
        let link = if self.options.floating_base {
            "free"
        } else {
            "weld"
        };
        format!(
            "join earth and {} with {link} as {} ;\n",
            self.names.links[self.tree.root], self.names.base
        )
    }

    fn joint(&mut self, index: usize) -> Result<String, Diagnostic> {
        let joint = &self.robot.joints[index];
        let (parent, child) = self.tree.joint_links[index];
        let first = frame(&joint.origin, &self.names.links[parent]);
        let link = self.joint_link(index)?;
        let name = &self.names.joints[index];
        Ok(format!(
            "join {first} and {} with {link} as {name} ;{}\n",
            self.names.links[child],
            self.original("joint", &joint.name, name)
        ))
    }

    /// The LSD link of a URDF joint type: a link of `joints`, or where the joint mimics another
    /// or has `<dynamics>`, a link with its fields written out.
    fn joint_link(&mut self, index: usize) -> Result<String, Diagnostic> {
        let stops = self.stops(index);
        let mut fields = self.coupling_fields(index)?;
        let joint = &self.robot.joints[index];
        if let Some(dynamics) = joint.dynamics.as_ref() {
            if dynamics.friction != 0.0 {
                fields.push(format!("friction = {}", number(dynamics.friction)));
            }
            if dynamics.damping != 0.0 {
                fields.push(format!("damping = {}", number(dynamics.damping)));
            }
        }
        let dof = match joint.joint_type {
            JointType::Revolute | JointType::Continuous => "q ||",
            JointType::Prismatic => "q *",
            _ => "",
        };
        if !fields.is_empty() && !dof.is_empty() {
            let mut all = vec![format!("dof = {dof} {}", vector(self.axis(index)?.into()))];
            if let Some((lower, upper)) = stops {
                all.push(format!(
                    "lower = {}, upper = {}, restitution = 0",
                    number(lower),
                    number(upper)
                ));
            }
            all.extend(fields);
            return Ok(format!("link(q) {} end", all.join(", ")));
        }
        Ok(match self.robot.joints[index].joint_type {
            JointType::Revolute => match stops {
                Some((lower, upper)) => format!(
                    "limited_revolute({}, {}, {}, 0)",
                    vector(self.axis(index)?.into()),
                    number(lower),
                    number(upper)
                ),
                None => format!("revolute({})", vector(self.axis(index)?.into())),
            },
            JointType::Continuous => format!("continuous({})", vector(self.axis(index)?.into())),
            JointType::Prismatic => match stops {
                Some((lower, upper)) => format!(
                    "limited_prismatic({}, {}, {}, 0)",
                    vector(self.axis(index)?.into()),
                    number(lower),
                    number(upper)
                ),
                None => format!("prismatic({})", vector(self.axis(index)?.into())),
            },
            JointType::Planar => planar(&self.axis(index)?),
            JointType::Fixed => "weld".to_string(),
            JointType::Floating => "free".to_string(),
            JointType::Spherical => "spherical".to_string(),
        })
    }

    /// The fields of a mimic joint (`mimic`, `mimic_multiplier`, `mimic_offset`), its leader's
    /// own coupling composed in when the leader mimics a joint too; none for other joints. A
    /// leader that is not a joint with one coordinate, or a cycle of mimics, is E0470 / E0472.
    fn coupling_fields(&self, index: usize) -> Result<Vec<String>, Diagnostic> {
        let single = |j: &urdf_rs::Joint| {
            matches!(
                j.joint_type,
                JointType::Revolute | JointType::Continuous | JointType::Prismatic
            )
        };
        if !single(&self.robot.joints[index]) {
            // A fixed (or multi-coordinate) joint's `<mimic>` has no coordinate to couple.
            return Ok(Vec::new());
        }
        let (mut multiplier, mut offset) = (1.0, 0.0);
        let mut current = index;
        let mut visited = vec![index];
        let joints = &self.robot.joints;
        while let Some(mimic) = joints[current].mimic.as_ref() {
            let element = self.source.element("joint", &joints[index].name);
            let at =
                child(element, "mimic").map_or(self.source.span(element), |m| self.source.span(m));
            let leader = joints.iter().position(|j| j.name == mimic.joint);
            let single = |j: &urdf_rs::Joint| {
                matches!(
                    j.joint_type,
                    JointType::Revolute | JointType::Continuous | JointType::Prismatic
                )
            };
            let Some(leader) = leader.filter(|&l| single(&joints[l]) && single(&joints[current]))
            else {
                return Err(Diagnostic::error("E0470", format!("joint `{}` mimics `{}`, which is not a revolute, continuous or prismatic joint of the robot", joints[current].name, mimic.joint))
                    .primary(at, "the mimic")
                    .help("a mimic couples two joints with one coordinate each"));
            };
            if visited.contains(&leader) {
                return Err(Diagnostic::error(
                    "E0472",
                    format!("the mimic joints of `{}` form a cycle", joints[index].name),
                )
                .primary(at, "the mimic")
                .help("one joint of the cycle must move on its own"));
            }
            visited.push(leader);
            // q = m q_current + o, q_current = m' q_leader + o'.
            let (m, o) = (mimic.multiplier.unwrap_or(1.0), mimic.offset.unwrap_or(0.0));
            offset += multiplier * o;
            multiplier *= m;
            current = leader;
        }
        if current == index {
            return Ok(Vec::new());
        }
        Ok(vec![
            format!("mimic = {}", self.names.joints[current]),
            format!("mimic_multiplier = {}", number(multiplier)),
            format!("mimic_offset = {}", number(offset)),
        ])
    }

    /// The position limits of a revolute or prismatic joint, when its `<limit>` gives a range
    /// (lower < upper; URDF's default 0, 0 gives none): imported as stops on its coordinate,
    /// with restitution 0 (URDF says nothing of the impact).
    fn stops(&self, index: usize) -> Option<(f64, f64)> {
        let joint = &self.robot.joints[index];
        let element = self.source.element("joint", &joint.name);
        child(element, "limit")?;
        let (lower, upper) = (joint.limit.lower, joint.limit.upper);
        let limited = matches!(joint.joint_type, JointType::Revolute | JointType::Prismatic);
        (limited && lower < upper && lower.is_finite() && upper.is_finite())
            .then_some((lower, upper))
    }

    /// The joint's axis as a unit vector; a warning when the URDF's was not one.
    fn axis(&mut self, index: usize) -> Result<Vector3<f64>, Diagnostic> {
        let joint = &self.robot.joints[index];
        let axis = Vector3::from(joint.axis.xyz.0);
        let element = self.source.element("joint", &joint.name);
        let at = child(element, "axis").map_or(self.source.span(element), |a| {
            self.source.attribute_span(a, "xyz")
        });
        if axis == Vector3::zeros() {
            return Err(Diagnostic::error(
                "E1008",
                format!("the axis of joint `{}` is zero", joint.name),
            )
            .primary(at, "no direction")
            .help("give the direction of the motion, e.g. `<axis xyz=\"0 0 1\"/>`"));
        }
        let length = axis.norm();
        if (length - 1.0).abs() <= 4.0 * f64::EPSILON {
            return Ok(axis);
        }
        // Scaled first so that huge or tiny components neither overflow nor underflow.
        let unit = (axis / axis.amax()).normalize();
        if (length - 1.0).abs() > 1e-9 {
            self.warnings.push(
                Diagnostic::warning(
                    "W1009",
                    format!("the axis of joint `{}` is not a unit vector", joint.name),
                )
                .primary(at, format!("its length is {}", number(length)))
                .note(format!("it is imported as {}", vector(unit.into()))),
            );
        }
        Ok(unit)
    }

    /// What each joint's elements say that LSD does not model.
    fn joint_warnings(&mut self, index: usize) {
        let joint = &self.robot.joints[index];
        let element = self.source.element("joint", &joint.name);
        let child = |tag: &str| child(element, tag);
        let mut found = Vec::new();
        match (child("limit"), self.stops(index)) {
            (Some(limit), Some(_)) => found.push(self.joint_warning(limit, "W1002", format!("the effort and velocity limits of joint `{}` are not modelled", joint.name))
                .help("its position limits are imported as stops (`lower`, `upper`, restitution 0); its efforts and rates are not bounded")),
            (Some(limit), None) => found.push(self.joint_warning(limit, "W1002", format!("the limits of joint `{}` are not modelled", joint.name))
                .help("the imported joint moves without limits: its `<limit>` gives no range of positions")),
            (None, _) => {}
        }
        if let Some(controller) = child("safety_controller") {
            found.push(
                self.joint_warning(
                    controller,
                    "W1005",
                    format!(
                        "the safety controller of joint `{}` is not modelled",
                        joint.name
                    ),
                )
                .help("soft limits and controller gains are not part of the mechanism"),
            );
        }
        if let Some(calibration) = child("calibration") {
            found.push(
                self.joint_warning(
                    calibration,
                    "W1006",
                    format!("the calibration of joint `{}` is not imported", joint.name),
                )
                .help("reference positions of sensors are not part of the mechanism"),
            );
        }
        self.warnings.extend(found);
    }

    /// A warning at a joint's child element, with its attributes as the URDF gives them.
    fn joint_warning(&self, element: Element, code: &'static str, message: String) -> Diagnostic {
        let given: Vec<String> = attributes(element)
            .map(|(name, value)| format!("{name} = {value}"))
            .collect();
        let diagnostic =
            Diagnostic::warning(code, message).primary(self.source.span(element), "not imported");
        if given.is_empty() {
            diagnostic
        } else {
            diagnostic.note(format!("the URDF gives {}", given.join(", ")))
        }
    }

    fn gravity(&self) -> String {
        if !self.options.gravity {
            return String::new();
        }
        let mut out = String::from(
            "\n(* Gravity: the weight of every link with mass, at its centre of mass *)\n",
        );
        for (link, name) in self.robot.links.iter().zip(&self.names.links) {
            if link.inertial.mass.value != 0.0 {
                out += &format!("apply weight({name}) on {name}.iframe ;\n");
            }
        }
        out
    }

    /// One warning for all the shapes and materials, which LSD has no place for.
    fn geometry_warning(&mut self) {
        let source = self.source;
        let root = source.root();
        let in_robot = |element: Element| parent(element) == Some(root);
        let is_top_link = |element: Element| tag_of(element) == "link" && in_robot(element);
        let is_shape = |element: &Element| match tag_of(*element).as_ref() {
            "visual" | "collision" => parent(*element).is_some_and(is_top_link),
            "material" => in_robot(*element),
            _ => false,
        };
        let Some(first) = root.descendants().find(is_shape) else {
            return;
        };
        let links = &self.robot.links;
        let shaped = links
            .iter()
            .filter(|l| !l.visual.is_empty() || !l.collision.is_empty())
            .count();
        let visual = links.iter().filter(|l| !l.visual.is_empty()).count();
        let collision = links.iter().filter(|l| !l.collision.is_empty()).count();
        let materials = source.top_level("material").count();
        let message = match shaped {
            0 => "the robot's materials are not imported".to_string(),
            n => format!(
                "the visual and collision geometry of {} is not imported",
                count(n, "link")
            ),
        };
        let mut diagnostic =
            Diagnostic::warning("W1007", message).primary(source.span(first), "the first of them");
        if shaped > 0 {
            let links = count(links.len(), "link");
            diagnostic = diagnostic.note(format!("of the robot's {links}, {visual} with `<visual>` and {collision} with `<collision>` elements"));
        }
        if materials > 0 {
            diagnostic = diagnostic.note(format!(
                "the robot defines {}",
                count(materials, "material")
            ));
        }
        let help = "LSD describes bodies, joints and efforts, not shapes: the bodies' mass properties come from `<inertial>`";
        self.warnings.push(diagnostic.help(help));
    }

    /// A warning for each kind of element that urdf-rs does not read: in the robot, any element
    /// but a link, joint or material; in a link or a joint, any element urdf-rs does not read
    /// there (see [`READ`](super::check::READ)), such as Pinocchio's `<collision_checking>`.
    fn unsupported_warnings(&mut self) {
        let source = self.source;
        // (the link or joint the elements are in, or `None` for the robot; their tag; them)
        let mut groups: Vec<(Option<&str>, String, Vec<Element>)> = Vec::new();
        for top in children(source.root()) {
            let owner = match tag_of(top).as_ref() {
                "link" => Some("link"),
                "joint" => Some("joint"),
                "material" => continue,
                _ => None,
            };
            let found: Vec<Element> = match owner {
                Some(owner) => children(top)
                    .filter(|&c| !reads(owner, &tag_of(c)))
                    .collect(),
                None => vec![top],
            };
            for element in found {
                let tag = tag_of(element);
                match groups.iter_mut().find(|(o, t, _)| *o == owner && *t == tag) {
                    Some((_, _, all)) => all.push(element),
                    None => groups.push((owner, tag.into_owned(), vec![element])),
                }
            }
        }
        for (owner, tag, all) in groups {
            let place = match owner {
                None => String::new(),
                Some(owner) => {
                    let mut names: Vec<&str> = all
                        .iter()
                        .filter_map(|&e| parent(e))
                        .map(|p| p.attribute("name").unwrap_or(""))
                        .collect();
                    names.dedup();
                    match names.as_slice() {
                        [name] => format!(" of {owner} `{name}`"),
                        _ => format!(" of {} {owner}s", names.len()),
                    }
                }
            };
            let message = match all.len() {
                1 => format!("`<{tag}>`{place} is not imported"),
                n => format!("{n} `<{tag}>` elements{place} are not imported"),
            };
            let mut diagnostic =
                Diagnostic::warning("W1008", message).primary(source.span(all[0]), "not imported");
            if all.len() > 1 {
                let lines: Vec<String> = all[1..]
                    .iter()
                    .map(|&e| source.line(e).to_string())
                    .collect();
                let others = if lines.len() == 1 {
                    "the other is at line"
                } else {
                    "the others are at lines"
                };
                diagnostic = diagnostic.note(format!("{others} {}", lines.join(", ")));
            }
            let help = match (owner, tag.as_str()) {
                (None, "transmission") => {
                    "transmissions (actuators, gear ratios) are outside the mechanism: apply the actuators' efforts with `apply` or link efforts"
                }
                (None, "gazebo") => "settings for the Gazebo simulator have no meaning in LSD",
                (None, _) => "LSD imports a robot's links and joints",
                (Some(_), "collision_checking") => "Pinocchio's collision-checking settings are about shapes, which LSD does not describe",
                (Some("link"), _) => "LSD imports a link's mass properties, its `<inertial>`",
                (Some(_), _) => "LSD imports a joint's `type`, `<origin>`, `<parent>`, `<child>` and `<axis>`",
            };
            self.warnings.push(diagnostic.help(help));
        }
    }
}
