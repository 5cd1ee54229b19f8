//! The formalism the equations of motion are derived by. Every form writes the same equations
//! M q' = S + F + Δᵀ Λ (the same values, to round-off), by a different road on the expression
//! graph, so that each checks the others:
//!
//! - `Lagrange`, the default: the thesis's mixed Newton–Euler and Lagrange formalism (Papegay
//!   1992, §3.3.1): free bodies' blocks 𝔐ᵢ, 𝔖ᵢ at their origins, premultiplied by Ψᵀ, the
//!   velocities' Jacobian built by the composition of velocities (`equations`);
//! - `Kane`: Kane's equations (Kane and Levinson 1985, ch. 6; Llibre 2009, §2.3): the partial
//!   velocities and partial angular velocities taken as derivatives, with respect to the rates,
//!   of the velocities obtained by differentiating the bodies' positions and orientations in
//!   time; the generalised inertia and active forces are their dot products with the inertia
//!   forces and the applied wrenches (`kane`);
//! - `NewtonEuler`: the recursive Newton–Euler algorithm (Luh, Walker and Paul 1980; Llibre
//!   2009, ch. 3): each body's Newton and Euler equations at its own centre of mass, the
//!   reactions carried from the leaves to the root, projected on the joints' columns; M column
//!   by column from unit accelerations (Walker and Orin 1982, method 1) (`newton_euler`).

/// The formalism of `--form`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Form {
    #[default]
    Lagrange,
    Kane,
    NewtonEuler,
}

impl Form {
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub const ALL: [Form; 3] = [Form::Lagrange, Form::Kane, Form::NewtonEuler];

    /// The name `--form` takes.
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub fn name(self) -> &'static str {
        match self {
            Form::Lagrange => "lagrange",
            Form::Kane => "kane",
            Form::NewtonEuler => "newton-euler",
        }
    }

    /// How the emitted equations say they were derived.
    pub fn description(self) -> &'static str {
        match self {
            Form::Lagrange => "the thesis's Lagrange form (free bodies' Newton-Euler blocks premultiplied by Psi^T)",
            Form::Kane => "Kane's equations (generalised active and inertia forces from partial velocities)",
            Form::NewtonEuler => "the recursive Newton-Euler form (bodies' equations at their centres of mass, reactions carried to the root)",
        }
    }
}
