//! The distributions a sweep samples its values from, each given by its quantile function
//! (inverse transform sampling): every design draws points of the unit cube, and a point's
//! coordinate u in (0, 1) becomes the value `quantile(u)`. A Latin hypercube or a Sobol design
//! thereby keeps its stratification through any of the distributions.

use std::fmt;

/// A distribution of one value: `uniform(a, b)`, `normal(mean, sd)` or
/// `truncnormal(mean, sd, low, high)` (the normal conditioned on [low, high]).
#[derive(Clone, Debug, PartialEq)]
pub enum Distribution {
    Uniform {
        low: f64,
        high: f64,
    },
    Normal {
        mean: f64,
        sd: f64,
    },
    TruncatedNormal {
        mean: f64,
        sd: f64,
        low: f64,
        high: f64,
    },
}

impl Distribution {
    /// The value below which a fraction `u` (in (0, 1)) of the distribution lies.
    pub fn quantile(&self, u: f64) -> f64 {
        match *self {
            Distribution::Uniform { low, high } => low + (high - low) * u,
            Distribution::Normal { mean, sd } => mean + sd * standard_normal_quantile(u),
            Distribution::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => {
                let below = standard_normal_cdf((low - mean) / sd);
                let above = standard_normal_cdf((high - mean) / sd);
                let z = standard_normal_quantile(below + u * (above - below));
                // Far in a tail the CDF's round-off may step just outside the bounds.
                (mean + sd * z).clamp(low, high)
            }
        }
    }

    /// Reads `uniform(a, b)`, `normal(mean, sd)` or `truncnormal(mean, sd, low, high)`.
    pub fn parse(text: &str) -> Result<Distribution, String> {
        let text = text.trim();
        let (kind, rest) = text
            .split_once('(')
            .ok_or_else(|| format!("`{text}`: write uniform(a, b), normal(mean, sd) or truncnormal(mean, sd, low, high)"))?;
        let arguments = rest
            .strip_suffix(')')
            .ok_or_else(|| format!("`{text}`: no closing parenthesis"))?;
        let numbers = (arguments.split(','))
            .map(|a| {
                let a = a.trim();
                a.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| format!("`{text}`: `{a}` is not a finite number"))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        let count = |n: usize, form: &str| match numbers.len() == n {
            true => Ok(()),
            false => Err(format!("`{text}`: write {form}")),
        };
        let distribution = match kind.trim() {
            "uniform" => {
                count(2, "uniform(low, high)")?;
                Distribution::Uniform {
                    low: numbers[0],
                    high: numbers[1],
                }
            }
            "normal" => {
                count(2, "normal(mean, sd)")?;
                Distribution::Normal {
                    mean: numbers[0],
                    sd: numbers[1],
                }
            }
            "truncnormal" => {
                count(4, "truncnormal(mean, sd, low, high)")?;
                Distribution::TruncatedNormal {
                    mean: numbers[0],
                    sd: numbers[1],
                    low: numbers[2],
                    high: numbers[3],
                }
            }
            other => {
                return Err(format!(
                "`{text}`: no distribution `{other}`; write uniform(a, b), normal(mean, sd) or truncnormal(mean, sd, low, high)"
            ))
            }
        };
        distribution
            .check()
            .map(|()| distribution)
            .map_err(|why| format!("`{text}`: {why}"))
    }

    fn check(&self) -> Result<(), String> {
        match *self {
            Distribution::Uniform { low, high } if low > high => {
                Err("the lower bound is above the upper one".to_string())
            }
            Distribution::Normal { sd, .. } if sd <= 0.0 => {
                Err("the standard deviation must be positive".to_string())
            }
            Distribution::TruncatedNormal { sd, .. } if sd <= 0.0 => {
                Err("the standard deviation must be positive".to_string())
            }
            Distribution::TruncatedNormal { low, high, .. } if low >= high => {
                Err("the lower bound must be below the upper one".to_string())
            }
            _ => Ok(()),
        }
    }
}

impl fmt::Display for Distribution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Distribution::Uniform { low, high } => write!(f, "uniform({low}, {high})"),
            Distribution::Normal { mean, sd } => write!(f, "normal({mean}, {sd})"),
            Distribution::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => write!(f, "truncnormal({mean}, {sd}, {low}, {high})"),
        }
    }
}

/// Φ(z), the standard normal distribution function, through the complementary error function
/// (which keeps its relative accuracy in the lower tail).
pub fn standard_normal_cdf(z: f64) -> f64 {
    0.5 * libm::erfc(-z / std::f64::consts::SQRT_2)
}

/// Φ⁻¹(p) for p in (0, 1): Wichura's algorithm AS 241 (PPND16), "The percentage points of the
/// normal distribution", Applied Statistics 37 (1988) 477–484, accurate to about 1e-16
/// relative. Rational approximations on three ranges of p.
pub fn standard_normal_quantile(p: f64) -> f64 {
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        let r = 0.180625 - q * q;
        return q * rational(r, &CENTRAL_NUMERATOR, &CENTRAL_DENOMINATOR);
    }
    let r = (-(p.min(1.0 - p)).ln()).sqrt();
    let magnitude = if r <= 5.0 {
        rational(r - 1.6, &INTERMEDIATE_NUMERATOR, &INTERMEDIATE_DENOMINATOR)
    } else {
        rational(r - 5.0, &TAIL_NUMERATOR, &TAIL_DENOMINATOR)
    };
    if q < 0.0 {
        -magnitude
    } else {
        magnitude
    }
}

/// The ratio of two polynomials of degree 7 in `x`, coefficients from the constant term up
/// (the denominators' constant term is 1).
fn rational(x: f64, numerator: &[f64; 8], denominator: &[f64; 8]) -> f64 {
    let horner = |c: &[f64; 8]| c.iter().rev().fold(0.0, |acc, &k| acc * x + k);
    horner(numerator) / horner(denominator)
}

// AS 241's coefficients, as published.
const CENTRAL_NUMERATOR: [f64; 8] = [
    3.387_132_872_796_366_5,
    1.331_416_678_917_843_8e2,
    1.971_590_950_306_551_3e3,
    1.373_169_376_550_946e4,
    4.592_195_393_154_987e4,
    6.726_577_092_700_87e4,
    3.343_057_558_358_813e4,
    2.509_080_928_730_122_7e3,
];
const CENTRAL_DENOMINATOR: [f64; 8] = [
    1.0,
    4.231_333_070_160_091e1,
    6.871_870_074_920_579e2,
    5.394_196_021_424_751e3,
    2.121_379_430_158_659_7e4,
    3.930_789_580_009_271e4,
    2.872_908_573_572_194_3e4,
    5.226_495_278_852_545e3,
];
const INTERMEDIATE_NUMERATOR: [f64; 8] = [
    1.423_437_110_749_683_5,
    4.630_337_846_156_546,
    5.769_497_221_460_691,
    3.647_848_324_763_204_5,
    1.270_458_252_452_368_4,
    2.417_807_251_774_506e-1,
    2.272_384_498_926_918_4e-2,
    7.745_450_142_783_414e-4,
];
const INTERMEDIATE_DENOMINATOR: [f64; 8] = [
    1.0,
    2.053_191_626_637_759,
    1.676_384_830_183_803_8,
    6.897_673_349_851e-1,
    1.481_039_764_274_800_8e-1,
    1.519_866_656_361_645_7e-2,
    5.475_938_084_995_345e-4,
    1.050_750_071_644_416_9e-9,
];
const TAIL_NUMERATOR: [f64; 8] = [
    6.657_904_643_501_103,
    5.463_784_911_164_114,
    1.784_826_539_917_291_3,
    2.965_605_718_285_048_7e-1,
    2.653_218_952_657_612_4e-2,
    1.242_660_947_388_078_4e-3,
    2.711_555_568_743_487_6e-5,
    2.010_334_399_292_288_1e-7,
];
const TAIL_DENOMINATOR: [f64; 8] = [
    1.0,
    5.998_322_065_558_88e-1,
    1.369_298_809_227_358e-1,
    1.487_536_129_085_061_5e-2,
    7.868_691_311_456_133e-4,
    1.846_318_317_510_054_8e-5,
    1.421_511_758_316_446e-7,
    2.044_263_103_389_939_8e-15,
];
