//! The elaborated mechanism: the bodies, links, joins, efforts and unknowns a program declares,
//! and the summary `lsdc check` prints.

use std::collections::{BTreeSet, HashMap};
use std::fmt::Write;

use serde::Serialize;

use super::value::*;
use crate::source::Span;
use crate::syntax::ast::Name;

/// A quantity the program either declares or leaves generic. A generic quantity is made of
/// generated unknowns (kind [`UnknownKind::Generic`]) that the compiler names, as the thesis's
/// compiler does for `mu_1` or `MIg_1`.
#[derive(Clone, Debug, PartialEq)]
pub enum Quantity<T> {
    Declared(T),
    Generic(T),
}

impl<T> Quantity<T> {
    pub fn value(&self) -> &T {
        match self {
            Quantity::Declared(v) | Quantity::Generic(v) => v,
        }
    }

    pub fn is_declared(&self) -> bool {
        matches!(self, Quantity::Declared(_))
    }
}

#[derive(Clone, Debug)]
pub struct Body {
    /// The `let` name the body was first bound to.
    pub name: Option<Name>,
    pub span: Span,
    pub mass: Quantity<Scalar>,
    /// Displacement from the reference frame to the principal inertia frame; a generic one is a
    /// translation followed by Bryant angles (rotations about x, y, z).
    pub iframe: Quantity<Displacement>,
    /// Principal moments of inertia.
    pub inertia: Quantity<Vector>,
}

/// A link: its joint coordinates, its dof chain in them, and the known link efforts.
#[derive(Clone, Debug)]
pub struct Link {
    pub name: Option<Name>,
    pub span: Span,
    pub coordinates: Vec<Name>,
    /// `dof` (one element) or `dof1`, `dof2`, … in order.
    pub dofs: Vec<Displacement>,
    /// `force`/`torque` (index 0) and `forceN`/`torqueN` (index N), vectors in the joint frame.
    pub forces: Vec<(u8, Vector)>,
    pub torques: Vec<(u8, Vector)>,
    /// `potential = ...`: the potential energy its efforts derive from, for the energy report.
    pub potential: Option<Scalar>,
    /// The fields few links write (a contact, stops, a rotor, a mimic coupling, friction),
    /// boxed together and absent when none is written: inline they made every link of a
    /// chain 150 bytes larger. Read through [`Link::contact`], [`Link::stops`] and the like.
    extras: Option<Box<LinkExtras>>,
}

/// The rarely written fields of a link (see [`Link`]).
#[derive(Clone, Debug, Default)]
pub struct LinkExtras {
    /// `rolling(r)` or `sliding(r, f)`: a contact between a plane and a round body, not a joint
    /// of the tree (see [`Contact`]).
    pub contact: Option<ContactLaw>,
    /// `lower = ..., upper = ..., restitution = ...`: stops on its coordinate, hit with that
    /// coefficient of restitution (0 when not given).
    pub stops: LinkStops,
    /// `rotor_inertia = ..., gear_ratio = ..., rotor_axis = ...`: a motor's rotor geared to its
    /// coordinate.
    pub rotor: LinkRotor,
    /// `mimic = leader, mimic_multiplier = m, mimic_offset = o`: its coordinate follows the
    /// leader join's, q = m q_leader + o.
    pub mimic: LinkMimic,
    /// `friction = F, damping = c`: dry (Coulomb) and viscous friction opposing the rate of its
    /// coordinate.
    pub friction: LinkFriction,
}

/// What a link without extras reads: nothing written.
static NO_EXTRAS: LinkExtras = LinkExtras {
    contact: None,
    stops: LinkStops {
        lower: None,
        upper: None,
        restitution: None,
    },
    rotor: LinkRotor {
        inertia: None,
        ratio: None,
        axis: None,
    },
    mimic: LinkMimic {
        leader: None,
        multiplier: None,
        offset: None,
    },
    friction: LinkFriction {
        dry: None,
        viscous: None,
    },
};

impl Link {
    /// A link in these coordinates with nothing else written yet.
    pub fn new(span: Span, coordinates: Vec<Name>) -> Link {
        Link {
            name: None,
            span,
            coordinates,
            dofs: Vec::new(),
            forces: Vec::new(),
            torques: Vec::new(),
            potential: None,
            extras: None,
        }
    }

    fn extras(&self) -> &LinkExtras {
        self.extras.as_deref().unwrap_or(&NO_EXTRAS)
    }

    /// The rarely written fields, to write one (made when the first is written).
    pub fn extras_mut(&mut self) -> &mut LinkExtras {
        self.extras.get_or_insert_with(Default::default)
    }

    /// Whether one of the rarely written fields is written (a contact, stops, a rotor, a mimic,
    /// friction).
    pub fn has_extras(&self) -> bool {
        self.extras.is_some()
    }

    /// The rarely written fields when one is written, to change them in place.
    pub fn written_extras_mut(&mut self) -> Option<&mut LinkExtras> {
        self.extras.as_deref_mut()
    }

    /// `rolling(r)` or `sliding(r, f)`: see [`LinkExtras::contact`].
    pub fn contact(&self) -> Option<&ContactLaw> {
        self.extras().contact.as_ref()
    }

    /// The stops of its coordinate, as declared: see [`LinkExtras::stops`].
    pub fn stops(&self) -> &LinkStops {
        &self.extras().stops
    }

    /// A geared rotor, as declared: see [`LinkExtras::rotor`].
    pub fn rotor(&self) -> &LinkRotor {
        &self.extras().rotor
    }

    /// A mimic coupling, as declared: see [`LinkExtras::mimic`].
    pub fn mimic(&self) -> &LinkMimic {
        &self.extras().mimic
    }

    /// Friction in its coordinate, as declared: see [`LinkExtras::friction`].
    pub fn friction(&self) -> &LinkFriction {
        &self.extras().friction
    }
}

/// How a round body touches a plane: which rows a contact adds to the equations of motion.
#[derive(Clone, Debug)]
pub struct ContactLaw {
    /// The body's radius: of a sphere about the second frame's origin (or a cylinder whose
    /// axis stays parallel to the plane), or of a disc's rim.
    pub radius: Scalar,
    /// Which point of the body touches the plane.
    pub shape: RoundShape,
    /// `None`: rolling without slipping (the contact point of the body has no velocity relative
    /// to the plane). `Some(f)`: sliding under Coulomb friction of coefficient f.
    pub friction: Option<Scalar>,
    /// Where `rolling(...)` or `sliding(...)` is written.
    pub span: Span,
}

/// The shape of a contact's round body, which decides where it touches the plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoundShape {
    /// `rolling(r)`, `sliding(r, f)`: a sphere of radius r about the second frame's origin,
    /// touching at the centre moved by r against the plane's normal.
    Sphere,
    /// `rolling_disc(r)`, `sliding_disc(r, f)`: a thin disc (a coin, a wheel) of radius r
    /// centred on the second frame's origin, its axis the frame's z axis, touching at the
    /// lowest point of its rim.
    Disc,
}

/// `join plane and ball with rolling(r)`: a contact between the plane through the first frame's
/// origin, normal to its z axis, and a round body centred on the second frame's origin. It is
/// a constraint on the tree's motion (a bilateral normal row, and for rolling two
/// non-holonomic tangential rows), not a joint: the bodies are joined to the tree otherwise.
#[derive(Clone, Debug)]
pub struct Contact {
    /// `as name`; unnamed contacts are called `contact1`, `contact2`, … in declaration order.
    pub name: Option<Name>,
    pub first: Frame,
    pub second: Frame,
    pub link: LinkId,
    pub span: Span,
}

/// The stops of a link's coordinate, as declared (each optional).
#[derive(Clone, Debug, Default)]
pub struct LinkStops {
    pub lower: Option<Scalar>,
    pub upper: Option<Scalar>,
    pub restitution: Option<Scalar>,
}

impl LinkStops {
    /// Whether any of the stops' fields is written.
    pub fn is_declared(&self) -> bool {
        self.lower.is_some() || self.upper.is_some() || self.restitution.is_some()
    }
}

/// A rotor spinning about `axis` (in the join's first frame) relative to the body of that frame
/// at `ratio` times the rate of the link's coordinate, with moment of inertia `inertia` about
/// its axis; each optional as declared.
#[derive(Clone, Debug, Default)]
pub struct LinkRotor {
    pub inertia: Option<Scalar>,
    pub ratio: Option<Scalar>,
    pub axis: Option<Vector>,
}

impl LinkRotor {
    /// Whether any of the rotor's fields is written.
    pub fn is_declared(&self) -> bool {
        self.inertia.is_some() || self.ratio.is_some() || self.axis.is_some()
    }
}

/// A holonomic coupling of the link's coordinate to the coordinate of another join, `leader`:
/// q = multiplier × q_leader + offset (multiplier 1 and offset 0 when not given).
#[derive(Clone, Debug, Default)]
pub struct LinkMimic {
    pub leader: Option<(JoinId, Span)>,
    pub multiplier: Option<Scalar>,
    pub offset: Option<Scalar>,
}

impl LinkMimic {
    /// Whether any of the coupling's fields is written.
    pub fn is_declared(&self) -> bool {
        self.leader.is_some() || self.multiplier.is_some() || self.offset.is_some()
    }
}

/// Friction in a link's coordinate: a dry (Coulomb) force or torque of constant magnitude
/// `dry` opposing its rate, holding it at rest while the force needed to hold it is within
/// `dry`, and a viscous one, −`viscous` × rate; each optional as declared.
#[derive(Clone, Debug, Default)]
pub struct LinkFriction {
    pub dry: Option<Scalar>,
    pub viscous: Option<Scalar>,
}

impl LinkFriction {
    /// Whether any of the friction's fields is written.
    pub fn is_declared(&self) -> bool {
        self.dry.is_some() || self.viscous.is_some()
    }
}

/// `join first and second with link`: the link's dof chain, in its own coordinates, carries the
/// first frame onto the second.
#[derive(Clone, Debug)]
pub struct Join {
    /// `as crank`; unnamed joins are called `join1`, `join2`, … in declaration order.
    pub name: Option<Name>,
    pub first: Frame,
    pub second: Frame,
    pub link: LinkId,
    pub span: Span,
}

/// `initial crank.q = 0.3 fixed` (order 0) or `initial crank.q' = 1` (order 1).
#[derive(Clone, Debug)]
pub struct InitialValue {
    pub join: JoinId,
    pub coordinate: usize,
    pub order: u32,
    pub value: Scalar,
    /// Held at its value by assembly.
    pub fixed: bool,
    /// A starting point for assembly only, moved without a warning.
    pub guess: bool,
    pub span: Span,
}

/// `drive crank.q = 2 * pi * time`: a coordinate imposed as a law of time (its rates are the
/// law's derivatives).
#[derive(Clone, Debug)]
pub struct Drive {
    pub join: JoinId,
    pub coordinate: usize,
    pub law: Scalar,
    /// The driven coordinate as written, and the law.
    pub span: Span,
    pub law_span: Span,
    /// `lock crank.q = 0.3` (in a scene): the coordinate held at one value, its law a
    /// constant of the program.
    pub locked: bool,
}

/// `drive position(nacelle) = [x(time), y(time), z(time)]`: the position of a frame's origin
/// in the fixed axes imposed as three laws of time (`kinematics::position_drives`).
#[derive(Clone, Debug)]
pub struct PositionDrive {
    pub frame: Frame,
    /// The frame as written (`nacelle`, `arm.tip`): the name of its efforts.
    pub name: String,
    pub law: Vector,
    /// The driven frame as written, and the law.
    pub span: Span,
    pub law_span: Span,
}

/// A state: a variable with its own differential equation, integrated with the motion (an
/// integral of an error, a motor's current, an estimate). `let s = state(x0);` makes it,
/// `rate s = f;` gives its derivative; `let u = sample(period, x0);` makes a sampled one,
/// `update u = f;` gives its value after each sampling instant.
#[derive(Clone, Debug)]
pub struct StateVariable {
    /// The name it is first bound to (`integral`, `motor[2]:current`).
    pub name: Option<Name>,
    /// Its value at the start of a run (`x0`).
    pub initial: Scalar,
    /// Its derivative (`rate s = ...`), or for a sampled state its next value
    /// (`update s = ...`), and where it was declared.
    pub rate: Option<(Scalar, Span)>,
    /// For a sampled state (`sample(period, x0)`), its period: its value is held between the
    /// sampling instants and changes at each one by its `update`.
    pub period: Option<Scalar>,
    /// The call `state(x0)` or `sample(period, x0)` that made it; for a value input, its name
    /// in the declaration.
    pub span: Span,
    /// A value input (`input voltage = 0;`): a state held at its start value until the caller
    /// of the run sets it (its rate zero), as a sampled state is held between its instants.
    pub input: bool,
}

impl StateVariable {
    /// Its name in columns and messages: the name it was bound to, else its number.
    pub fn label(&self, index: usize) -> String {
        match &self.name {
            Some(name) => name.to_string(),
            None => format!("state#{}", index + 1),
        }
    }
}

/// `actuate shoulder.q = law`: a generalised effort along a coordinate (a torque about a
/// revolute joint's axis, a force along a prismatic one), whose law may read the model
/// (`mass_matrix`, `bias`, `gravity_effort`, `inverse_dynamics`), which does not count it.
#[derive(Clone, Debug)]
pub struct Actuator {
    pub join: JoinId,
    pub coordinate: usize,
    pub law: Scalar,
    /// The actuated coordinate as written, and the law.
    pub span: Span,
    pub law_span: Span,
}

/// `input swing.q = 0`: the generalised effort along a joint coordinate, declared an input of
/// the program, which an importer or a study sets; `start` is its value until set.
#[derive(Clone, Debug)]
pub struct DeclaredInput {
    pub join: JoinId,
    pub coordinate: usize,
    pub start: f64,
    /// The coordinate as written.
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum EffortKind {
    Force,
    Torque,
}

#[derive(Clone, Debug)]
pub struct Effort {
    pub kind: EffortKind,
    pub name: Option<Name>,
    pub span: Span,
    pub value: Quantity<Vector>,
    /// The body whose basis the vector is written in; `earth` (the fixed basis) when omitted.
    pub basis: BodyRef,
    /// `potential = ...`: the potential energy the effort derives from, for the energy report.
    pub potential: Option<Scalar>,
    /// `field = g` of a force: a uniform field (an acceleration, fixed basis) that `apply F`
    /// turns into the weight m g of every body with mass.
    pub field: Option<Vector>,
}

/// `apply <effort> on <frame>`; for a torque the frame is the body's reference frame.
#[derive(Clone, Debug)]
pub struct Application {
    pub effort: EffortId,
    pub target: Frame,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum UnknownKind {
    /// `?s` (or any `?name` but `?v`).
    Scalar,
    /// One component of a `?v`.
    Vector,
    /// `?fs(x, x')`
    Function,
    /// A quantity the program left generic (a mass, an inertia, an effort's value).
    Generic,
}

/// What a generic unknown stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Written in the program (`?s`, `?v`, `?fs(...)`).
    Written,
    Mass(BodyId),
    /// Principal moment about the inertia frame's x, y or z axis.
    Inertia(BodyId, u8),
    /// Of the inertia frame: translation x, y, z (0..3), then Bryant angles (3..6).
    InertiaFrame(BodyId, u8),
    EffortValue(EffortId, u8),
}

#[derive(Clone, Debug)]
pub struct Unknown {
    pub kind: UnknownKind,
    pub origin: Origin,
    /// Component of a `?v` (0, 1, 2); 0 otherwise.
    pub component: u8,
    /// Where it comes from: the `?s` occurrence, or the declaration that left it generic.
    pub span: Span,
    /// Set by `let L = ?s;`.
    pub name: Option<Name>,
}

/// A frame the main program names at its top level (`let tip = [l, 0, 0] ++ 1 @ arm;`): the
/// outputs and the viewer refer to frames by these names.
#[derive(Clone, Debug)]
pub struct NamedFrame {
    pub name: Name,
    pub frame: Frame,
    pub span: Span,
}

#[derive(Clone, Debug, Default)]
pub struct Mechanism {
    pub bodies: Vec<Body>,
    pub links: Vec<Link>,
    pub joins: Vec<Join>,
    /// Joins whose link is a contact (`rolling`, `sliding`), in declaration order.
    pub contacts: Vec<Contact>,
    pub efforts: Vec<Effort>,
    pub applications: Vec<Application>,
    pub unknowns: Vec<Unknown>,
    pub initial: Vec<InitialValue>,
    /// The `drive` declarations, in declaration order.
    pub drives: Vec<Drive>,
    /// The `drive position(F) = law` declarations, in declaration order.
    pub position_drives: Vec<PositionDrive>,
    /// The states (`state(x0)`), in the order they were made.
    pub states: Vec<StateVariable>,
    /// The `actuate` declarations, in declaration order: the model's coordinates.
    pub actuators: Vec<Actuator>,
    /// The `input` declarations, in declaration order.
    pub inputs: Vec<DeclaredInput>,
    /// `given` values of unknowns.
    pub given: Vec<(UnknownId, Scalar, Span)>,
    pub scenario: Option<Scenario>,
    /// The frames the main program names, in declaration order.
    pub frames: Vec<NamedFrame>,
    /// The `output` declarations, in the order they were evaluated.
    pub outputs: Vec<NamedOutput>,
    /// The scene the mechanism was reduced for, and what its model holds
    /// (`elab::scene::reduce`); `None` for a program without scenes.
    pub scene: Option<super::scene_model::SceneModel>,
    /// The `apply` declarations the selected scene's `apply only` or `apply without` left out.
    pub applications_not_chosen: usize,
}

/// What an `output` declaration writes at each output of a run.
#[derive(Clone, Debug)]
pub enum OutputValue {
    /// One column: the output's name.
    Scalar(Scalar),
    /// Three columns, `name.x`, `name.y`, `name.z`.
    Vector(Vector),
    /// Nine columns by rows, `name.xx`, `name.xy`, … `name.zz`.
    Matrix(Box<Matrix>),
    /// The frame's state, the columns of `--output-frame`: `name.x` … `name.wz`.
    Frame(Frame),
}

/// `output name = value;`, its name qualified by its instance (`leg[2]:tip`).
#[derive(Clone, Debug)]
pub struct NamedOutput {
    pub name: Name,
    pub value: OutputValue,
    pub span: Span,
}

/// The `simulate` declaration: numeric settings by field name, and the integrator's name.
#[derive(Clone, Debug, Default)]
pub struct Scenario {
    pub settings: Vec<(String, Scalar, Span)>,
    pub integrator: Option<(String, Span)>,
    pub span: Option<Span>,
}

impl Scenario {
    pub fn setting(&self, name: &str) -> Option<&(String, Scalar, Span)> {
        self.settings.iter().find(|(n, _, _)| n == name)
    }
}

/// Counts `lsdc check` prints: only what the joins and applications reach.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Summary {
    pub bodies: usize,
    pub links: usize,
    pub joins: usize,
    pub applied_forces: usize,
    pub applied_torques: usize,
    pub unknown_scalars: usize,
    pub unknown_vectors: usize,
    pub unknown_functions: usize,
    pub body_names: Vec<String>,
}

/// Bodies, links and unknowns the joins and applications reach.
#[derive(Default)]
struct Reached {
    bodies: BTreeSet<BodyId>,
    links: BTreeSet<LinkId>,
    unknowns: BTreeSet<UnknownId>,
}

impl Reached {
    fn scalar(&mut self, s: &SExpr) {
        s.collect_unknowns(&mut self.unknowns);
    }

    fn vector(&mut self, v: &Vector) {
        v.iter().for_each(|s| self.scalar(s));
    }

    fn displacement(&mut self, d: &Displacement) {
        for step in &d.0 {
            match step {
                Elementary::Translation(t) => self.vector(t),
                Elementary::Rotation { angle, axis } => {
                    self.scalar(angle);
                    self.vector(axis);
                }
            }
        }
    }

    fn body_ref(&mut self, body: BodyRef) {
        if let BodyRef::Body(id) = body {
            self.bodies.insert(id);
        }
    }

    fn frame(&mut self, frame: &Frame) {
        self.body_ref(frame.body);
        self.displacement(&frame.displacement);
    }
}

impl Mechanism {
    pub fn join(&self, id: JoinId) -> &Join {
        &self.joins[id.0 as usize]
    }

    /// The contact's name: `as wheel_on_ground`, or `contact2` for the second contact declared.
    pub fn contact_name(&self, index: usize) -> String {
        self.contacts[index]
            .name
            .as_deref()
            .map_or_else(|| format!("contact{}", index + 1), str::to_string)
    }

    /// The declared inputs (`input swing.q = 0;`): the names of their coordinates
    /// (`swing.q`), the names of the velocities the efforts act along, with their start
    /// values.
    pub fn declared_inputs(&self) -> Vec<(String, f64)> {
        (self.inputs.iter())
            .map(|input| {
                (
                    self.coordinate_name(input.join, input.coordinate),
                    input.start,
                )
            })
            .collect()
    }

    /// The declared value inputs (`input voltage = 0;`): their names (with their instance,
    /// `motor[2]:voltage`) and start values.
    pub fn declared_value_inputs(&self) -> Vec<(String, f64)> {
        (self.states.iter().enumerate())
            .filter(|(_, state)| state.input)
            .map(|(k, state)| {
                let start = crate::elab::value::constant(&state.initial).unwrap_or(0.0);
                (state.label(k), start)
            })
            .collect()
    }

    /// `swing.q`: a join's coordinate by its join's name and its link's parameter.
    pub fn coordinate_name(&self, join: JoinId, coordinate: usize) -> String {
        let link = &self.links[self.join(join).link.0 as usize];
        let name = link.coordinates.get(coordinate).map(|n| n.to_string());
        format!("{}.{}", self.join_name(join), name.unwrap_or_default())
    }

    /// The join's name: `as crank`, or `join3` for the third join declared.
    pub fn join_name(&self, id: JoinId) -> String {
        self.join(id)
            .name
            .as_deref()
            .map_or_else(|| format!("join{}", id.0 + 1), str::to_string)
    }

    /// The frame a name denotes: a named frame of the main program, else a body's reference
    /// frame (by its `let` name), else `earth`.
    pub fn frame_named(&self, name: &str) -> Option<Frame> {
        let reference = |body| Frame {
            body,
            displacement: Displacement(Vec::new()),
        };
        if let Some(named) = self.frames.iter().find(|f| &*f.name == name) {
            return Some(named.frame.clone());
        }
        if let Some(id) = self
            .bodies
            .iter()
            .position(|b| b.name.as_deref() == Some(name))
        {
            return Some(reference(BodyRef::Body(BodyId(id as u32))));
        }
        (name == "earth").then(|| reference(BodyRef::Earth))
    }

    /// The names `frame_named` knows, for suggestions.
    pub fn frame_names(&self) -> Vec<String> {
        let frames = self.frames.iter().map(|f| f.name.to_string());
        let bodies = self
            .bodies
            .iter()
            .filter_map(|b| b.name.as_deref().map(str::to_string));
        frames.chain(bodies).chain(["earth".to_string()]).collect()
    }

    pub fn body(&self, id: BodyId) -> &Body {
        &self.bodies[id.0 as usize]
    }

    pub fn link(&self, id: LinkId) -> &Link {
        &self.links[id.0 as usize]
    }

    pub fn effort(&self, id: EffortId) -> &Effort {
        &self.efforts[id.0 as usize]
    }

    fn reached(&self) -> Reached {
        let mut reached = Reached::default();
        for join in &self.joins {
            reached.frame(&join.first);
            reached.frame(&join.second);
            reached.links.insert(join.link);
        }
        for contact in &self.contacts {
            reached.frame(&contact.first);
            reached.frame(&contact.second);
            reached.links.insert(contact.link);
        }
        for application in &self.applications {
            reached.frame(&application.target);
            let effort = self.effort(application.effort);
            reached.vector(effort.value.value());
            reached.body_ref(effort.basis);
        }
        for &id in &reached.bodies.clone() {
            let body = self.body(id);
            reached.scalar(body.mass.value());
            reached.displacement(body.iframe.value());
            reached.vector(body.inertia.value());
        }
        for &id in &reached.links.clone() {
            let link = self.link(id);
            link.dofs.iter().for_each(|d| reached.displacement(d));
            link.forces
                .iter()
                .chain(&link.torques)
                .for_each(|(_, v)| reached.vector(v));
            if let Some(law) = link.contact() {
                reached.scalar(&law.radius);
                law.friction.iter().for_each(|f| reached.scalar(f));
            }
        }
        reached
    }

    pub fn summary(&self) -> Summary {
        let reached = self.reached();
        let count = |kind| {
            let unknowns = reached
                .unknowns
                .iter()
                .map(|id| &self.unknowns[id.0 as usize]);
            unknowns
                .filter(|u| u.kind == kind && u.component == 0)
                .count()
        };
        let applied = |kind| {
            self.applications
                .iter()
                .filter(|a| self.effort(a.effort).kind == kind)
                .count()
        };
        Summary {
            bodies: reached.bodies.len(),
            links: reached.links.len(),
            joins: self.joins.len(),
            applied_forces: applied(EffortKind::Force),
            applied_torques: applied(EffortKind::Torque),
            unknown_scalars: count(UnknownKind::Scalar),
            unknown_vectors: count(UnknownKind::Vector),
            unknown_functions: count(UnknownKind::Function),
            body_names: reached
                .bodies
                .iter()
                .map(|&id| self.body_name(BodyRef::Body(id)))
                .collect(),
        }
    }

    /// A readable name for a generic quantity: `mass(satellite)`, `inertia_y(arm)`.
    pub fn generic_name(&self, origin: Origin) -> String {
        const AXES: [&str; 3] = ["x", "y", "z"];
        const FRAME: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
        let body = |id| self.body_name(BodyRef::Body(id));
        match origin {
            Origin::Written => "unknown".to_string(),
            Origin::Mass(id) => format!("mass({})", body(id)),
            Origin::Inertia(id, i) => format!("inertia_{}({})", AXES[i as usize % 3], body(id)),
            Origin::InertiaFrame(id, i) => {
                format!("iframe_{}({})", FRAME[i as usize % 6], body(id))
            }
            Origin::EffortValue(id, i) => {
                let effort = self.effort(id);
                let name = effort
                    .name
                    .as_deref()
                    .map_or_else(|| format!("effort#{}", id.0 + 1), str::to_string);
                format!(
                    "{}_{}({name})",
                    if effort.kind == EffortKind::Force {
                        "force"
                    } else {
                        "torque"
                    },
                    AXES[i as usize % 3]
                )
            }
        }
    }

    pub fn body_name(&self, body: BodyRef) -> String {
        match body {
            BodyRef::Earth => "earth".to_string(),
            BodyRef::Body(id) => self
                .body(id)
                .name
                .as_deref()
                .map_or_else(|| format!("body#{}", id.0 + 1), str::to_string),
        }
    }

    /// A canonical text form of what the joins and applications reach, with unknowns numbered in
    /// order of appearance: two programs describing the same mechanism dump the same text.
    pub fn dump(&self) -> String {
        let mut text = Dumper {
            mechanism: self,
            numbering: HashMap::new(),
        };
        let mut out = String::new();
        for join in &self.joins {
            let link = self.link(join.link);
            let first = text.frame(&join.first);
            let second = text.frame(&join.second);
            let _ = writeln!(
                out,
                "join {first} and {second} with link({})",
                link.coordinates.join(", ")
            );
            for (i, dof) in link.dofs.iter().enumerate() {
                let _ = writeln!(out, "  dof{} = {}", i + 1, text.displacement(dof));
            }
            for (label, efforts) in [("force", &link.forces), ("torque", &link.torques)] {
                for (index, v) in efforts.iter() {
                    let number = if *index == 0 {
                        String::new()
                    } else {
                        index.to_string()
                    };
                    let _ = writeln!(out, "  {label}{number} = {}", text.vector(v));
                }
            }
        }
        for application in &self.applications {
            let effort = self.effort(application.effort);
            let value = text.vector(effort.value.value());
            let basis = self.body_name(effort.basis);
            let target = text.frame(&application.target);
            let _ = writeln!(
                out,
                "apply {:?} value {value} basis {basis} on {target}",
                effort.kind
            );
        }
        for &id in &self.reached().bodies {
            let body = self.body(id);
            let mass = text.scalar(body.mass.value());
            let iframe = text.displacement(body.iframe.value());
            let inertia = text.vector(body.inertia.value());
            let _ = writeln!(
                out,
                "body {}: mass {mass}, iframe {iframe}, inertia {inertia}",
                self.body_name(BodyRef::Body(id))
            );
        }
        out
    }
}

/// Writes values with unknowns renumbered in order of first appearance.
struct Dumper<'m> {
    mechanism: &'m Mechanism,
    numbering: HashMap<UnknownId, usize>,
}

impl Dumper<'_> {
    fn scalar(&mut self, s: &Scalar) -> String {
        let numbering = &mut self.numbering;
        let mechanism = self.mechanism;
        s.render(&mut |id| {
            let unknown = &mechanism.unknowns[id.0 as usize];
            if unknown.origin != Origin::Written {
                return mechanism.generic_name(unknown.origin);
            }
            let next = numbering.len() + 1;
            let n = *numbering.entry(id).or_insert(next);
            let prefix = if unknown.kind == UnknownKind::Function {
                "f"
            } else {
                "s"
            };
            format!("?{prefix}{n}")
        })
    }

    fn vector(&mut self, v: &Vector) -> String {
        format!(
            "[{}, {}, {}]",
            self.scalar(&v[0]),
            self.scalar(&v[1]),
            self.scalar(&v[2])
        )
    }

    fn displacement(&mut self, d: &Displacement) -> String {
        if d.is_identity() {
            return "1".to_string();
        }
        let steps: Vec<String> =
            d.0.iter()
                .map(|step| match step {
                    Elementary::Translation(t) => format!("T{}", self.vector(t)),
                    Elementary::Rotation { angle, axis } => {
                        format!("R({}, {})", self.scalar(angle), self.vector(axis))
                    }
                })
                .collect();
        steps.join(" ")
    }

    fn frame(&mut self, frame: &Frame) -> String {
        format!(
            "{} @ {}",
            self.displacement(&frame.displacement),
            self.mechanism.body_name(frame.body)
        )
    }
}

/// Why a body's mass or principal moments cannot be those of a rigid body.
#[derive(Clone, Debug, PartialEq)]
pub struct InertiaProblem {
    /// The mass is at fault (else the principal moments).
    pub about_mass: bool,
    pub message: String,
    pub help: &'static str,
}

/// Relative slack of the triangle inequality of the principal moments, for rounded values.
const TRIANGLE_SLACK: f64 = 1e-9;

/// Checks what is known of a body's mass and principal moments: a mass is finite and not
/// negative; moments are finite, not negative, and each is at most the sum of the other two (the
/// triangle inequality of every rigid body). `None` when nothing is wrong.
pub fn inertia_problem(mass: Option<f64>, moments: Option<[f64; 3]>) -> Option<InertiaProblem> {
    let shown = crate::diag::number::shortest;
    if let Some(m) = mass.filter(|m| !m.is_finite() || *m < 0.0) {
        return Some(InertiaProblem {
            about_mass: true,
            message: format!("a mass of {} is impossible", shown(m)),
            help: "a mass is a finite number, 0 or more",
        });
    }
    let [a, b, c] = moments?;
    if let Some(i) = [a, b, c].into_iter().find(|i| !i.is_finite() || *i < 0.0) {
        return Some(InertiaProblem {
            about_mass: false,
            message: format!(
                "a principal moment of inertia of {} is impossible",
                shown(i)
            ),
            help: "principal moments of inertia are finite numbers, 0 or more",
        });
    }
    for (big, x, y) in [(a, b, c), (b, c, a), (c, a, b)] {
        if big > (x + y) * (1.0 + TRIANGLE_SLACK) {
            return Some(InertiaProblem {
                about_mass: false,
                message: format!(
                    "principal moments of inertia {}, {}, {} violate the triangle inequality",
                    shown(a),
                    shown(b),
                    shown(c)
                ),
                help: "no rigid body has a principal moment larger than the sum of the other two: check the values and their order",
            });
        }
    }
    None
}
