//! The equations of motion as expressions, by the formalism of Papegay (1992, §3.3):
//!
//! - each body i is a free body with kinematic vector 𝐪ᵢ = (v(Oᵢ), ωᵢ) in the fixed axes and its
//!   Newton–Euler block at its origin, 𝔐ᵢ 𝐪̇ᵢ = 𝔖ᵢ + 𝔉ᵢ, with
//!   𝔐ᵢ = [[μ Id, −μ r̃], [μ r̃, I(Oᵢ)]], 𝔖ᵢ = (−μ ω∧(ω∧r), −ω∧I(Oᵢ)ω), r = OᵢGᵢ;
//! - the tree's coordinates parametrise every body: 𝐪 = Ψ(p) q, built parent first
//!   (`kinematics`), so 𝐪̇ = Ψ q̇ + Ψ̇ q;
//! - premultiplying by Ψᵀ eliminates the tree's reactions: M(p) q̇ = S(p, q) + F(p, q) with
//!   M = Ψᵀ𝔐Ψ, S = Ψᵀ(𝔖 − 𝔐Ψ̇q), F = Ψᵀ𝔉 plus the links' own efforts;
//! - each complementary link adds six rows Δ(p) q = 0 (the difference of the twists of its two
//!   frames) and the term Δᵀ Λ.
//!
//! Ψᵀ is applied in its product form, Ψᵀ = Ψ₁ᵀ⋯Ψₙᵀ: a sweep from the last body to the first that
//! carries each body's force and moment to its parent's origin. So the work and the size of the
//! result grow with the number of entries of M, not with bodies × entries.
//!
//! The complementary links' own coordinates are variables of the equations (after the tree's),
//! with no inertia: their rows of M and S are zero, their rows of F hold their links' efforts.

#[cfg(lsdc_internals)]
use nalgebra::{DMatrix, DVector};

#[cfg(lsdc_internals)]
use super::expr::Tape;
use super::expr::{ExprId, Pool};
use super::form::Form;
use super::generator::Generator;
use super::lower::{LowerError, Variables};
use super::quaternion_joints::QuaternionJoins;
use super::vector as v;
use super::vector::Wrench;
use crate::diag::Diagnostic;
use crate::elab::imposed_motion::first_imposed_motion;
use crate::elab::mechanism::Mechanism;
use crate::topology::Topology;

#[derive(Clone)]
pub struct Equations {
    pub pool: Pool,
    pub variables: Variables,
    /// M, row-major, n × n with n the number of positions.
    pub mass: Vec<ExprId>,
    /// S: the velocity-product terms.
    pub second_member: Vec<ExprId>,
    /// F: the generalised forces of the applied efforts and of the links' efforts.
    pub forces: Vec<ExprId>,
    /// Δ, row-major, 6 rows per complementary link: rotation then translation, fixed axes.
    pub constraints: Vec<ExprId>,
    /// Δ̇ q: the constraints' acceleration at zero q̇, so that Δ q̇ + Δ̇ q = 0.
    pub constraint_bias: Vec<ExprId>,
    /// One name per constraint row, which is also the name of its multiplier: `c.rx`, `c.x`.
    pub constraint_names: Vec<String>,
    /// For trees, the coordinates' second derivatives q̇ = M⁻¹(S + F), written by the
    /// articulated-body recursion (O(n) expressions rather than a solve).
    pub accelerations: Option<Vec<ExprId>>,
    /// The formalism the equations were derived by.
    pub form: Form,
}

impl Equations {
    /// Number of rates (rows of M): the coordinates' number, but where a join is written in
    /// the simulator's state (`quaternion_joints`).
    pub fn dimension(&self) -> usize {
        self.variables.rates.len()
    }

    pub fn constraint_rows(&self) -> usize {
        self.constraint_names.len()
    }

    /// Every expression the equations are made of: M, S, F, Δ, Δ̇q, then the accelerations.
    pub fn roots(&self) -> Vec<ExprId> {
        let accelerations = self.accelerations.iter().flatten();
        [
            &self.mass,
            &self.second_member,
            &self.forces,
            &self.constraints,
            &self.constraint_bias,
        ]
        .into_iter()
        .flatten()
        .chain(accelerations)
        .copied()
        .collect()
    }

    /// Number of distinct nodes of the equations: their size once common subexpressions are
    /// shared.
    #[cfg(lsdc_internals)]
    pub fn size(&self) -> usize {
        self.tape().size()
    }

    /// The tape that evaluates every root, in the order of `roots`.
    #[cfg(lsdc_internals)]
    pub fn tape(&self) -> Tape {
        Tape::new(&self.pool, &self.roots())
    }

    /// Values for every symbol of the pool, by name; the first symbol without one otherwise.
    #[cfg(lsdc_internals)]
    pub fn symbol_values(
        &self,
        value: impl Fn(&str) -> Option<f64>,
    ) -> Result<Vec<f64>, MissingSymbol> {
        (0..self.pool.symbol_count() as u32)
            .map(|i| {
                let name = self.pool.symbol_name(i);
                value(name).ok_or_else(|| MissingSymbol(name.to_string()))
            })
            .collect()
    }

    /// The equations at `symbols` (one value per pool symbol), evaluated by `tape`.
    #[cfg(lsdc_internals)]
    pub fn evaluate(&self, tape: &Tape, symbols: &[f64]) -> Values {
        let values = tape.eval(symbols);
        let (n, m) = (self.dimension(), self.constraint_rows());
        let mut rest = values.as_slice();
        let mut take = |count: usize| {
            let (head, tail) = rest.split_at(count);
            rest = tail;
            head.to_vec()
        };
        Values {
            mass: DMatrix::from_row_slice(n, n, &take(n * n)),
            second_member: DVector::from_vec(take(n)),
            forces: DVector::from_vec(take(n)),
            constraints: DMatrix::from_row_slice(m, n, &take(m * n)),
            constraint_bias: DVector::from_vec(take(m)),
            accelerations: self
                .accelerations
                .as_ref()
                .map(|a| DVector::from_vec(take(a.len()))),
        }
    }
}

/// A symbol of the equations that was given no value.
#[derive(Clone, Debug, PartialEq, Eq)]
#[cfg(lsdc_internals)]
pub struct MissingSymbol(pub String);

#[cfg(lsdc_internals)]
impl std::fmt::Display for MissingSymbol {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "no value for the symbol `{}`", self.0)
    }
}

#[cfg(lsdc_internals)]
impl std::error::Error for MissingSymbol {}

/// The equations' values at one point.
#[derive(Clone, Debug)]
#[cfg(lsdc_internals)]
pub struct Values {
    pub mass: DMatrix<f64>,
    pub second_member: DVector<f64>,
    pub forces: DVector<f64>,
    pub constraints: DMatrix<f64>,
    pub constraint_bias: DVector<f64>,
    pub accelerations: Option<DVector<f64>>,
}

/// Generates the equations of a mechanism whose bodies are numbered by `topology`.
/// E0828 for a motion imposed in time: a `drive`, whose row and effort the equations do not
/// carry (they would be the free mechanism's), or `time` in a dof chain, whose motion's rates
/// the generator's velocities (by the coordinates' rates alone) would leave out.
fn imposed_motion(mechanism: &Mechanism) -> Option<Diagnostic> {
    let motion = first_imposed_motion(mechanism)?;
    Some(
        Diagnostic::error(
            "E0828",
            "the equations of motion of a mechanism with motions imposed in time (`drive`, `time` in a dof chain) are not written",
        )
        .primary(motion.span, motion.label)
        .help("`lsdc simulate` integrates it and `lsdc inverse` gives the efforts that impose the motion; the symbolic equations cover free coordinates only"),
    )
}

pub fn generate(mechanism: &Mechanism, topology: &Topology) -> Result<Equations, Vec<Diagnostic>> {
    generate_in(mechanism, topology, Form::Lagrange)
}

/// The equations in the simulator's state: the joins of `quaternion_joins` in their quaternion
/// and body twist (`quaternion_joints`), the others in their declared coordinates. For native
/// code that takes the simulator's state as it is.
pub fn generate_in_state(
    mechanism: &Mechanism,
    topology: &Topology,
    quaternion_joins: QuaternionJoins,
) -> Result<Equations, Vec<Diagnostic>> {
    written(mechanism, topology, Form::Lagrange, quaternion_joins)
}

/// The equations derived by `form`: the same equations, to round-off, by another road (`form`).
pub fn generate_in(
    mechanism: &Mechanism,
    topology: &Topology,
    form: Form,
) -> Result<Equations, Vec<Diagnostic>> {
    written(mechanism, topology, form, QuaternionJoins::new())
}

/// The equations by `form`, in the state of `quaternion_joins`, or why they are not written.
fn written(
    mechanism: &Mechanism,
    topology: &Topology,
    form: Form,
    quaternion_joins: QuaternionJoins,
) -> Result<Equations, Vec<Diagnostic>> {
    if let Some(contact) = mechanism.contacts.first() {
        // The equations below are the tree's and its loops'; leaving the contacts' rows out
        // would write the equations of another mechanism.
        return Err(vec![Diagnostic::error(
            "E0825",
            "the equations of motion of a mechanism with contacts (`rolling`, `sliding`) are not written",
        )
        .primary(contact.span, "this contact constrains the motion")
        .help("`lsdc simulate` integrates it; the symbolic equations cover joints and closed loops only")]);
    }
    let coupled = |join: &&crate::elab::mechanism::Join| {
        let link = mechanism.link(join.link);
        link.mimic().is_declared() || link.friction().is_declared()
    };
    if let Some(join) = mechanism.joins.iter().find(coupled) {
        // The generator writes one equation per coordinate, with no coupling or friction.
        return Err(vec![Diagnostic::error(
            "E0826",
            "the equations of motion of a mechanism with mimic joints or joint friction are not written",
        )
        .primary(join.span, "this join is a mimic or has friction")
        .help("`lsdc simulate` integrates it; the symbolic equations cover free joints only")]);
    }
    if let Some(join) = mechanism
        .joins
        .iter()
        .find(|join| mechanism.link(join.link).rotor().is_declared())
    {
        // The generator writes the bodies' kinetic energy only; a rotor's own energy and its
        // gyroscopic coupling would be missing from M and S.
        return Err(vec![Diagnostic::error(
            "E0826",
            "the equations of motion of a mechanism with geared rotors are not written",
        )
        .primary(join.span, "this join carries a geared rotor")
        .help(
            "`lsdc simulate` integrates it; the symbolic equations cover the bodies' inertia only",
        )]);
    }
    if let Some(refused) = imposed_motion(mechanism) {
        return Err(vec![refused]);
    }
    let mut generator = Generator::in_state(mechanism, topology, quaternion_joins);
    generator.run(form).map_err(|e| {
        let error = Diagnostic::error(
            "E1101",
            format!("the equations of motion cannot be written: {}", e.0),
        );
        vec![match generator.context {
            Some(span) => error.primary(span, "in this declaration"),
            None => error,
        }]
    })
}

impl Generator<'_> {
    fn run(&mut self, form: Form) -> Result<Equations, LowerError> {
        self.place_bodies()?;
        self.anchors = self.anchors();
        (self.local_inertias, self.inertias) = self.merged_inertias()?;
        let tree_coordinates = self.tree_coordinates();
        if form != Form::Lagrange {
            return self.run_other(form, tree_coordinates);
        }
        let mass = self.mass_matrix(tree_coordinates);
        let velocity_terms: Vec<Option<Wrench>> = (0..=self.topology.body_count())
            .map(|i| {
                self.inertias[i]
                    .as_ref()
                    .map(|m| m.velocity_terms(&mut self.pool, &self.bodies[i]))
            })
            .collect();
        let second_member = self.project(velocity_terms);
        self.frame_states()?;
        let applied = self.applied_wrenches()?;
        let mut forces = self.project(applied.clone());
        let link_forces = self.add_link_forces(&mut forces)?;
        let accelerations = self
            .topology
            .complementary
            .is_empty()
            .then(|| self.articulated(&applied, &link_forces));
        self.equations(form, [mass, second_member, forces], accelerations)
    }

    /// The equations by Kane's or the Newton–Euler form. The constraint rows are the loops'
    /// kinematics, the same in every form; the accelerations (the articulated-body recursion,
    /// not a form of the equations) are left out.
    fn run_other(&mut self, form: Form, tree_coordinates: usize) -> Result<Equations, LowerError> {
        self.frame_states()?;
        let applied = self.applied_wrenches()?;
        let (mass, second_member, mut forces) = match form {
            Form::Kane => self.kane(tree_coordinates, &applied),
            _ => self.newton_euler(tree_coordinates, &applied)?,
        };
        self.add_link_forces(&mut forces)?;
        self.equations(form, [mass, second_member, forces], None)
    }

    /// Adds the links' efforts to the generalised forces `forces`; the links' efforts alone.
    fn add_link_forces(&mut self, forces: &mut [ExprId]) -> Result<Vec<ExprId>, LowerError> {
        let zero = self.pool.constant(0.0);
        let mut link_forces = vec![zero; self.columns()];
        self.add_link_efforts(&mut link_forces)?;
        for (f, l) in forces.iter_mut().zip(&link_forces) {
            *f = self.pool.add(*f, *l);
        }
        Ok(link_forces)
    }

    /// The equations of `form` from its M, S and F, with the loops' rows (their kinematics,
    /// the same in every form).
    fn equations(
        &mut self,
        form: Form,
        [mass, second_member, forces]: [Vec<ExprId>; 3],
        accelerations: Option<Vec<ExprId>>,
    ) -> Result<Equations, LowerError> {
        let closure = self.loops()?;
        Ok(Equations {
            pool: std::mem::take(&mut self.pool),
            variables: self.lowering.variables.clone(),
            mass,
            second_member,
            forces,
            constraints: closure.rows,
            constraint_bias: closure.bias,
            constraint_names: closure.names,
            accelerations,
            form,
        })
    }

    /// Ψᵀ applied to per-body wrenches (force, moment at the body's origin), from the last body
    /// to the first: the generalised forces on every tree coordinate (zero on the others).
    fn project(&mut self, mut wrenches: Vec<Option<Wrench>>) -> Vec<ExprId> {
        let zero = self.pool.constant(0.0);
        let mut generalised = vec![zero; self.columns()];
        for b in (1..=self.topology.body_count()).rev() {
            let Some(wrench) = wrenches[b] else { continue };
            for column in self.own_columns(b) {
                generalised[column] = self.power(b, column, &wrench);
            }
            self.carry_to_parent(b, wrench, &mut wrenches);
        }
        generalised
    }

    /// The power of `wrench` on body `b` per unit rate of `column`: Ψᵀ's entry.
    fn power(&mut self, b: usize, column: usize, wrench: &Wrench) -> ExprId {
        match self.bodies[b].column(column) {
            Some([angular, linear]) => {
                let (angular, linear) = (*angular, *linear);
                let f = v::dot(&mut self.pool, &linear, &wrench[0]);
                let m = v::dot(&mut self.pool, &angular, &wrench[1]);
                self.pool.add(f, m)
            }
            None => self.pool.constant(0.0),
        }
    }

    /// Adds body b's wrench, moved to its parent's anchor's origin, to the anchor's.
    fn carry_to_parent(&mut self, b: usize, wrench: Wrench, wrenches: &mut [Option<Wrench>]) {
        // Straight to the anchor: a welded parent between them has no coordinate to project on.
        let parent = self.anchors[self.topology.parent(b)];
        if parent == 0 {
            return;
        }
        let pool = &mut self.pool;
        let arm = v::sub(pool, &self.bodies[b].origin, &self.bodies[parent].origin);
        let lever = v::cross(pool, &arm, &wrench[0]);
        let moment = v::add(pool, &wrench[1], &lever);
        wrenches[parent] = Some(match wrenches[parent] {
            Some([f, m]) => [v::add(pool, &f, &wrench[0]), v::add(pool, &m, &moment)],
            None => [wrench[0], moment],
        });
    }

    /// M = Ψᵀ𝔐Ψ column by column: each column's momenta swept to the root; only the entries on
    /// and above the diagonal are formed, the others are their mirror.
    fn mass_matrix(&mut self, tree_coordinates: usize) -> Vec<ExprId> {
        let n = self.columns();
        let zero = self.pool.constant(0.0);
        let mut mass = vec![zero; n * n];
        for l in 0..tree_coordinates {
            let mut wrenches: Vec<Option<Wrench>> = vec![None; self.topology.body_count() + 1];
            for (b, wrench) in wrenches.iter_mut().enumerate().skip(1) {
                if let (Some(inertia), Some([angular, linear])) =
                    (&self.inertias[b], self.bodies[b].column(l))
                {
                    *wrench = Some(inertia.times(&mut self.pool, angular, linear));
                }
            }
            for b in (self.owner(l)..=self.topology.body_count())
                .rev()
                .filter(|&b| b > 0)
            {
                let Some(wrench) = wrenches[b] else { continue };
                for row in self.own_columns(b).filter(|&row| row <= l) {
                    let entry = self.power(b, row, &wrench);
                    mass[row * n + l] = entry;
                    mass[l * n + row] = entry;
                }
                self.carry_to_parent(b, wrench, &mut wrenches);
            }
            // Above the column's own body only ancestors remain: keep sweeping to the root.
            let mut b = self.topology.parent(self.owner(l).max(1));
            while b > 0 {
                if let Some(wrench) = wrenches[b] {
                    for row in self.own_columns(b) {
                        let entry = self.power(b, row, &wrench);
                        mass[row * n + l] = entry;
                        mass[l * n + row] = entry;
                    }
                    self.carry_to_parent(b, wrench, &mut wrenches);
                }
                b = self.topology.parent(b);
            }
        }
        mass
    }
}
