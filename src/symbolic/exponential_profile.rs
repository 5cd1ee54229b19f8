//! The profile of the exponential law of motion (`exponential(time, t0, q0, t1, q1, sigma,
//! lambda)`), the Delta seed's "trajectoire exponentielle" (its §III.6.2.3, from Biagiotti &
//! Melchiorri, *Trajectory Planning for Automatic Machines and Robots*, 2008, §2.3): a velocity
//!
//!   q̇ = v_c exp(−σ f(τ', λ)),  f(τ', λ) = (2τ')² / |1 − (2τ')²|^λ,  τ' = τ − 1/2 ∈ [−1/2, 1/2],
//!
//! over the normalised time τ = (t − t0)/(t1 − t0), with v_c the velocity that covers q1 − q0.
//! With g = 1 − (2τ')² = 4τ(1 − τ), the rate of the normalised profile is
//! s'(τ) = r(τ)/R, r(τ) = exp(−σ (1 − g)/g^λ), R = ∫₀¹ r: zero with all its derivatives at both
//! ends (for σ, λ > 0), one at the middle over R.
//!
//! The position s(τ) = ∫₀^τ r / R has no closed form: it is a node of its own on the
//! expression pool (`expr`), whose value is a quadrature and whose derivative is the rate
//! above as ordinary nodes (`Pool::exponential_rate`), so that the rate and the acceleration
//! a drive takes are exact, and the position is the quadrature's. The quadrature: by the symmetry r(τ) = r(1 − τ), R = 2 P(1/2)
//! and s(τ) = 1 − s(1 − τ), so only P(x) = ∫₀^x r for x ≤ 1/2 is computed, by the composite
//! Gauss–Legendre rule of `POINTS` (10) points on `PANELS` (32) equal panels of [0, x] (Davis &
//! Rabinowitz, *Methods of Numerical Integration*, 2nd ed., 1984, §2.7), the first panel
//! halved towards 0 ([h/2, h], [h/4, h/2], …): r = exp(−σ (4τ)^−λ …) is smooth but not
//! analytic at 0, and a panel that touches 0 converges slowly (with σ = 1, λ = 0.2 the 8-point
//! rule on equal panels alone was 1.6e-10 off at τ = 0.003), while each halved panel is as far
//! from 0 as it is wide. Against an independent adaptive Simpson quadrature, the position, and
//! the closed forms of the rate and acceleration agree to 5e-14 of each one's largest value for
//! σ from 1 to 30 and λ from 0.2 to 2 (tests/suite/references.rs).

use std::sync::OnceLock;

/// Gauss–Legendre points per panel.
pub(crate) const POINTS: usize = 10;
/// Equal panels over [0, x].
pub(crate) const PANELS: usize = 32;
/// Halvings of the first panel at most (its last part, below 2⁻⁶⁰ of it, is left out: r is
/// below e^(−σ·2^(12λ)/(4x)^λ) there).
pub(crate) const GRADED: usize = 60;

/// The parameters σ and λ (stored by their bits, so that the pool can hash its nodes) and the
/// normalisation R they give.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ExponentialProfile {
    sigma: u64,
    lambda: u64,
    total: u64,
}

impl ExponentialProfile {
    /// The profile of σ > 0 and λ > 0 (the caller checks them).
    pub fn new(sigma: f64, lambda: f64) -> ExponentialProfile {
        let mut profile = ExponentialProfile {
            sigma: sigma.to_bits(),
            lambda: lambda.to_bits(),
            total: 0,
        };
        profile.total = (2.0 * profile.partial(0.5)).to_bits();
        profile
    }

    pub fn sigma(self) -> f64 {
        f64::from_bits(self.sigma)
    }

    pub fn lambda(self) -> f64 {
        f64::from_bits(self.lambda)
    }

    /// R = ∫₀¹ r.
    pub fn total(self) -> f64 {
        f64::from_bits(self.total)
    }

    /// r(τ) = exp(−σ (1 − g)/g^λ), g = 4τ(1 − τ); 0 where g ≤ 0.
    pub fn unnormalised_rate(self, tau: f64) -> f64 {
        let g = 4.0 * tau * (1.0 - tau);
        if g <= 0.0 {
            return 0.0;
        }
        (-self.sigma() * (1.0 - g) / g.powf(self.lambda())).exp()
    }

    /// P(x) = ∫₀^x r, for 0 ≤ x ≤ 1/2: the panels of [0, x] but the first, then the first
    /// graded towards 0 (module comment).
    fn partial(self, x: f64) -> f64 {
        let width = x / PANELS as f64;
        let mut sum = 0.0;
        for panel in 1..PANELS {
            let lower = panel as f64 * width;
            sum += self.panel(lower, lower + width);
        }
        let mut upper = width;
        for _ in 0..GRADED {
            // r rises on [0, 1/2]: nothing below a point where it is 0.
            if self.unnormalised_rate(upper) == 0.0 {
                break;
            }
            sum += self.panel(0.5 * upper, upper);
            upper *= 0.5;
        }
        sum
    }

    /// ∫ₐᵇ r by the Gauss–Legendre rule.
    fn panel(self, a: f64, b: f64) -> f64 {
        let (middle, half) = (0.5 * (a + b), 0.5 * (b - a));
        let mut sum = 0.0;
        for &(node, weight) in gauss_legendre() {
            sum += weight * self.unnormalised_rate(middle + half * node);
        }
        half * sum
    }

    /// s(τ): 0 up to τ = 0, 1 from τ = 1 on.
    pub fn value(self, tau: f64) -> f64 {
        if tau.is_nan() {
            return tau;
        }
        if tau <= 0.0 {
            return 0.0;
        }
        if tau >= 1.0 {
            return 1.0;
        }
        match tau <= 0.5 {
            true => self.partial(tau) / self.total(),
            false => 1.0 - self.partial(1.0 - tau) / self.total(),
        }
    }
}

/// The Gauss–Legendre points and weights of [`POINTS`] points on [−1, 1]: the roots of the
/// Legendre polynomial P_n by Newton's method from Tricomi's estimates cos(π(k − 1/4)/(n + 1/2)),
/// the weights 2/((1 − x²) P_n'(x)²) (Davis & Rabinowitz §2.7).
pub(crate) fn gauss_legendre() -> &'static [(f64, f64); POINTS] {
    static RULE: OnceLock<[(f64, f64); POINTS]> = OnceLock::new();
    RULE.get_or_init(|| {
        let n = POINTS as f64;
        std::array::from_fn(|k| {
            let mut x = (std::f64::consts::PI * (k as f64 + 0.75) / (n + 0.5)).cos();
            let mut derivative = 0.0;
            for _ in 0..100 {
                // P_n(x) and P_n'(x) by the three-term recurrence.
                let (mut previous, mut current) = (1.0, x);
                for j in 2..=POINTS {
                    let j = j as f64;
                    (previous, current) = (
                        current,
                        ((2.0 * j - 1.0) * x * current - (j - 1.0) * previous) / j,
                    );
                }
                derivative = n * (x * current - previous) / (x * x - 1.0);
                let step = current / derivative;
                x -= step;
                if step.abs() <= 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * derivative * derivative))
        })
    })
}

/// The C99 definition of `exponential_profile(tau, sigma, lambda)` for generated code: the
/// same rule, the same operations in the same order as [`ExponentialProfile::value`].
pub(crate) fn c_definition() -> String {
    let (nodes, weights) = rule_literals();
    format!(
        "\n/* The exponential law's normalised profile (lsdc's `exponential`): the rate\n\
         \x20  exp(-sigma (1 - g) / g^lambda), g = 4 tau (1 - tau), integrated on [0, x], x <= 1/2, by\n\
         \x20  the Gauss-Legendre rule of {POINTS} points on {PANELS} equal panels, the first halved towards\n\
         \x20  0 ({GRADED} times at most), over its integral on [0, 1]. */\n\
         static inline double exponential_rate(double tau, double sigma, double lambda) {{\n\
         \x20   double g = 4.0 * tau * (1.0 - tau);\n\
         \x20   return g <= 0.0 ? 0.0 : exp(-sigma * (1.0 - g) / pow(g, lambda));\n\
         }}\n\
         static inline double exponential_panel(double a, double b, double sigma, double lambda) {{\n\
         \x20   static const double nodes[{POINTS}] = {{{nodes}}};\n\
         \x20   static const double weights[{POINTS}] = {{{weights}}};\n\
         \x20   double middle = 0.5 * (a + b), half = 0.5 * (b - a), sum = 0.0;\n\
         \x20   for (int k = 0; k < {POINTS}; k++)\n\
         \x20       sum += weights[k] * exponential_rate(middle + half * nodes[k], sigma, lambda);\n\
         \x20   return half * sum;\n\
         }}\n\
         static inline double exponential_partial(double x, double sigma, double lambda) {{\n\
         \x20   double width = x / {PANELS}.0, sum = 0.0, upper = width;\n\
         \x20   for (int panel = 1; panel < {PANELS}; panel++) {{\n\
         \x20       double lower = panel * width;\n\
         \x20       sum += exponential_panel(lower, lower + width, sigma, lambda);\n\
         \x20   }}\n\
         \x20   for (int k = 0; k < {GRADED} && exponential_rate(upper, sigma, lambda) != 0.0; k++) {{\n\
         \x20       sum += exponential_panel(0.5 * upper, upper, sigma, lambda);\n\
         \x20       upper *= 0.5;\n\
         \x20   }}\n\
         \x20   return sum;\n\
         }}\n\
         static inline double exponential_profile(double tau, double sigma, double lambda) {{\n\
         \x20   double total = 2.0 * exponential_partial(0.5, sigma, lambda);\n\
         \x20   if (isnan(tau)) return tau;\n\
         \x20   if (tau <= 0.0) return 0.0;\n\
         \x20   if (tau >= 1.0) return 1.0;\n\
         \x20   return tau <= 0.5 ? exponential_partial(tau, sigma, lambda) / total\n\
         \x20                     : 1.0 - exponential_partial(1.0 - tau, sigma, lambda) / total;\n\
         }}\n"
    )
}

/// The Rust definition of `exponential_profile(tau, sigma, lambda)` for generated code, as
/// [`c_definition`].
pub(crate) fn rust_definition() -> String {
    let (nodes, weights) = rule_literals();
    format!(
        "\n/// The exponential law's normalised profile (lsdc's `exponential`): the rate\n\
         /// exp(-sigma (1 - g) / g^lambda), g = 4 tau (1 - tau), integrated on [0, x], x <= 1/2, by\n\
         /// the Gauss-Legendre rule of {POINTS} points on {PANELS} equal panels, the first halved towards\n\
         /// 0 ({GRADED} times at most), over its integral on [0, 1].\n\
         #[allow(dead_code)]\n\
         fn exponential_profile(tau: f64, sigma: f64, lambda: f64) -> f64 {{\n\
         \x20   const NODES: [f64; {POINTS}] = [{nodes}];\n\
         \x20   const WEIGHTS: [f64; {POINTS}] = [{weights}];\n\
         \x20   let rate = |tau: f64| {{\n\
         \x20       let g = 4.0 * tau * (1.0 - tau);\n\
         \x20       if g <= 0.0 {{ 0.0 }} else {{ (-sigma * (1.0 - g) / g.powf(lambda)).exp() }}\n\
         \x20   }};\n\
         \x20   let panel = |a: f64, b: f64| {{\n\
         \x20       let (middle, half) = (0.5 * (a + b), 0.5 * (b - a));\n\
         \x20       let mut sum = 0.0;\n\
         \x20       for k in 0..{POINTS} {{\n\
         \x20           sum += WEIGHTS[k] * rate(middle + half * NODES[k]);\n\
         \x20       }}\n\
         \x20       half * sum\n\
         \x20   }};\n\
         \x20   let partial = |x: f64| {{\n\
         \x20       let width = x / {PANELS}.0;\n\
         \x20       let mut sum = 0.0;\n\
         \x20       for k in 1..{PANELS} {{\n\
         \x20           let lower = k as f64 * width;\n\
         \x20           sum += panel(lower, lower + width);\n\
         \x20       }}\n\
         \x20       let mut upper = width;\n\
         \x20       for _ in 0..{GRADED} {{\n\
         \x20           if rate(upper) == 0.0 {{ break; }}\n\
         \x20           sum += panel(0.5 * upper, upper);\n\
         \x20           upper *= 0.5;\n\
         \x20       }}\n\
         \x20       sum\n\
         \x20   }};\n\
         \x20   let total = 2.0 * partial(0.5);\n\
         \x20   if tau.is_nan() {{ tau }} else if tau <= 0.0 {{ 0.0 }} else if tau >= 1.0 {{ 1.0 }}\n\
         \x20   else if tau <= 0.5 {{ partial(tau) / total }} else {{ 1.0 - partial(1.0 - tau) / total }}\n\
         }}\n"
    )
}

/// The rule's points and weights as literals that read back to the same doubles.
fn rule_literals() -> (String, String) {
    let rule = gauss_legendre();
    let list = |pick: fn(&(f64, f64)) -> f64| {
        (rule.iter().map(|p| format!("{:?}", pick(p))))
            .collect::<Vec<_>>()
            .join(", ")
    };
    (list(|p| p.0), list(|p| p.1))
}
