//! The explicit Runge–Kutta pair DOP853 of Dormand and Prince as given by Hairer: an 8th-order
//! solution from 12 stages, an error estimate that blends embedded 5th- and 3rd-order solutions
//! (the "8(5,3)" pair), and a continuous extension of order 7 that costs three more stages, taken
//! only on the steps that have outputs inside them.
//!
//! Coefficients from Hairer, Nørsett and Wanner, Solving ODEs I (2nd ed.), II.10 ("Dense output
//! ... DOP853", Tables 10.2–10.3 and the code DOP853 printed with the book); the digits are those
//! of the published code, kept as printed (more than an f64 holds) so that they can be checked
//! against it.
#![allow(clippy::excessive_precision)]

use super::control::{Gains, StepController};
use super::driver::AdaptiveStepper;
use super::evaluator::{Evaluator, Halt};
use super::hermite::hermite_part_into;
use super::settings::Settings;

/// Stages of one step.
const STAGES: usize = 12;

/// |h λ| at the boundary of the method's stability region on the negative real axis (Hairer's
/// DOP853 takes 6.1 in its stiffness test).
pub const STABILITY_LIMIT: f64 = 6.0;
/// The step's stages, dy/dt at its end, and the three stages of the continuous extension.
const ALL_STAGES: usize = 16;
/// Index of dy/dt at the step's end among the stages.
const END: usize = 12;

/// Fractions of the step at which the stages are evaluated (the step's 12, its end, the three of
/// the continuous extension).
const C: [f64; ALL_STAGES] = [
    0.0,
    0.526001519587677318785587544488e-1,
    0.789002279381515978178381316732e-1,
    0.118350341907227396726757197510,
    0.281649658092772603273242802490,
    0.333333333333333333333333333333,
    0.25,
    0.307692307692307692307692307692,
    0.651282051282051282051282051282,
    0.6,
    0.857142857142857142857142857142,
    1.0,
    1.0,
    0.1,
    0.2,
    0.777777777777777777777777777778,
];

/// Weights of earlier stages in each stage's state, as (stage, weight) pairs: most are zero.
/// Row 12 is the 8th-order solution (its weights `b`); rows 13 to 15 the continuous extension's
/// stages, which also weigh dy/dt at the step's end (stage 12).
const A: [&[(usize, f64)]; ALL_STAGES] = [
    &[],
    &[(0, 5.26001519587677318785587544488e-2)],
    &[
        (0, 1.97250569845378994544595329183e-2),
        (1, 5.91751709536136983633785987549e-2),
    ],
    &[
        (0, 2.95875854768068491816892993775e-2),
        (2, 8.87627564304205475450678981324e-2),
    ],
    &[
        (0, 2.41365134159266685502369798665e-1),
        (2, -8.84549479328286085344864962717e-1),
        (3, 9.24834003261792003115737966543e-1),
    ],
    &[
        (0, 3.7037037037037037037037037037e-2),
        (3, 1.70828608729473871279604482173e-1),
        (4, 1.25467687566822425016691814123e-1),
    ],
    &[
        (0, 3.7109375e-2),
        (3, 1.70252211019544039314978060272e-1),
        (4, 6.02165389804559606850219397283e-2),
        (5, -1.7578125e-2),
    ],
    &[
        (0, 3.70920001185047927108779319836e-2),
        (3, 1.70383925712239993810214054705e-1),
        (4, 1.07262030446373284651809199168e-1),
        (5, -1.53194377486244017527936158236e-2),
        (6, 8.27378916381402288758473766002e-3),
    ],
    &[
        (0, 6.24110958716075717114429577812e-1),
        (3, -3.36089262944694129406857109825),
        (4, -8.68219346841726006818189891453e-1),
        (5, 2.75920996994467083049415600797e1),
        (6, 2.01540675504778934086186788979e1),
        (7, -4.34898841810699588477366255144e1),
    ],
    &[
        (0, 4.77662536438264365890433908527e-1),
        (3, -2.48811461997166764192642586468),
        (4, -5.90290826836842996371446475743e-1),
        (5, 2.12300514481811942347288949897e1),
        (6, 1.52792336328824235832596922938e1),
        (7, -3.32882109689848629194453265587e1),
        (8, -2.03312017085086261358222928593e-2),
    ],
    &[
        (0, -9.3714243008598732571704021658e-1),
        (3, 5.18637242884406370830023853209),
        (4, 1.09143734899672957818500254654),
        (5, -8.14978701074692612513997267357),
        (6, -1.85200656599969598641566180701e1),
        (7, 2.27394870993505042818970056734e1),
        (8, 2.49360555267965238987089396762),
        (9, -3.0467644718982195003823669022),
    ],
    &[
        (0, 2.27331014751653820792359768449),
        (3, -1.05344954667372501984066689879e1),
        (4, -2.00087205822486249909675718444),
        (5, -1.79589318631187989172765950534e1),
        (6, 2.79488845294199600508499808837e1),
        (7, -2.85899827713502369474065508674),
        (8, -8.87285693353062954433549289258),
        (9, 1.23605671757943030647266201528e1),
        (10, 6.43392746015763530355970484046e-1),
    ],
    &[
        (0, 5.42937341165687622380535766363e-2),
        (5, 4.45031289275240888144113950566),
        (6, 1.89151789931450038304281599044),
        (7, -5.8012039600105847814672114227),
        (8, 3.1116436695781989440891606237e-1),
        (9, -1.52160949662516078556178806805e-1),
        (10, 2.01365400804030348374776537501e-1),
        (11, 4.47106157277725905176885569043e-2),
    ],
    &[
        (0, 5.61675022830479523392909219681e-2),
        (6, 2.53500210216624811088794765333e-1),
        (7, -2.46239037470802489917441475441e-1),
        (8, -1.24191423263816360469010140626e-1),
        (9, 1.5329179827876569731206322685e-1),
        (10, 8.20105229563468988491666602057e-3),
        (11, 7.56789766054569976138603589584e-3),
        (12, -8.298e-3),
    ],
    &[
        (0, 3.18346481635021405060768473261e-2),
        (5, 2.83009096723667755288322961402e-2),
        (6, 5.35419883074385676223797384372e-2),
        (7, -5.49237485713909884646569340306e-2),
        (10, -1.08347328697249322858509316994e-4),
        (11, 3.82571090835658412954920192323e-4),
        (12, -3.40465008687404560802977114492e-4),
        (13, 1.41312443674632500278074618366e-1),
    ],
    &[
        (0, -4.28896301583791923408573538692e-1),
        (5, -4.69762141536116384314449447206),
        (6, 7.68342119606259904184240953878),
        (7, 4.06898981839711007970213554331),
        (8, 3.56727187455281109270669543021e-1),
        (12, -1.39902416515901462129418009734e-3),
        (13, 2.9475147891527723389556272149),
        (14, -9.15095847217987001081870187138),
    ],
];

/// The 8th-order weights minus those of the embedded 5th-order solution.
const ERROR_5: [(usize, f64); 8] = [
    (0, 0.1312004499419488073250102996e-1),
    (5, -0.1225156446376204440720569753e1),
    (6, -0.4957589496572501915214079952),
    (7, 0.1664377182454986536961530415e1),
    (8, -0.3503288487499736816886487290),
    (9, 0.3341791187130174790297318841),
    (10, 0.8192320648511571246570742613e-1),
    (11, -0.2235530786388629525884427845e-1),
];

/// The 8th-order weights minus those of the embedded 3rd-order solution, which differ from them
/// only in stages 0, 8 and 11.
const THIRD_ORDER_CHANGES: [(usize, f64); 3] = [
    (0, 0.244094488188976377952755905512),
    (8, 0.733846688281611857341361741547),
    (11, 0.220588235294117647058823529412e-1),
];

/// Weights of the stages in the four highest coefficients of the continuous extension.
const DENSE: [&[(usize, f64)]; 4] = [
    &[
        (0, -0.84289382761090128651353491142e1),
        (5, 0.56671495351937776962531783590),
        (6, -0.30689499459498916912797304727e1),
        (7, 0.23846676565120698287728149680e1),
        (8, 0.21170345824450282767155149946e1),
        (9, -0.87139158377797299206789907490),
        (10, 0.22404374302607882758541771650e1),
        (11, 0.63157877876946881815570249290),
        (12, -0.88990336451333310820698117400e-1),
        (13, 0.18148505520854727256656404962e2),
        (14, -0.91946323924783554000451984436e1),
        (15, -0.44360363875948939664310572000e1),
    ],
    &[
        (0, 0.10427508642579134603413151009e2),
        (5, 0.24228349177525818288430175319e3),
        (6, 0.16520045171727028198505394887e3),
        (7, -0.37454675472269020279518312152e3),
        (8, -0.22113666853125306036270938578e2),
        (9, 0.77334326684722638389603898808e1),
        (10, -0.30674084731089398182061213626e2),
        (11, -0.93321305264302278729567221706e1),
        (12, 0.15697238121770843886131091075e2),
        (13, -0.31139403219565177677282850411e2),
        (14, -0.93529243588444783865713862664e1),
        (15, 0.35816841486394083752465898540e2),
    ],
    &[
        (0, 0.19985053242002433820987653617e2),
        (5, -0.38703730874935176555105901742e3),
        (6, -0.18917813819516756882830838328e3),
        (7, 0.52780815920542364900561016686e3),
        (8, -0.11573902539959630126141871134e2),
        (9, 0.68812326946963000169666922661e1),
        (10, -0.10006050966910838403183860980e1),
        (11, 0.77771377980534432092869265740),
        (12, -0.27782057523535084065932004339e1),
        (13, -0.60196695231264120758267380846e2),
        (14, 0.84320405506677161018159903784e2),
        (15, 0.11992291136182789328035130030e2),
    ],
    &[
        (0, -0.25693933462703749003312586129e2),
        (5, -0.15418974869023643374053993627e3),
        (6, -0.23152937917604549567536039109e3),
        (7, 0.35763911791061412378285349910e3),
        (8, 0.93405324183624310003907691704e2),
        (9, -0.37458323136451633156875139351e2),
        (10, 0.10409964950896230045147246184e3),
        (11, 0.29840293426660503123344363579e2),
        (12, -0.43533456590011143754432175058e2),
        (13, 0.96324553959188282948394950600e2),
        (14, -0.39177261675615439165231486172e2),
        (15, -0.14972683625798562581422125276e3),
    ],
];

pub(super) struct Dop853 {
    /// The stages of the current attempt (`stages[0]` is dy/dt at the current point), dy/dt at
    /// its end once accepted (`END`), and the continuous extension's stages when taken.
    stages: [Vec<f64>; ALL_STAGES],
    stage_state: Vec<f64>,
    /// Coefficients of the interpolating polynomial over the last accepted step.
    dense: [Vec<f64>; 8],
    dense_start: f64,
    dense_step: f64,
    /// Whether the continuous extension's stages were taken for the attempt being accepted;
    /// without them the interpolant is the cubic Hermite through the step's ends.
    extension_taken: bool,
    rtol: f64,
    atol: f64,
    /// Components of the state the error control watches (the leading ones).
    controlled: usize,
}

impl Dop853 {
    pub(super) fn new(dimension: usize, settings: &Settings) -> Self {
        let zeros = vec![0.0; dimension];
        Dop853 {
            stages: std::array::from_fn(|_| zeros.clone()),
            stage_state: zeros.clone(),
            dense: std::array::from_fn(|_| zeros.clone()),
            dense_start: 0.0,
            dense_step: 0.0,
            extension_taken: false,
            rtol: settings.rtol,
            atol: settings.atol,
            controlled: settings.controlled_len(dimension),
        }
    }

    /// Hairer's error norm of the 8(5,3) pair: the 5th-order estimate err₅, damped where the
    /// 3rd-order one err₃ is larger, h ‖err₅‖² / √(‖err₅‖² + 0.01 ‖err₃‖²) in the scaled
    /// root-mean-square norm. It behaves like h⁸ for small steps (Solving ODEs I, II.10).
    fn error_norm(&self, y: &[f64], y_new: &[f64], h: f64) -> f64 {
        let (mut fifth, mut third) = (0.0, 0.0);
        for i in 0..self.controlled {
            let scale = self.atol + self.rtol * y[i].abs().max(y_new[i].abs());
            let eighth_order = weighted(A[STAGES], &self.stages, i);
            let against_third = eighth_order - weighted(&THIRD_ORDER_CHANGES, &self.stages, i);
            fifth += (weighted(&ERROR_5, &self.stages, i) / scale).powi(2);
            third += (against_third / scale).powi(2);
        }
        let denominator = fifth + 0.01 * third;
        if denominator <= 0.0 {
            return 0.0;
        }
        h.abs() * fifth / (denominator * self.controlled.max(1) as f64).sqrt()
    }
}

/// Σ w_j k_j[i] over the (stage, weight) pairs.
fn weighted(weights: &[(usize, f64)], stages: &[Vec<f64>], i: usize) -> f64 {
    weights.iter().map(|&(j, w)| w * stages[j][i]).sum()
}

/// y + h * (the stages weighted by `stage`'s row of A), into `out`.
fn stage_state_into(stages: &[Vec<f64>], stage: usize, y: &[f64], h: f64, out: &mut [f64]) {
    for (i, value) in out.iter_mut().enumerate() {
        *value = y[i] + h * weighted(A[stage], stages, i);
    }
}

impl AdaptiveStepper for Dop853 {
    fn order(&self) -> u32 {
        8
    }

    fn stability_limit(&self) -> Option<f64> {
        Some(STABILITY_LIMIT)
    }

    fn controller(&self) -> StepController {
        // The error norm behaves like h^8 (an order-7 estimate). Hairer's DOP853 defaults: an
        // elementary controller (β = 0), safety 0.9, growth at most 6; the predictive limit
        // extrapolates the rise of the error constant as Gustafsson does.
        StepController::new(7, Gains::elementary(6.0))
    }

    fn start(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        eval.rhs(t, y, &mut self.stages[0])
    }

    fn derivative(&self) -> &[f64] {
        &self.stages[0]
    }

    fn attempt(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
        y_new: &mut [f64],
    ) -> Result<f64, Halt> {
        self.extension_taken = false;
        for (stage, fraction) in C.iter().enumerate().take(STAGES).skip(1) {
            stage_state_into(&self.stages, stage, y, h, &mut self.stage_state);
            eval.rhs(t + fraction * h, &self.stage_state, &mut self.stages[stage])?;
        }
        stage_state_into(&self.stages, END, y, h, y_new);
        let error = self.error_norm(y, y_new, h);
        if error <= 1.0 {
            // dy/dt at the end: the dense output's and, first same as last, the next step's.
            eval.rhs(t + h, y_new, &mut self.stages[END])?;
        }
        Ok(error)
    }

    fn prepare_interpolation(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), Halt> {
        for (stage, fraction) in C.iter().enumerate().skip(END + 1) {
            stage_state_into(&self.stages, stage, y, h, &mut self.stage_state);
            eval.rhs(t + fraction * h, &self.stage_state, &mut self.stages[stage])?;
        }
        self.extension_taken = true;
        Ok(())
    }

    fn accept(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]) {
        let (first, end) = (&self.stages[0], &self.stages[END]);
        let [r0, r1, r2, r3, high @ ..] = &mut self.dense;
        hermite_part_into(h, (y, y_new), (first, end), [r0, r1, r2, r3]);
        for (coefficient, weights) in high.iter_mut().zip(DENSE) {
            for (i, value) in coefficient.iter_mut().enumerate() {
                *value = match self.extension_taken {
                    true => h * weighted(weights, &self.stages, i),
                    false => 0.0,
                };
            }
        }
        self.dense_start = t;
        self.dense_step = h;
        // First same as last: dy/dt at the new point starts the next step.
        self.stages.swap(0, END);
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let s = (t - self.dense_start) / self.dense_step;
        let r = 1.0 - s;
        let [r0, r1, r2, r3, r4, r5, r6, r7] = &self.dense;
        for i in 0..out.len() {
            let inner = r4[i] + s * (r5[i] + r * (r6[i] + s * r7[i]));
            out[i] = r0[i] + s * (r1[i] + r * (r2[i] + s * (r3[i] + r * inner)));
        }
    }
}
